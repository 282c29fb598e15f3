#include "beams.hpp"
#include "mesh_fixtures.hpp"
#include "near.hpp"

#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/sim/static_solver.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace coro;

namespace {
PcgSettings tight_pcg()
{
    PcgSettings settings;
    settings.max_iterations = 5000;
    settings.tolerance = 1e-10;
    return settings;
}
} // namespace

TEST(StaticSolver, PatchTestReproducesLinearFieldOnIrregularMesh)
{
    // Boundary nodes are moved by u = A X + b and held; the interior must follow exactly.
    const TetMesh mesh = test::irregular_box(4, 0.3, 21);
    BodySpec spec;
    spec.name = "patch";
    spec.material.young = 100.0;
    spec.material.poisson = 0.3;
    Body body(mesh, spec);
    Mat3 a;
    a << 0.02, 0.01, -0.005, 0.01, -0.01, 0.004, -0.005, 0.004, 0.015; // symmetric: no rotation
    const Vec3 b(0.1, -0.2, 0.3);
    const Tris faces = boundary_faces(mesh);
    for (const Index v : surface_vertices(faces)) {
        body.fix_vertex(v);
        const Vec3 p = mesh.rest_positions.row(v).transpose();
        body.positions().segment<3>(3 * v) = p + a * p + b;
    }
    PhaseTimes times;
    const StaticResult result = solve_static(body, 1.0, Vec3::Zero(), tight_pcg(), 1e-12, 20, times);
    ASSERT_TRUE(result.converged) << "residual " << result.residual;
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
        const Vec3 p = mesh.rest_positions.row(v).transpose();
        ASSERT_NEAR_REL(body.positions().segment<3>(3 * v), Vec3(p + a * p + b), 1e-10, 0.0) << "node " << v;
    }
}

TEST(StaticSolver, PatchTestWithLargeRotationStaysExact)
{
    // The same linear field followed by a 60° rigid rotation: co-rotation must be exact too.
    const TetMesh mesh = test::irregular_box(3, 0.3, 22);
    BodySpec spec;
    spec.name = "patch";
    Body body(mesh, spec);
    Mat3 a;
    a << 0.03, 0.01, 0.0, 0.01, -0.02, 0.0, 0.0, 0.0, 0.01;
    const Mat3 r = Eigen::AngleAxisd(M_PI / 3, Vec3(1, 2, 3).normalized()).toRotationMatrix();
    for (const Index v : surface_vertices(boundary_faces(mesh))) {
        body.fix_vertex(v);
        const Vec3 p = mesh.rest_positions.row(v).transpose();
        body.positions().segment<3>(3 * v) = r * (p + a * p);
    }
    PhaseTimes times;
    const StaticResult result = solve_static(body, 1.0, Vec3::Zero(), tight_pcg(), 1e-11, 50, times);
    ASSERT_TRUE(result.converged) << "residual " << result.residual;
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
        const Vec3 p = mesh.rest_positions.row(v).transpose();
        ASSERT_NEAR_REL(body.positions().segment<3>(3 * v), Vec3(r * (p + a * p)), 1e-9, 0.0) << "node " << v;
    }
}

TEST(StaticSolver, CantileverConvergesToTimoshenkoUnderRefinement)
{
    // Small tip load (linear regime). Timoshenko: δ = PL³/(3EI) + PL/(κGA), κ = 5/6.
    test::Cantilever beam;
    beam.tip_force = Vec3(0.0, -1.0, 0.0);
    const double g = beam.young / (2 * (1 + beam.poisson));
    const double p = 1.0, l = beam.length, i = test::Cantilever::second_moment();
    const double timoshenko = p * l * l * l / (3 * beam.young * i) + p * l / (5.0 / 6.0 * g * 1.0);

    std::vector<double> errors;
    for (const Index n : {1, 2, 4, 8}) {
        beam.cells_across = n;
        beam.cells_along = 5 * n;
        Body body = beam.body();
        PhaseTimes times;
        const StaticResult result = solve_static(body, 1.0, Vec3::Zero(), tight_pcg(), 1e-8, 20, times);
        ASSERT_TRUE(result.converged) << "residual " << result.residual;
        const double deflection = -test::tip_displacement(body, l).y();
        errors.push_back((timoshenko - deflection) / timoshenko);
        std::printf("cantilever %dx%dx%d cells: tip deflection %.6g, Timoshenko %.6g, error %.2f%%\n",
                    static_cast<int>(5 * n), static_cast<int>(n), static_cast<int>(n), deflection, timoshenko,
                    100 * errors.back());
        RecordProperty("error_percent_" + std::to_string(n), std::to_string(100 * errors.back()));
    }
    // Linear tets are too stiff in bending: the error is positive and falls under refinement,
    // faster and faster as the meshes reach the asymptotic second-order regime (ratio → 4).
    double previous_ratio = 1.0;
    for (std::size_t k = 0; k + 1 < errors.size(); ++k) {
        EXPECT_GT(errors[k + 1], 0.0);
        const double ratio = errors[k] / errors[k + 1];
        EXPECT_GT(ratio, previous_ratio) << "refinement " << k;
        previous_ratio = ratio;
    }
    EXPECT_LT(errors.back(), 0.10);
    // Richardson extrapolation (order 2) of the two finest meshes lands near Timoshenko.
    const double extrapolated = (4.0 * errors[3] - errors[2]) / 3.0;
    std::printf("Richardson-extrapolated error %.2f%%\n", 100 * extrapolated);
    EXPECT_LT(std::abs(extrapolated), 0.05);
}

TEST(StaticSolver, ReportsNonConvergenceAsData)
{
    test::Cantilever beam;
    beam.tip_force = Vec3(0.0, -50.0, 0.0);
    Body body = beam.body();
    PcgSettings settings;
    settings.max_iterations = 2;
    PhaseTimes times;
    const StaticResult result = solve_static(body, 1.0, Vec3::Zero(), settings, 1e-12, 1, times);
    EXPECT_FALSE(result.converged);
    EXPECT_EQ(result.iterations, 1);
    EXPECT_GT(result.residual, 1e-12);
}
