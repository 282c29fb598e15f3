// Single-precision matrix values (solver.matrix_precision = "single") in the scene PCG, against
// double values: the accuracy floor docs/solver.md documents, and bitwise determinism.
#include "mesh_fixtures.hpp"
#include "near.hpp"

#include <corocontact/fem/corotational_fem.hpp>
#include <corocontact/solver/pcg.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

using namespace coro;

namespace {

/// The unit roundoff of float (2⁻²⁴).
constexpr double FLOAT_ROUNDOFF = std::numeric_limits<float>::epsilon() / 2.0;

/// A stiff, rotated elasticity system K' + M/h², assembled once with double values and once
/// with single ones by the same element loop, and a load.
struct Pair {
    TetMesh mesh;
    CorotationalFem fem;
    BsrMatrix double_values;
    BsrMatrix single_values;
    VecX b;

    /// @param[in] cells  cells per side of the box: 3 (64 nodes) for dense checks, 12 (2197
    ///                   nodes) for several chunks in every reduction
    explicit Pair(Index cells = 3)
        : mesh(test::irregular_box(cells, 0.2, 7)), fem(mesh, material()),
          double_values(fem.make_matrix(MatrixPrecision::DOUBLE)), single_values(fem.make_matrix(MatrixPrecision::SINGLE))
    {
        VecX x(3 * mesh.num_vertices());
        std::mt19937 rng(11);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        for (Index v = 0; v < mesh.num_vertices(); ++v)
            x.segment<3>(3 * v) = 1.1 * mesh.rest_positions.row(v).transpose() + 0.05 * Vec3(u(rng), u(rng), u(rng));
        fem.update_rotations(x);
        std::vector<char> fixed(static_cast<std::size_t>(mesh.num_vertices()), 0);
        fixed[0] = 1;
        fem.assemble(1.0, 10.0, fixed, double_values);
        fem.assemble(1.0, 10.0, fixed, single_values);
        b.resize(x.size());
        for (Eigen::Index i = 0; i < b.size(); ++i)
            b[i] = fixed[static_cast<std::size_t>(i / 3)] ? 0.0 : u(rng);
    }

    static Material material()
    {
        Material m;
        m.young = 1e5;
        m.poisson = 0.45;
        m.density = 1.0;
        return m;
    }
};

PcgSettings to(double tolerance, PcgPreconditioner kind = PcgPreconditioner::JACOBI)
{
    PcgSettings settings;
    settings.max_iterations = 100000;
    settings.tolerance = tolerance;
    settings.preconditioner = kind;
    return settings;
}

/// |A| x, entry by entry absolute values.
VecX abs_product(const SparseMat& a, const VecX& x) { return a.cwiseAbs() * x.cwiseAbs(); }

} // namespace

TEST(MatrixPrecision, ASingleSolveMeetsTheDoubleSystemWithinTheDocumentedFloor)
{
    // Solved to a tolerance far below float rounding, the single-valued system's own residual
    // reaches it, but measured with the double matrix A the residual stops at the floor
    //   ‖b − A x‖/‖b‖ ≤ tolerance + ‖(A − A_single) x‖/‖b‖,
    // where the element loop rounds each stored value to float once per tet it adds, so
    // ‖(A − A_single) x‖ is a few u‖|A| |x|‖ (u = 2⁻²⁴): ~1e-7 of ‖b‖ for a well-scaled system,
    // more where A x cancels. The solution differs from the double one by at most the two
    // residuals over λ_min(A).
    const Pair pair;
    const double tolerance = 1e-12;
    PcgSolver pcg;
    VecX x_double = VecX::Zero(pair.b.size()), x_single = x_double;
    const PcgResult with_double = pcg.solve(pair.double_values, pair.b, x_double, to(tolerance));
    const PcgResult with_single = pcg.solve(pair.single_values, pair.b, x_single, to(tolerance));
    ASSERT_TRUE(with_double.converged);
    ASSERT_TRUE(with_single.converged);

    const SparseMat a = pair.double_values.to_sparse();
    const SparseMat rounding = a - pair.single_values.to_sparse();
    const double b_norm = pair.b.norm();
    const double floor = (rounding * x_single).norm() / b_norm;
    const double scale = FLOAT_ROUNDOFF * abs_product(a, x_single).norm() / b_norm;
    const double residual = (pair.b - a * x_single).norm() / b_norm;
    std::printf("single values: residual with the double matrix %.2e, floor %.2e = %.1f u‖|A||x|‖/‖b‖\n", residual,
                floor, floor / scale);
    EXPECT_LE(residual, tolerance + floor * (1.0 + 1e-6));
    EXPECT_GT(residual, 100.0 * tolerance); // the floor, not the tolerance, limits the single solve
    EXPECT_LT(floor, 8.0 * scale);          // a few roundings per value, not more

    const double lambda_min = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Eigen::MatrixXd(a)).eigenvalues().minCoeff();
    ASSERT_GT(lambda_min, 0.0);
    const double bound = (residual + with_double.residual) * b_norm / lambda_min;
    EXPECT_LE((x_single - x_double).norm(), bound);
    EXPECT_GT((x_single - x_double).norm(), 0.0);
}

TEST(MatrixPrecision, ACappedSingleSolveFollowsTheDoubleOneClosely)
{
    // Ten iterations (the speed-first setting): the float rounding moves the iterates by far less
    // than the ten iterations leave of the residual.
    const Pair pair;
    PcgSettings settings = to(0.0);
    settings.max_iterations = 10;
    PcgSolver pcg;
    VecX x_double = VecX::Zero(pair.b.size()), x_single = x_double;
    const PcgResult with_double = pcg.solve(pair.double_values, pair.b, x_double, settings);
    const PcgResult with_single = pcg.solve(pair.single_values, pair.b, x_single, settings);
    EXPECT_EQ(with_single.iterations, 10);
    EXPECT_NEAR(with_single.residual, with_double.residual, 1e-3 * with_double.residual);
    EXPECT_LT((x_single - x_double).norm(), 1e-4 * x_double.norm());
}

TEST(MatrixPrecision, SingleValuesGiveTheSameBitsForOneAndTwoThreads)
{
    const Pair pair(12);
    std::vector<PcgPreconditioner> kinds{PcgPreconditioner::JACOBI, PcgPreconditioner::BLOCK_JACOBI};
    for (const PcgPreconditioner kind : kinds) {
        std::vector<VecX> solutions;
        for (const int threads : {1, 2}) {
            tbb::task_arena arena(threads);
            arena.execute([&] {
                PcgSolver pcg;
                VecX x = VecX::Zero(pair.b.size());
                PcgSettings settings = to(0.0, kind);
                settings.max_iterations = 10;
                pcg.solve(pair.single_values, pair.b, x, settings);
                solutions.push_back(x);
            });
        }
        EXPECT_TRUE(solutions[0] == solutions[1]) << preconditioner_name(kind);
    }
}
