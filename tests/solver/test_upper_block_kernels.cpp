// The upper-storage product's inner loops (src/solver/detail/upper_block_kernels.hpp): the
// scalar form every build has, and the AVX2 form where it is built, against a brute-force
// product, for double and float values.
#include "near.hpp"

#include "detail/upper_block_kernels.hpp"

#include <gtest/gtest.h>

#include <array>
#include <random>
#include <vector>

using namespace coro;

namespace {

// An upper-stored pattern over n block rows (the diagonal first in every row) with random
// values, rows [0, split) as the chunk whose product is taken, and the blocks of earlier rows
// reaching into rows ≥ split listed per row for the gather.
struct UpperCase {
    Index n = 0, split = 0;
    std::vector<Index> offsets{0}, columns;
    std::vector<double> values;
    std::vector<Index> gather_offsets;
    std::vector<std::array<Index, 2>> gather_blocks; // (block, source row)

    UpperCase(Index rows, Index chunk_end, unsigned seed) : n(rows), split(chunk_end)
    {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        for (Index r = 0; r < n; ++r) {
            for (Index c = r; c < n; ++c)
                if (c == r || rng() % 4 == 0)
                    columns.push_back(c);
            offsets.push_back(static_cast<Index>(columns.size()));
        }
        for (std::size_t i = 0; i < 9 * columns.size(); ++i)
            values.push_back(u(rng));
        gather_offsets.assign(static_cast<std::size_t>(n) + 1, 0);
        for (Index c = split; c < n; ++c) {
            for (Index r = 0; r < split; ++r)
                for (Index k = offsets[static_cast<std::size_t>(r)]; k < offsets[static_cast<std::size_t>(r) + 1]; ++k)
                    if (columns[static_cast<std::size_t>(k)] == c)
                        gather_blocks.push_back({k, r});
            gather_offsets[static_cast<std::size_t>(c) + 1] = static_cast<Index>(gather_blocks.size());
        }
        for (Index c = 0; c < split; ++c)
            gather_offsets[static_cast<std::size_t>(c) + 1] = gather_offsets[static_cast<std::size_t>(c)];
    }

    // y = A x over all rows, every block and its mirror, in long double from the given values.
    template <class Value> VecX reference(const std::vector<Value>& v, const VecX& x) const
    {
        std::vector<long double> y(static_cast<std::size_t>(3 * n), 0.0L);
        for (Index r = 0; r < n; ++r)
            for (Index k = offsets[static_cast<std::size_t>(r)]; k < offsets[static_cast<std::size_t>(r) + 1]; ++k) {
                const Index c = columns[static_cast<std::size_t>(k)];
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j) {
                        const long double a = v[static_cast<std::size_t>(9 * k + 3 * i + j)];
                        y[static_cast<std::size_t>(3 * r + i)] += a * x[3 * c + j];
                        if (c != r)
                            y[static_cast<std::size_t>(3 * c + j)] += a * x[3 * r + i];
                    }
            }
        VecX out(3 * n);
        for (Index i = 0; i < 3 * n; ++i)
            out[i] = static_cast<double>(y[static_cast<std::size_t>(i)]);
        return out;
    }
};

// The product as BsrMatrix runs it: the chunk [0, split), the chunk [split, n), then the
// gathers into the second chunk's rows.
template <class Value, class Rows, class Gather>
VecX product(const UpperCase& m, const std::vector<Value>& v, const VecX& x, Rows rows, Gather gather)
{
    VecX y = VecX::Zero(3 * m.n);
    rows(v.data(), m.columns.data(), m.offsets.data(), x.data(), y.data(), 0, m.split);
    rows(v.data(), m.columns.data(), m.offsets.data(), x.data(), y.data(), m.split, m.n);
    for (Index r = m.split; r < m.n; ++r)
        gather(v.data(), m.gather_blocks.data(), m.gather_offsets[static_cast<std::size_t>(r)],
               m.gather_offsets[static_cast<std::size_t>(r) + 1], x.data(), y.data() + 3 * r);
    return y;
}

} // namespace

TEST(UpperBlockKernels, EveryFormMatchesTheBruteForceProductForDoubleAndFloatValues)
{
    const UpperCase m(50, 20, 11);
    ASSERT_FALSE(m.gather_blocks.empty());
    const std::vector<float> single(m.values.begin(), m.values.end());
    const VecX x = VecX::LinSpaced(3 * m.n, -1.0, 2.0);
    const VecX expected_double = m.reference(m.values, x), expected_single = m.reference(single, x);
    EXPECT_NEAR_REL(product(m, m.values, x, detail::scalar::upper_chunk_rows<double>, detail::scalar::gather_row<double>),
                    expected_double, 1e-13, 1e-13);
    EXPECT_NEAR_REL(product(m, single, x, detail::scalar::upper_chunk_rows<float>, detail::scalar::gather_row<float>),
                    expected_single, 1e-13, 1e-13);
#if defined(CORO_UPPER_BLOCK_AVX2)
    EXPECT_NEAR_REL(product(m, m.values, x, detail::avx2::upper_chunk_rows<double>, detail::avx2::gather_row<double>),
                    expected_double, 1e-13, 1e-13);
    EXPECT_NEAR_REL(product(m, single, x, detail::avx2::upper_chunk_rows<float>, detail::avx2::gather_row<float>),
                    expected_single, 1e-13, 1e-13);
#endif
}
