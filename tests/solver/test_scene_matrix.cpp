#include "near.hpp"

#include <corocontact/solver/pcg.hpp>
#include <corocontact/solver/scene_matrix.hpp>

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <random>
#include <stdexcept>

using namespace coro;

namespace {
// A random symmetric positive definite matrix in upper storage (diagonally dominant).
BsrMatrix random_spd_upper(Index n, unsigned seed, std::vector<Index> chunks)
{
    std::mt19937 rng(seed);
    std::vector<Index> offsets{0}, columns;
    for (Index r = 0; r < n; ++r) {
        for (Index c = r; c < n; ++c)
            if (c == r || rng() % 5 == 0)
                columns.push_back(c);
        offsets.push_back(static_cast<Index>(columns.size()));
    }
    BsrMatrix a = BsrMatrix::symmetric_upper(offsets, columns, std::move(chunks));
    std::uniform_real_distribution<double> u(-1, 1);
    for (double& v : a.values())
        v = u(rng);
    for (Index r = 0; r < n; ++r)
        a.set_block(a.diagonal(r), Block3(0.5 * (a.block(a.diagonal(r)) + a.block(a.diagonal(r)).transpose()) +
                                          Block3::Identity() * 4.0 * n));
    return a;
}

// Three bodies: one chunk, several chunks with blocks across them, and a tiny one.
struct Bodies {
    BsrMatrix a = random_spd_upper(30, 1, {});
    BsrMatrix b = random_spd_upper(50, 2, {0, 10, 11, 35, 50});
    BsrMatrix c = random_spd_upper(3, 3, {});
};

// A coupling term as the test wrote it: K and its shares (row, coefficient).
struct Term {
    Mat3 k;
    std::vector<std::pair<Index, double>> shares;
};

// Random contact-like terms between random rows (1 to 4 shares, some twice the same node, some
// with a fixed node), K symmetric positive semi-definite; all bodies in one component.
std::vector<Term> random_coupling(SceneMatrix& scene, unsigned seed, Index count)
{
    scene.set_components(std::vector<Index>(static_cast<std::size_t>(scene.num_bodies()), 0));
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const auto row = [&] { return static_cast<Index>(rng() % static_cast<unsigned>(scene.num_block_rows())); };
    std::vector<Term> terms(static_cast<std::size_t>(count));
    std::vector<Index> offsets{0};
    for (Index t = 0; t < count; ++t) {
        Term& term = terms[static_cast<std::size_t>(t)];
        Mat3 a;
        for (int i = 0; i < 9; ++i)
            a.data()[i] = u(rng);
        term.k = a * a.transpose();
        const auto shares = static_cast<int>(1 + rng() % 4);
        for (int s = 0; s < shares; ++s)
            term.shares.emplace_back(s == 1 && t % 5 == 0 ? term.shares[0].first : row(), u(rng));
        offsets.push_back(offsets.back() + shares + (t % 6 == 0 ? 1 : 0));
    }
    ContactCoupling& coupling = scene.coupling();
    coupling.reset(offsets);
    for (Index t = 0; t < count; ++t) {
        const Term& term = terms[static_cast<std::size_t>(t)];
        coupling.stiffness(t) = term.k;
        Index k = 0;
        for (const auto& [r, c] : term.shares)
            coupling.share(t, k++) = {r, r, c};
        if (t % 6 == 0)
            coupling.share(t, k) = {-1, row(), 0.0}; // a fixed node: no part in the matrix
    }
    coupling.finish();
    return terms;
}

// The whole scene matrix, every block, as an Eigen matrix: the bodies' blocks and c_r c_s K of
// every pair of shares of every term.
SparseMat assembled(const SceneMatrix& scene, const std::vector<Term>& terms)
{
    std::vector<Eigen::Triplet<double, Index>> triplets;
    for (Index b = 0; b < scene.num_bodies(); ++b) {
        const SparseMat body = scene.body_matrix(b).to_sparse();
        for (Index k = 0; k < body.outerSize(); ++k)
            for (SparseMat::InnerIterator it(body, k); it; ++it)
                triplets.emplace_back(3 * scene.offset(b) + it.row(), 3 * scene.offset(b) + it.col(), it.value());
    }
    for (const Term& term : terms)
        for (const auto& [r, cr] : term.shares)
            for (const auto& [s, cs] : term.shares)
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        triplets.emplace_back(3 * r + i, 3 * s + j, cr * cs * term.k(i, j));
    SparseMat whole(scene.num_dofs(), scene.num_dofs());
    whole.setFromTriplets(triplets.begin(), triplets.end());
    return whole;
}
} // namespace

TEST(SceneMatrix, RowsAndChunksFollowTheBodies)
{
    Bodies bodies;
    const SceneMatrix scene({&bodies.a, &bodies.b, &bodies.c});
    EXPECT_EQ(scene.num_block_rows(), 83);
    EXPECT_EQ(scene.offset(1), 30);
    EXPECT_EQ(scene.offset(2), 80);
    // a: one chunk; b: its four; c: one.
    EXPECT_EQ(scene.chunks().offsets, (std::vector<Index>{0, 30, 40, 41, 65, 80, 83}));
    EXPECT_EQ(scene.chunk_body(0), 0);
    EXPECT_EQ(scene.chunk_body(4), 1);
    EXPECT_EQ(scene.chunk_body(5), 2);
    BsrMatrix general({0, 1}, {0});
    EXPECT_THROW(SceneMatrix({&general}), std::invalid_argument);
}

TEST(SceneMatrix, MultiplyMatchesTheAssembledMatrixWithCoupling)
{
    Bodies bodies;
    SceneMatrix scene({&bodies.a, &bodies.b, &bodies.c});
    const SparseMat whole = assembled(scene, random_coupling(scene, 5, 40));
    EXPECT_NEAR(SparseMat(whole - SparseMat(whole.transpose())).norm(), 0.0, 1e-14);
    const VecX x = VecX::LinSpaced(scene.num_dofs(), -1.0, 1.5);
    VecX y(scene.num_dofs());
    std::vector<double> dots(static_cast<std::size_t>(scene.chunks().num_chunks()));
    scene.multiply(x.data(), y.data(), dots.data());
    const VecX expected = whole * x;
    EXPECT_NEAR_REL(y, expected, 1e-12, 1e-12);
    for (Index c = 0; c < scene.chunks().num_chunks(); ++c) {
        const Index begin = scene.chunks().offsets[static_cast<std::size_t>(c)];
        const Index end = scene.chunks().offsets[static_cast<std::size_t>(c) + 1];
        EXPECT_NEAR(dots[static_cast<std::size_t>(c)],
                    x.segment(3 * begin, 3 * (end - begin)).dot(expected.segment(3 * begin, 3 * (end - begin))),
                    1e-10);
    }
}

TEST(SceneMatrix, DiagonalBlocksIncludeTheCoupling)
{
    Bodies bodies;
    SceneMatrix scene({&bodies.a, &bodies.b, &bodies.c});
    const Eigen::MatrixXd whole = Eigen::MatrixXd(assembled(scene, random_coupling(scene, 6, 60)));
    for (Index c = 0; c < scene.chunks().num_chunks(); ++c) {
        const Index begin = scene.chunks().offsets[static_cast<std::size_t>(c)];
        const Index end = scene.chunks().offsets[static_cast<std::size_t>(c) + 1];
        std::vector<Block3> blocks(static_cast<std::size_t>(end - begin));
        scene.diagonal_blocks(c, blocks.data());
        for (Index r = begin; r < end; ++r)
            EXPECT_TRUE(test::is_near(blocks[static_cast<std::size_t>(r - begin)], whole.block<3, 3>(3 * r, 3 * r),
                                      1e-14, 1e-15))
                << "row " << r;
    }
}

TEST(CouplingBlocks, SortsByRowAndColumnAndSumsRepeatsInContributionOrder)
{
    CouplingBlocks coupling;
    coupling.reset(5);
    const Block3 one = Block3::Constant(1.0), tiny = Block3::Constant(1e-17);
    coupling.entry(0) = {45, 2, one};
    coupling.entry(1) = {3, 3, one};
    coupling.entry(2) = {45, 2, tiny};
    coupling.entry(3) = {45, 1, one};
    coupling.entry(4) = {45, 2, -one};
    coupling.finish(83);
    ASSERT_EQ(coupling.size(), 3);
    EXPECT_EQ(coupling.block(0).row, 3);
    EXPECT_EQ(coupling.block(1).column, 1);
    EXPECT_EQ(coupling.block(2).column, 2);
    // (1 + 1e-17) − 1 in this order is 0; any other order would leave 1e-17.
    EXPECT_EQ(coupling.block(2).value, Block3(Block3::Zero()));
}

TEST(ContactCoupling, ItsBlocksAreItsTermsWrittenOut)
{
    Bodies bodies;
    SceneMatrix scene({&bodies.a, &bodies.b, &bodies.c});
    const std::vector<Term> terms = random_coupling(scene, 9, 40);
    CouplingBlocks blocks;
    scene.coupling().blocks(scene.num_block_rows(), blocks);
    std::vector<Eigen::Triplet<double, Index>> triplets;
    for (Index k = 0; k < blocks.size(); ++k) {
        const CouplingBlocks::Entry& e = blocks.block(k);
        if (k > 0) {
            const CouplingBlocks::Entry& before = blocks.block(k - 1);
            EXPECT_LT(std::make_pair(before.row, before.column), std::make_pair(e.row, e.column));
        }
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                triplets.emplace_back(3 * e.row + i, 3 * e.column + j, e.value(i, j));
    }
    SparseMat written(scene.num_dofs(), scene.num_dofs());
    written.setFromTriplets(triplets.begin(), triplets.end());
    SparseMat bodies_only = assembled(scene, {});
    const SparseMat expected = assembled(scene, terms) - bodies_only;
    EXPECT_LT(SparseMat(written - expected).norm(), 1e-13 * expected.norm());
}

TEST(SceneMatrix, PcgOverTheSceneSolvesTheCoupledSystem)
{
    Bodies bodies;
    SceneMatrix scene({&bodies.a, &bodies.b, &bodies.c});
    const SparseMat whole = assembled(scene, random_coupling(scene, 7, 30));
    const VecX rhs = VecX::LinSpaced(scene.num_dofs(), -2.0, 1.0);
    const VecX direct = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>(whole).solve(rhs);
    for (const PcgPreconditioner kind : {PcgPreconditioner::JACOBI, PcgPreconditioner::BLOCK_JACOBI}) {
        VecX x = VecX::Zero(scene.num_dofs());
        PcgSettings settings;
        settings.tolerance = 1e-12;
        settings.max_iterations = 500;
        settings.preconditioner = kind;
        const PcgResult result = PcgSolver().solve(scene, rhs, x, settings);
        EXPECT_TRUE(result.converged);
        EXPECT_NEAR_REL(x, direct, 1e-10 * direct.cwiseAbs().maxCoeff(), 0.0);
        EXPECT_NEAR((rhs - whole * x).norm() / rhs.norm(), result.residual, 1e-13);
    }
}

TEST(SceneMatrix, ProductsAndSolvesAreBitwiseTheSameForAnyThreadCount)
{
    Bodies bodies;
    SceneMatrix scene({&bodies.a, &bodies.b, &bodies.c});
    random_coupling(scene, 8, 50);
    const VecX rhs = VecX::LinSpaced(scene.num_dofs(), -1.0, 3.0);
    std::vector<double> dots_one(static_cast<std::size_t>(scene.chunks().num_chunks())), dots_two = dots_one;
    VecX y_one(scene.num_dofs()), y_two(scene.num_dofs());
    VecX x_one = VecX::Zero(scene.num_dofs()), x_two = x_one;
    PcgSettings settings;
    settings.tolerance = 1e-14;
    settings.max_iterations = 25;
    PcgResult one, two;
    tbb::task_arena(1).execute([&] {
        scene.multiply(rhs.data(), y_one.data(), dots_one.data());
        one = PcgSolver().solve(scene, rhs, x_one, settings);
    });
    tbb::task_arena(2).execute([&] {
        scene.multiply(rhs.data(), y_two.data(), dots_two.data());
        two = PcgSolver().solve(scene, rhs, x_two, settings);
    });
    EXPECT_TRUE(y_one == y_two);
    EXPECT_EQ(dots_one, dots_two);
    EXPECT_TRUE(x_one == x_two);
    EXPECT_EQ(one.residual, two.residual);
}

TEST(SceneMatrix, ComponentsAreNumberedByTheirFirstBody)
{
    Bodies bodies;
    SceneMatrix scene({&bodies.a, &bodies.b, &bodies.c});
    EXPECT_EQ(scene.num_components(), 3);
    scene.set_components({0, 1, 0});
    EXPECT_EQ(scene.num_components(), 2);
    EXPECT_EQ(scene.chunk_component(0), 0);
    EXPECT_EQ(scene.chunk_component(3), 1);
    EXPECT_EQ(scene.chunk_component(5), 0);
    EXPECT_THROW(scene.set_components({1, 0, 0}), std::invalid_argument);
    EXPECT_THROW(scene.set_components({0, 2, 1}), std::invalid_argument);
    EXPECT_THROW(scene.set_components({0, 0}), std::invalid_argument);
}

TEST(PcgSolver, EachComponentIteratesAsItsOwnSolveWould)
{
    // Body a alone, and bodies b and c coupled: the scene solve of the two components gives, bit
    // for bit, the solves of each component alone, and stops each at its own tolerance.
    Bodies bodies;
    const auto coupled = [&](SceneMatrix& scene, Index b_offset) {
        // Springs between rows 7 and 50 and rows 2 and 51 of b and c.
        ContactCoupling& coupling = scene.coupling();
        coupling.reset({0, 2, 4});
        coupling.stiffness(0) = Mat3::Constant(0.3);
        coupling.share(0, 0) = {b_offset + 7, b_offset + 7, 1.0};
        coupling.share(0, 1) = {b_offset + 50, b_offset + 50, -1.0};
        coupling.stiffness(1) = Mat3::Identity();
        coupling.share(1, 0) = {b_offset + 2, b_offset + 2, 0.5};
        coupling.share(1, 1) = {b_offset + 51, b_offset + 51, -0.5};
        coupling.finish();
    };
    SceneMatrix scene({&bodies.a, &bodies.b, &bodies.c});
    scene.set_components({0, 1, 1});
    coupled(scene, 30);
    SceneMatrix alone_a({&bodies.a});
    SceneMatrix alone_bc({&bodies.b, &bodies.c});
    alone_bc.set_components({0, 0});
    coupled(alone_bc, 0);

    // Body a starts close to its solution, so it needs fewer iterations than b and c.
    VecX rhs = VecX::LinSpaced(scene.num_dofs(), -1.0, 2.0);
    VecX x = VecX::Zero(scene.num_dofs());
    const VecX near_a = VecX::LinSpaced(90, 0.5, 1.0);
    VecX a_times(90);
    bodies.a.multiply(near_a, a_times);
    rhs.head(90) = a_times + VecX::Constant(90, 1e-7);
    x.head(90) = near_a;
    PcgSettings settings;
    settings.tolerance = 1e-9;
    settings.max_iterations = 200;
    VecX x_a = x.head(90), x_bc = VecX::Zero(scene.num_dofs() - 90);
    const PcgResult whole = PcgSolver().solve(scene, rhs, x, settings);
    const PcgResult a = PcgSolver().solve(alone_a, rhs.head(90), x_a, settings);
    const PcgResult bc = PcgSolver().solve(alone_bc, rhs.tail(scene.num_dofs() - 90), x_bc, settings);
    EXPECT_TRUE(x.head(90) == x_a);
    EXPECT_TRUE(x.tail(scene.num_dofs() - 90) == x_bc);
    EXPECT_NE(a.iterations, bc.iterations);
    EXPECT_EQ(whole.iterations, std::max(a.iterations, bc.iterations));
    EXPECT_EQ(whole.residual, std::max(a.residual, bc.residual));
    EXPECT_TRUE(whole.converged);
}

TEST(PcgSolver, AComponentWithZeroRightHandSideGetsZero)
{
    Bodies bodies;
    SceneMatrix scene({&bodies.a, &bodies.b});
    VecX rhs = VecX::Ones(scene.num_dofs());
    rhs.head(90).setZero();
    VecX x = VecX::Ones(scene.num_dofs());
    PcgSettings settings;
    settings.tolerance = 1e-10;
    settings.max_iterations = 300;
    const PcgResult result = PcgSolver().solve(scene, rhs, x, settings);
    EXPECT_TRUE(result.converged);
    EXPECT_TRUE(x.head(90).isZero(0.0));
    EXPECT_GT(x.tail(150).norm(), 0.0);
}
