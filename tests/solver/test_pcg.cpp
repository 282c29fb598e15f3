#include "mesh_fixtures.hpp"
#include "near.hpp"

#include <corocontact/fem/corotational_fem.hpp>
#include <corocontact/solver/pcg.hpp>

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <string>

using namespace coro;

namespace {
// An SPD system from a real mesh: mass + stiffness.
BsrMatrix fem_system(Index cells)
{
    const TetMesh mesh = test::irregular_box(cells, 0.2, 12);
    Material material;
    material.young = 1e4;
    CorotationalFem fem(mesh, material);
    BsrMatrix a = fem.make_matrix();
    fem.assemble(1e-3, 1.0, {}, a);
    return a;
}
} // namespace

class PcgPreconditioners : public ::testing::TestWithParam<PcgPreconditioner> {};

TEST_P(PcgPreconditioners, SolvesToToleranceAgainstDirectSolve)
{
    const BsrMatrix a = fem_system(4);
    const VecX b = VecX::LinSpaced(a.num_dofs(), -1.0, 2.0);
    VecX x = VecX::Zero(a.num_dofs());
    PcgSolver solver;
    PcgSettings settings;
    settings.tolerance = 1e-10;
    settings.max_iterations = 1000;
    settings.preconditioner = GetParam();
    const PcgResult result = solver.solve(a, b, x, settings);
    EXPECT_TRUE(result.converged);
    EXPECT_LE(result.residual, 1e-10);
    const SparseMat sparse = a.to_sparse();
    const VecX direct = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>(sparse).solve(b);
    EXPECT_NEAR_REL(x, direct, 1e-8 * direct.cwiseAbs().maxCoeff(), 0.0);
    // The reported residual is the true one.
    EXPECT_NEAR((b - sparse * x).norm() / b.norm(), result.residual, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Kinds, PcgPreconditioners,
                         ::testing::Values(PcgPreconditioner::JACOBI, PcgPreconditioner::BLOCK_JACOBI),
                         [](const ::testing::TestParamInfo<PcgPreconditioner>& param_info) {
                             return std::string(param_info.param == PcgPreconditioner::JACOBI ? "Jacobi" : "BlockJacobi");
                         });

TEST(PcgSolver, StopsAtIterationCapAndReportsIt)
{
    const BsrMatrix a = fem_system(4);
    const VecX b = VecX::Ones(a.num_dofs());
    VecX x = VecX::Zero(a.num_dofs());
    PcgSettings settings;
    settings.max_iterations = 3;
    settings.tolerance = 1e-14;
    const PcgResult result = PcgSolver().solve(a, b, x, settings);
    EXPECT_FALSE(result.converged);
    EXPECT_EQ(result.iterations, 3);
    EXPECT_GT(result.residual, 1e-14);
}

TEST(PcgSolver, ToleranceZeroIteratesToTheResidualFloorWithoutFalseBreakdown)
{
    // Run far past convergence, the residual would underflow and pᵀAp read 0.
    const BsrMatrix a = fem_system(4);
    const VecX b = VecX::LinSpaced(a.num_dofs(), -1.0, 2.0);
    VecX x = VecX::Zero(a.num_dofs());
    PcgSettings settings;
    settings.max_iterations = 5000;
    settings.tolerance = 0.0;
    const PcgResult result = PcgSolver().solve(a, b, x, settings);
    EXPECT_TRUE(result.converged);
    EXPECT_LT(result.iterations, settings.max_iterations);
    EXPECT_LE(result.residual, 1e-30);
    const SparseMat sparse = a.to_sparse();
    EXPECT_LE((b - sparse * x).norm() / b.norm(), 1e-13);
}

TEST(PcgSolver, WarmStartFromSolutionTakesNoIteration)
{
    const BsrMatrix a = fem_system(3);
    const VecX expected = VecX::LinSpaced(a.num_dofs(), 0.0, 1.0);
    VecX b(a.num_dofs());
    a.multiply(expected, b);
    VecX x = expected;
    PcgSettings settings;
    settings.tolerance = 1e-8;
    const PcgResult result = PcgSolver().solve(a, b, x, settings);
    EXPECT_TRUE(result.converged);
    EXPECT_EQ(result.iterations, 0);
}

TEST(PcgSolver, ZeroRightHandSideGivesZero)
{
    const BsrMatrix a = fem_system(2);
    VecX x = VecX::Ones(a.num_dofs());
    const PcgResult result = PcgSolver().solve(a, VecX::Zero(a.num_dofs()), x, PcgSettings{});
    EXPECT_TRUE(result.converged);
    EXPECT_EQ(x.norm(), 0.0);
}

namespace {
// Textbook PCG (Saad, Algorithm 9.1) with Eigen, serial: the reference for the fused passes.
VecX textbook_pcg(const SparseMat& a, const VecX& b, VecX x, const VecX& inverse_diagonal, Index iterations)
{
    VecX r = b - a * x;
    VecX z = inverse_diagonal.cwiseProduct(r);
    VecX p = z;
    double rz = r.dot(z);
    for (Index k = 0; k < iterations; ++k) {
        const VecX q = a * p;
        const double alpha = rz / p.dot(q);
        x += alpha * p;
        r -= alpha * q;
        z = inverse_diagonal.cwiseProduct(r);
        const double rz_next = r.dot(z);
        p = z + (rz_next / rz) * p;
        rz = rz_next;
    }
    return x;
}
} // namespace

TEST(PcgSolver, FusedIterationsMatchTextbookPcg)
{
    const BsrMatrix a = fem_system(6);
    const SparseMat sparse = a.to_sparse();
    const VecX b = VecX::LinSpaced(a.num_dofs(), -1.0, 2.0);
    const VecX x0 = VecX::Constant(a.num_dofs(), 0.1);
    PcgSettings settings;
    settings.max_iterations = 7;
    settings.tolerance = 1e-14;
    settings.preconditioner = PcgPreconditioner::JACOBI;
    VecX x = x0;
    const PcgResult result = PcgSolver().solve(a, b, x, settings);
    ASSERT_EQ(result.iterations, 7);
    const VecX expected = textbook_pcg(sparse, b, x0, sparse.diagonal().cwiseInverse(), 7);
    EXPECT_NEAR_REL(x, expected, 1e-10 * expected.cwiseAbs().maxCoeff(), 0.0);
    EXPECT_NEAR((b - sparse * x).norm() / b.norm(), result.residual, 1e-12);
}

TEST(PcgSolver, BitwiseIdenticalForOneAndTwoThreads)
{
    const BsrMatrix a = fem_system(12); // 2197 nodes: several leaves in every reduction
    const VecX b = VecX::LinSpaced(a.num_dofs(), -1.0, 2.0);
    for (const PcgPreconditioner kind : {PcgPreconditioner::JACOBI, PcgPreconditioner::BLOCK_JACOBI}) {
        PcgSettings settings;
        settings.max_iterations = 10;
        settings.tolerance = 1e-14;
        settings.preconditioner = kind;
        VecX one = VecX::Zero(a.num_dofs()), two = one;
        PcgResult r1, r2;
        tbb::task_arena(1).execute([&] { r1 = PcgSolver().solve(a, b, one, settings); });
        tbb::task_arena(2).execute([&] { r2 = PcgSolver().solve(a, b, two, settings); });
        EXPECT_TRUE(one == two);
        EXPECT_EQ(r1.residual, r2.residual);
        EXPECT_EQ(r1.iterations, r2.iterations);
    }
}
