#include "beams.hpp"
#include "mesh_fixtures.hpp"
#include "near.hpp"

#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/sim/static_solver.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

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

namespace {
// The cantilever of the CalculiX test, coarser: a tip load that rotates the tip by ~35°.
test::Cantilever bent_beam()
{
    test::Cantilever beam;
    beam.length = 10.0;
    beam.cells_along = 20;
    beam.cells_across = 2;
    beam.young = 1e7;
    beam.tip_force = Vec3(0.0, -15000.0, 0.0);
    return beam;
}
} // namespace

TEST(StaticSolver, NewtonConvergesQuadraticallyWithinALoadStep)
{
    // A quarter of the load in one step from rest (about 10° at the tip): the residual after k
    // iterations, each run from the same start, falls with order ≈ 2 once Newton is close.
    const Body start = bent_beam().body();
    std::vector<double> residuals;
    for (Index k = 1; k <= 15; ++k) {
        Body body = start;
        PhaseTimes times;
        const StaticResult result = solve_static(body, 0.25, Vec3::Zero(), tight_pcg(), 1e-14, k, times);
        residuals.push_back(result.residual);
        std::printf("%d Newton iterations: residual %.3e\n", static_cast<int>(k), result.residual);
        if (result.residual < 1e-6)
            break; // the round-off floor (~1e-11 here) is not far below
    }
    ASSERT_GE(residuals.size(), 4u);
    ASSERT_LT(residuals.back(), 1e-6);
    // The last two reductions: quadratic, not linear.
    const std::size_t n = residuals.size();
    const double order = std::log(residuals[n - 1] / residuals[n - 2]) / std::log(residuals[n - 2] / residuals[n - 3]);
    EXPECT_GT(order, 1.6) << "residuals " << residuals[n - 3] << ", " << residuals[n - 2] << ", " << residuals[n - 1];
}

TEST(StaticSolver, LargeRotationTakesAFewNewtonIterationsPerLoadStep)
{
    Body body = bent_beam().body();
    PcgSettings settings;
    settings.max_iterations = 5000;
    settings.tolerance = 1e-8;
    const Index load_steps = 10;
    Index most = 0;
    for (Index k = 1; k <= load_steps; ++k) {
        PhaseTimes times;
        const StaticResult result = solve_static(body, static_cast<double>(k) / load_steps, Vec3::Zero(), settings,
                                                 1e-8, 50, times);
        ASSERT_TRUE(result.converged) << "load step " << k << ": residual " << result.residual;
        EXPECT_EQ(result.projected_steps, 0) << "the exact tangent is positive definite on this beam";
        EXPECT_EQ(result.solves_not_converged, 0);
        most = std::max(most, result.iterations);
    }
    const Vec3 tip = test::tip_displacement(body, 10.0);
    std::printf("tip displacement (%.4f, %.4f, %.4f), at most %d Newton iterations per load step\n", tip.x(), tip.y(),
                tip.z(), static_cast<int>(most));
    EXPECT_LE(most, 8);
    EXPECT_LT(tip.x(), -0.4); // a large rotation: the tip moves back markedly
}

TEST(StaticSolver, BuckledColumnFallsBackToTheProjectedTangent)
{
    // A clamped column pressed along its axis at 1.5× its Euler load, nudged sideways: past
    // buckling the straight column is unstable and the exact tangent indefinite. Newton must
    // still find the bent equilibrium, redoing the indefinite iterations with the projected
    // tangent.
    test::Cantilever column = bent_beam();
    const double euler = M_PI * M_PI * column.young * test::Cantilever::second_moment() /
                         (4.0 * column.length * column.length);
    column.tip_force = Vec3(-4.0 * euler, -0.01 * euler, 0.0);
    Body body = column.body();
    PcgSettings settings;
    settings.max_iterations = 5000;
    settings.tolerance = 1e-10;
    Index projected = 0;
    for (Index k = 1; k <= 10; ++k) {
        PhaseTimes times;
        const StaticResult result = solve_static(body, k / 10.0, Vec3::Zero(), settings, 1e-8, 100, times);
        ASSERT_TRUE(result.converged) << "load step " << k << ": residual " << result.residual;
        projected += result.projected_steps;
        std::printf("load step %d: %d iterations, %d projected, %d cuts\n", static_cast<int>(k),
                    static_cast<int>(result.iterations), static_cast<int>(result.projected_steps),
                    static_cast<int>(result.line_search_cuts));
    }
    const Vec3 tip = test::tip_displacement(body, column.length);
    std::printf("tip displacement (%.4f, %.4f, %.4f)\n", tip.x(), tip.y(), tip.z());
    EXPECT_GT(projected, 0);
    EXPECT_LT(tip.y(), -1.0); // buckled sideways, far beyond the nudge's linear deflection
}
