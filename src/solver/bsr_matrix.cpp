#include <corocontact/solver/bsr_matrix.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <functional>
#include <stdexcept>
#include <string>

namespace coro {

namespace {
constexpr Index SPMV_GRAIN = 256; // block rows per task (and per reduction leaf of multiply_dot)

// y_r = Σ_k A_rk x_k for block rows [begin, end), each row summed in pattern order.
inline void multiply_rows(const double* values, const Index* columns, const Index* offsets, const double* xd,
                          double* yd, Index begin, Index end)
{
    for (Index r = begin; r != end; ++r) {
        double y0 = 0.0, y1 = 0.0, y2 = 0.0;
        for (Index k = offsets[r]; k < offsets[r + 1]; ++k) {
            const double* a = values + 9 * static_cast<std::ptrdiff_t>(k);
            const double* xc = xd + 3 * static_cast<std::ptrdiff_t>(columns[k]);
            y0 += a[0] * xc[0] + a[1] * xc[1] + a[2] * xc[2];
            y1 += a[3] * xc[0] + a[4] * xc[1] + a[5] * xc[2];
            y2 += a[6] * xc[0] + a[7] * xc[1] + a[8] * xc[2];
        }
        yd[3 * r] = y0;
        yd[3 * r + 1] = y1;
        yd[3 * r + 2] = y2;
    }
}
} // namespace

BsrMatrix::BsrMatrix(std::vector<Index> row_offsets, std::vector<Index> columns)
    : m_row_offsets(std::move(row_offsets)), m_columns(std::move(columns))
{
    if (m_row_offsets.empty() || m_row_offsets.front() != 0 ||
        m_row_offsets.back() != static_cast<Index>(m_columns.size()))
        throw std::invalid_argument("BsrMatrix: row offsets do not match the column count");
    const Index n = num_block_rows();
    m_diagonal.assign(static_cast<std::size_t>(n), -1);
    for (Index r = 0; r < n; ++r) {
        const auto begin = m_columns.begin() + m_row_offsets[static_cast<std::size_t>(r)];
        const auto end = m_columns.begin() + m_row_offsets[static_cast<std::size_t>(r) + 1];
        if (!std::is_sorted(begin, end) || std::adjacent_find(begin, end) != end)
            throw std::invalid_argument("BsrMatrix: columns of row " + std::to_string(r) +
                                        " are not strictly ascending");
        if (begin != end && (*begin < 0 || *(end - 1) >= n))
            throw std::invalid_argument("BsrMatrix: column out of range in row " + std::to_string(r));
        m_diagonal[static_cast<std::size_t>(r)] = find(r, r);
        if (m_diagonal[static_cast<std::size_t>(r)] < 0)
            throw std::invalid_argument("BsrMatrix: row " + std::to_string(r) + " has no diagonal block");
    }
    m_values.assign(9 * m_columns.size(), 0.0);
}

Index BsrMatrix::find(Index row, Index column) const
{
    const auto begin = m_columns.begin() + m_row_offsets[static_cast<std::size_t>(row)];
    const auto end = m_columns.begin() + m_row_offsets[static_cast<std::size_t>(row) + 1];
    const auto it = std::lower_bound(begin, end, column);
    return (it != end && *it == column) ? static_cast<Index>(it - m_columns.begin()) : -1;
}

void BsrMatrix::multiply(CRef<VecX> x, Eigen::Ref<VecX> y) const
{
    const double* values = m_values.data();
    const Index* columns = m_columns.data();
    const Index* offsets = m_row_offsets.data();
    const double* xd = x.data();
    double* yd = y.data();
    tbb::parallel_for(tbb::blocked_range<Index>(0, num_block_rows(), SPMV_GRAIN),
                      [&](const tbb::blocked_range<Index>& range) {
                          multiply_rows(values, columns, offsets, xd, yd, range.begin(), range.end());
                      });
}

double BsrMatrix::multiply_dot(CRef<VecX> x, Eigen::Ref<VecX> y) const
{
    const double* values = m_values.data();
    const Index* columns = m_columns.data();
    const Index* offsets = m_row_offsets.data();
    const double* xd = x.data();
    double* yd = y.data();
    return tbb::parallel_deterministic_reduce(
        tbb::blocked_range<Index>(0, num_block_rows(), SPMV_GRAIN), 0.0,
        [&](const tbb::blocked_range<Index>& range, double acc) {
            multiply_rows(values, columns, offsets, xd, yd, range.begin(), range.end());
            double sum = 0.0;
            for (std::ptrdiff_t i = 3 * static_cast<std::ptrdiff_t>(range.begin());
                 i < 3 * static_cast<std::ptrdiff_t>(range.end()); ++i)
                sum += xd[i] * yd[i];
            return acc + sum;
        },
        std::plus<double>());
}

SparseMat BsrMatrix::to_sparse() const
{
    std::vector<Eigen::Triplet<double, Index>> triplets;
    triplets.reserve(m_values.size());
    for (Index r = 0; r < num_block_rows(); ++r)
        for (Index k = m_row_offsets[static_cast<std::size_t>(r)];
             k < m_row_offsets[static_cast<std::size_t>(r) + 1]; ++k)
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b)
                    triplets.emplace_back(3 * r + a, 3 * m_columns[static_cast<std::size_t>(k)] + b,
                                          block(k)(a, b));
    SparseMat sparse(num_dofs(), num_dofs());
    sparse.setFromTriplets(triplets.begin(), triplets.end());
    return sparse;
}

} // namespace coro
