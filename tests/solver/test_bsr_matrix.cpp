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

namespace {
// A random symmetric matrix in upper storage: pattern c ≥ r with the diagonal, random values.
BsrMatrix random_upper(Index n, unsigned seed, std::vector<Index> chunks)
{
    std::mt19937 rng(seed);
    std::vector<Index> offsets{0}, columns;
    for (Index r = 0; r < n; ++r) {
        for (Index c = r; c < n; ++c)
            if (c == r || rng() % 6 == 0)
                columns.push_back(c);
        offsets.push_back(static_cast<Index>(columns.size()));
    }
    BsrMatrix a = BsrMatrix::symmetric_upper(offsets, columns, std::move(chunks));
    std::uniform_real_distribution<double> u(-1, 1);
    for (double& v : a.values())
        v = u(rng);
    for (Index r = 0; r < n; ++r) // diagonal blocks of a symmetric matrix are symmetric
        a.set_block(a.diagonal(r), Block3(0.5 * (a.block(a.diagonal(r)) + a.block(a.diagonal(r)).transpose())));
    return a;
}
} // namespace

TEST(BsrMatrixUpper, MultiplyMatchesTheWholeSymmetricMatrix)
{
    // Chunks: none given (default), a single one, and uneven ones with many cross-chunk blocks.
    for (const std::vector<Index>& chunks :
         {std::vector<Index>{}, std::vector<Index>{0, 60}, std::vector<Index>{0, 7, 8, 31, 59, 60}}) {
        const BsrMatrix a = random_upper(60, 3, chunks);
        const SparseMat whole = a.to_sparse();
        EXPECT_NEAR(SparseMat(whole - SparseMat(whole.transpose())).norm(), 0.0, 0.0) << "to_sparse is not symmetric";
        const VecX x = VecX::LinSpaced(a.num_dofs(), -1.0, 1.5);
        VecX y(a.num_dofs());
        a.multiply(x, y);
        EXPECT_NEAR_REL(y, VecX(whole * x), 1e-13, 1e-13);
        // The general copy holds the same matrix, every block.
        const BsrMatrix general = a.to_general();
        EXPECT_FALSE(general.is_symmetric_upper());
        EXPECT_EQ(general.num_blocks(), 2 * a.num_blocks() - a.num_block_rows());
        EXPECT_NEAR(SparseMat(general.to_sparse() - whole).norm(), 0.0, 0.0);
    }
}

TEST(BsrMatrixUpper, MultiplyIsBitwiseTheSameForAnyThreadCount)
{
    const BsrMatrix a = random_upper(900, 7, {0, 100, 350, 351, 700, 900});
    const VecX x = VecX::LinSpaced(a.num_dofs(), -2.0, 1.0);
    VecX m_one(a.num_dofs()), m_two(a.num_dofs());
    tbb::task_arena(1).execute([&] { a.multiply(x, m_one); });
    tbb::task_arena(2).execute([&] { a.multiply(x, m_two); });
    EXPECT_TRUE(m_one == m_two);
}

TEST(BsrMatrixUpper, SymmetricPartsAddOnceAndLowerBlocksAreNotStored)
{
    BsrMatrix a = BsrMatrix::symmetric_upper({0, 2, 3}, {0, 1, 1});
    EXPECT_EQ(a.find(0, 1), 1);
    EXPECT_EQ(a.find(1, 0), -1);
    EXPECT_EQ(a.diagonal(1), 2);
    Mat3 m;
    m << 1, 2, 3, 4, 5, 6, 7, 8, 9;
    a.add_symmetric_part(0, 1, m);
    a.add_symmetric_part(1, 0, m.transpose()); // the mirror: carried by (0, 1) already
    Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(6, 6);
    expected.block<3, 3>(0, 3) = m;
    expected.block<3, 3>(3, 0) = m.transpose();
    EXPECT_EQ(Eigen::MatrixXd(a.to_sparse()), expected);
    EXPECT_THROW(a.add_symmetric_part(0, 2, m), std::invalid_argument); // no row/column 2
}

TEST(BsrMatrixUpper, RejectsMalformedPatternsAndChunks)
{
    EXPECT_THROW(BsrMatrix::symmetric_upper({0, 1, 3}, {0, 0, 1}), std::invalid_argument); // below the diagonal
    EXPECT_THROW(BsrMatrix::symmetric_upper({0, 1, 2}, {1, 1}), std::invalid_argument);    // row 0 lacks its diagonal
    EXPECT_THROW(BsrMatrix::symmetric_upper({0, 1, 2}, {0, 1}, {0, 2, 2}), std::invalid_argument); // empty chunk
    EXPECT_THROW(BsrMatrix::symmetric_upper({0, 1, 2}, {0, 1}, {0, 1}), std::invalid_argument);    // short of the rows
    EXPECT_NO_THROW(BsrMatrix::symmetric_upper({0}, {}));                                          // empty matrix
}

TEST(BsrMatrixSingle, StoresValuesRoundedToFloatAndMultipliesInDouble)
{
    // The same matrix in single precision: every value is the double one rounded to float, and
    // the product is that of the rounded values with double vectors and sums (an upper-stored
    // matrix with cross-chunk blocks, and a general one).
    const BsrMatrix a = random_upper(60, 3, {0, 7, 8, 31, 59, 60});
    const BsrMatrix single = a.with_precision(MatrixPrecision::SINGLE);
    EXPECT_EQ(single.precision(), MatrixPrecision::SINGLE);
    EXPECT_TRUE(single.values().empty());
    ASSERT_EQ(single.single_values().size(), a.values().size());
    for (std::size_t i = 0; i < a.values().size(); ++i)
        ASSERT_EQ(single.single_values()[i], static_cast<float>(a.values()[i])) << "value " << i;
    const VecX x = VecX::LinSpaced(a.num_dofs(), -1.0, 1.5);
    for (const BsrMatrix& m : {single, single.to_general()}) {
        EXPECT_EQ(m.precision(), MatrixPrecision::SINGLE);
        VecX y(m.num_dofs());
        m.multiply(x, y);
        EXPECT_NEAR_REL(y, VecX(single.to_sparse() * x), 1e-13, 1e-13);
    }
    VecX y_one(a.num_dofs()), y_two(a.num_dofs());
    tbb::task_arena(1).execute([&] { single.multiply(x, y_one); });
    tbb::task_arena(2).execute([&] { single.multiply(x, y_two); });
    EXPECT_TRUE(y_one == y_two);
    // Widening back to double is exact.
    EXPECT_TRUE(single.with_precision(MatrixPrecision::DOUBLE).to_sparse().isApprox(single.to_sparse(), 0.0));
}

TEST(BsrMatrixSingle, BlockWritesRoundOnceAfterAddingInDouble)
{
    BsrMatrix a = BsrMatrix::symmetric_upper({0, 1}, {0}, {}, MatrixPrecision::SINGLE);
    const Block3 third = Block3::Constant(1.0 / 3.0);
    a.set_block(0, third);
    EXPECT_EQ(a.block(0)(1, 2), static_cast<double>(static_cast<float>(1.0 / 3.0)));
    a.add_to_block(0, Block3::Constant(1e-9)); // below half a float ulp of 1/3: rounds back
    EXPECT_EQ(a.block(0)(1, 2), static_cast<double>(static_cast<float>(1.0 / 3.0)));
    a.add_to_block(0, third);
    EXPECT_EQ(a.block(0)(0, 0),
              static_cast<double>(static_cast<float>(static_cast<double>(static_cast<float>(1.0 / 3.0)) + 1.0 / 3.0)));
}
