#include "near.hpp"

#include <corocontact/solver/bsr_matrix.hpp>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <random>
#include <stdexcept>

using namespace coro;

namespace {
BsrMatrix random_matrix(Index n, unsigned seed)
{
    std::mt19937 rng(seed);
    std::vector<Index> offsets{0}, columns;
    for (Index r = 0; r < n; ++r) {
        for (Index c = 0; c < n; ++c)
            if (c == r || rng() % 4 == 0)
                columns.push_back(c);
        offsets.push_back(static_cast<Index>(columns.size()));
    }
    BsrMatrix a(offsets, columns);
    std::uniform_real_distribution<double> u(-1, 1);
    for (double& v : a.values())
        v = u(rng);
    return a;
}
} // namespace

TEST(BsrMatrix, MultiplyMatchesEigenSparse)
{
    const BsrMatrix a = random_matrix(40, 1);
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> u(-1, 1);
    VecX x(a.num_dofs());
    for (Eigen::Index i = 0; i < x.size(); ++i)
        x[i] = u(rng);
    VecX y(a.num_dofs());
    a.multiply(x, y);
    const VecX reference = a.to_sparse() * x;
    EXPECT_NEAR_REL(y, reference, 1e-13, 1e-13);
}

TEST(BsrMatrix, FindsStoredBlocksOnly)
{
    const BsrMatrix a({0, 2, 3}, {0, 1, 1});
    EXPECT_EQ(a.find(0, 1), 1);
    EXPECT_EQ(a.find(1, 0), -1);
    EXPECT_EQ(a.diagonal(1), 2);
}

TEST(BsrMatrix, RejectsMalformedPatterns)
{
    EXPECT_THROW(BsrMatrix({0, 1, 2}, {1, 0}), std::invalid_argument);   // no diagonals
    EXPECT_THROW(BsrMatrix({0, 2, 3}, {1, 0, 1}), std::invalid_argument); // unsorted row
    EXPECT_THROW(BsrMatrix({0, 2}, {0}), std::invalid_argument);         // offsets vs columns
}

TEST(BsrMatrix, MultiplyDotEqualsMultiplyThenDotForAnyThreadCount)
{
    const BsrMatrix a = random_matrix(700, 5); // several reduction leaves
    const VecX x = VecX::LinSpaced(a.num_dofs(), -1.0, 2.0);
    VecX y_plain(a.num_dofs()), y_one(a.num_dofs()), y_two(a.num_dofs());
    a.multiply(x, y_plain);
    double one = 0.0, two = 0.0;
    tbb::task_arena(1).execute([&] { one = a.multiply_dot(x, y_one); });
    tbb::task_arena(2).execute([&] { two = a.multiply_dot(x, y_two); });
    EXPECT_TRUE(y_one == y_plain);
    EXPECT_TRUE(y_two == y_plain);
    EXPECT_EQ(one, two);
    EXPECT_NEAR(one, x.dot(y_plain), 1e-12 * x.cwiseAbs().dot(y_plain.cwiseAbs()));
}
