#include <corocontact/solver/bsr_matrix.hpp>

#include "detail/upper_block_kernels.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <functional>
#include <numeric>
#include <stdexcept>
#include <string>

namespace coro {

namespace {
constexpr Index SPMV_GRAIN = 256; // block rows per task of the general product
constexpr Index DEFAULT_CHUNK_ROWS = 1024; // upper storage without given chunks

std::size_t at(Index i) { return static_cast<std::size_t>(i); }

// y_r = Σ_k A_rk x_k for block rows [begin, end), each row summed in pattern order.
template <class Value>
void multiply_rows(const Value* values, const Index* columns, const Index* offsets, const double* xd, double* yd,
                   Index begin, Index end)
{
    for (Index r = begin; r != end; ++r) {
        double y0 = 0.0, y1 = 0.0, y2 = 0.0;
        for (Index k = offsets[r]; k < offsets[r + 1]; ++k) {
            const Value* v = values + 9 * static_cast<std::ptrdiff_t>(k);
            double a[9];
            for (int i = 0; i < 9; ++i)
                a[i] = static_cast<double>(v[i]);
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

BsrMatrix::BsrMatrix(std::vector<Index> row_offsets, std::vector<Index> columns, MatrixPrecision precision)
    : m_row_offsets(std::move(row_offsets)), m_columns(std::move(columns)), m_precision(precision)
{
    check_pattern(false);
    allocate_values();
}

void BsrMatrix::allocate_values()
{
    const std::size_t count = 9 * m_columns.size();
    m_values.assign(m_precision == MatrixPrecision::DOUBLE ? count : 0, 0.0);
    m_single_values.assign(m_precision == MatrixPrecision::SINGLE ? count : 0, 0.0f);
}

BsrMatrix BsrMatrix::symmetric_upper(std::vector<Index> row_offsets, std::vector<Index> columns,
                                     std::vector<Index> chunk_offsets, MatrixPrecision precision)
{
    BsrMatrix a;
    a.m_precision = precision;
    a.m_row_offsets = std::move(row_offsets);
    a.m_columns = std::move(columns);
    a.check_pattern(true);
    const Index n = a.num_block_rows();
    if (chunk_offsets.empty()) {
        for (Index r = 0; r < n; r += DEFAULT_CHUNK_ROWS)
            chunk_offsets.push_back(r);
        chunk_offsets.push_back(n); // {0, 0} for an empty matrix: one empty chunk
    }
    const bool rising = n == 0 || std::adjacent_find(chunk_offsets.begin(), chunk_offsets.end(),
                                                     std::greater_equal<Index>()) == chunk_offsets.end();
    if (chunk_offsets.front() != 0 || chunk_offsets.back() != n || !rising)
        throw std::invalid_argument("BsrMatrix: chunk offsets must rise strictly from 0 to the row count");
    a.m_chunk_offsets = std::move(chunk_offsets);

    // Blocks whose column lies beyond their row's chunk, listed per column (CSC order).
    std::vector<Index> chunk_end(at(n));
    for (std::size_t c = 0; c + 1 < a.m_chunk_offsets.size(); ++c)
        for (Index r = a.m_chunk_offsets[c]; r < a.m_chunk_offsets[c + 1]; ++r)
            chunk_end[at(r)] = a.m_chunk_offsets[c + 1];
    a.m_gather_offsets.assign(at(n) + 1, 0);
    for (Index r = 0; r < n; ++r)
        for (Index k = a.m_row_offsets[at(r)]; k < a.m_row_offsets[at(r) + 1]; ++k)
            if (a.m_columns[at(k)] >= chunk_end[at(r)])
                ++a.m_gather_offsets[at(a.m_columns[at(k)]) + 1];
    std::partial_sum(a.m_gather_offsets.begin(), a.m_gather_offsets.end(), a.m_gather_offsets.begin());
    a.m_gather_blocks.resize(at(a.m_gather_offsets.back()));
    std::vector<Index> fill(a.m_gather_offsets.begin(), a.m_gather_offsets.end() - 1);
    for (Index r = 0; r < n; ++r) // ascending rows: each column's list comes out sorted by source row
        for (Index k = a.m_row_offsets[at(r)]; k < a.m_row_offsets[at(r) + 1]; ++k)
            if (a.m_columns[at(k)] >= chunk_end[at(r)])
                a.m_gather_blocks[at(fill[at(a.m_columns[at(k)])]++)] = {k, r};
    a.allocate_values();
    return a;
}

void BsrMatrix::check_pattern(bool upper)
{
    if (m_row_offsets.empty() || m_row_offsets.front() != 0 ||
        m_row_offsets.back() != static_cast<Index>(m_columns.size()))
        throw std::invalid_argument("BsrMatrix: row offsets do not match the column count");
    const Index n = num_block_rows();
    m_diagonal.assign(at(n), -1);
    for (Index r = 0; r < n; ++r) {
        const auto begin = m_columns.begin() + m_row_offsets[at(r)];
        const auto end = m_columns.begin() + m_row_offsets[at(r) + 1];
        if (m_row_offsets[at(r)] > m_row_offsets[at(r) + 1] || !std::is_sorted(begin, end) ||
            std::adjacent_find(begin, end) != end)
            throw std::invalid_argument("BsrMatrix: columns of row " + std::to_string(r) +
                                        " are not strictly ascending");
        if (begin != end && (*begin < 0 || *(end - 1) >= n))
            throw std::invalid_argument("BsrMatrix: column out of range in row " + std::to_string(r));
        if (upper && (begin == end || *begin != r))
            throw std::invalid_argument("BsrMatrix: row " + std::to_string(r) +
                                        " of an upper-stored matrix must start with its diagonal block");
        m_diagonal[at(r)] = find(r, r);
        if (m_diagonal[at(r)] < 0)
            throw std::invalid_argument("BsrMatrix: row " + std::to_string(r) + " has no diagonal block");
    }
}

Index BsrMatrix::find(Index row, Index column) const
{
    const auto begin = m_columns.begin() + m_row_offsets[static_cast<std::size_t>(row)];
    const auto end = m_columns.begin() + m_row_offsets[static_cast<std::size_t>(row) + 1];
    const auto it = std::lower_bound(begin, end, column);
    return (it != end && *it == column) ? static_cast<Index>(it - m_columns.begin()) : -1;
}

void BsrMatrix::add_symmetric_part(Index row, Index column, const Mat3& value)
{
    if (is_symmetric_upper() && column < row)
        return;
    const Index k = find(row, column);
    if (k < 0)
        throw std::invalid_argument("BsrMatrix: block (" + std::to_string(row) + ", " + std::to_string(column) +
                                    ") is not in the pattern");
    add_to_block(k, value);
}

const Block3 BsrMatrix::block(Index k) const
{
    if (m_precision == MatrixPrecision::DOUBLE)
        return Eigen::Map<const Block3>(m_values.data() + 9 * static_cast<std::ptrdiff_t>(k));
    return Eigen::Map<const Eigen::Matrix<float, 3, 3, Eigen::RowMajor>>(m_single_values.data() +
                                                                         9 * static_cast<std::ptrdiff_t>(k))
        .cast<double>();
}

void BsrMatrix::set_block(Index k, const Block3& value)
{
    if (m_precision == MatrixPrecision::DOUBLE)
        Eigen::Map<Block3>(m_values.data() + 9 * static_cast<std::ptrdiff_t>(k)) = value;
    else
        Eigen::Map<Eigen::Matrix<float, 3, 3, Eigen::RowMajor>>(m_single_values.data() +
                                                                9 * static_cast<std::ptrdiff_t>(k)) =
            value.cast<float>();
}

void BsrMatrix::add_to_block(Index k, const Block3& value) { set_block(k, block(k) + value); }

void BsrMatrix::multiply_chunk(Index chunk, const double* xd, double* yd) const
{
    const Index begin = m_chunk_offsets[at(chunk)], end = m_chunk_offsets[at(chunk) + 1];
    std::fill(yd + 3 * static_cast<std::ptrdiff_t>(begin), yd + 3 * static_cast<std::ptrdiff_t>(end), 0.0);
    if (m_precision == MatrixPrecision::DOUBLE)
        detail::upper_chunk_rows(m_values.data(), m_columns.data(), m_row_offsets.data(), xd, yd, begin, end);
    else
        detail::upper_chunk_rows(m_single_values.data(), m_columns.data(), m_row_offsets.data(), xd, yd, begin, end);
}

void BsrMatrix::gather_chunk(Index chunk, const double* xd, double* yd) const
{
    for (Index row = m_chunk_offsets[at(chunk)]; row < m_chunk_offsets[at(chunk) + 1]; ++row) {
        const Index first = m_gather_offsets[at(row)], last = m_gather_offsets[at(row) + 1];
        if (first == last)
            continue;
        double* y_row = yd + 3 * static_cast<std::ptrdiff_t>(row);
        if (m_precision == MatrixPrecision::DOUBLE)
            detail::gather_row(m_values.data(), m_gather_blocks.data(), first, last, xd, y_row);
        else
            detail::gather_row(m_single_values.data(), m_gather_blocks.data(), first, last, xd, y_row);
    }
}

void BsrMatrix::multiply_upper_chunks(const double* xd, double* yd) const
{
    const auto n_chunks = static_cast<Index>(m_chunk_offsets.size()) - 1;
    tbb::parallel_for(tbb::blocked_range<Index>(0, n_chunks, 1), [&](const tbb::blocked_range<Index>& range) {
        for (Index chunk = range.begin(); chunk != range.end(); ++chunk)
            multiply_chunk(chunk, xd, yd);
    });
    tbb::parallel_for(tbb::blocked_range<Index>(0, n_chunks, 1), [&](const tbb::blocked_range<Index>& range) {
        for (Index chunk = range.begin(); chunk != range.end(); ++chunk)
            gather_chunk(chunk, xd, yd);
    });
}

void BsrMatrix::multiply(CRef<VecX> x, Eigen::Ref<VecX> y) const
{
    if (is_symmetric_upper()) {
        multiply_upper_chunks(x.data(), y.data());
        return;
    }
    tbb::parallel_for(tbb::blocked_range<Index>(0, num_block_rows(), SPMV_GRAIN),
                      [&](const tbb::blocked_range<Index>& range) {
                          if (m_precision == MatrixPrecision::DOUBLE)
                              multiply_rows(m_values.data(), m_columns.data(), m_row_offsets.data(), x.data(),
                                            y.data(), range.begin(), range.end());
                          else
                              multiply_rows(m_single_values.data(), m_columns.data(), m_row_offsets.data(), x.data(),
                                            y.data(), range.begin(), range.end());
                      });
}

SparseMat BsrMatrix::to_sparse() const
{
    std::vector<Eigen::Triplet<double, Index>> triplets;
    triplets.reserve(18 * m_columns.size());
    for (Index r = 0; r < num_block_rows(); ++r)
        for (Index k = m_row_offsets[at(r)]; k < m_row_offsets[at(r) + 1]; ++k) {
            const Index c = m_columns[at(k)];
            const Block3 value = block(k);
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b) {
                    triplets.emplace_back(3 * r + a, 3 * c + b, value(a, b));
                    if (is_symmetric_upper() && c != r)
                        triplets.emplace_back(3 * c + b, 3 * r + a, value(a, b));
                }
        }
    SparseMat sparse(num_dofs(), num_dofs());
    sparse.setFromTriplets(triplets.begin(), triplets.end());
    return sparse;
}

BsrMatrix BsrMatrix::with_precision(MatrixPrecision precision) const
{
    BsrMatrix copy = *this;
    copy.m_precision = precision;
    copy.allocate_values();
    for (Index k = 0; k < num_blocks(); ++k)
        copy.set_block(k, block(k));
    return copy;
}

BsrMatrix BsrMatrix::to_general() const
{
    if (!is_symmetric_upper())
        return *this;
    const Index n = num_block_rows();
    // Row r of the whole matrix: the mirrored blocks (k, source) of rows above it, then its own.
    std::vector<std::vector<std::pair<Index, Index>>> lower(at(n)); // per row: (column, stored block)
    for (Index r = 0; r < n; ++r)
        for (Index k = m_row_offsets[at(r)] + 1; k < m_row_offsets[at(r) + 1]; ++k)
            lower[at(m_columns[at(k)])].emplace_back(r, k);
    std::vector<Index> offsets{0}, columns;
    columns.reserve(2 * m_columns.size());
    for (Index r = 0; r < n; ++r) {
        for (const auto& [c, k] : lower[at(r)])
            columns.push_back(c);
        columns.insert(columns.end(), m_columns.begin() + m_row_offsets[at(r)],
                       m_columns.begin() + m_row_offsets[at(r) + 1]);
        offsets.push_back(static_cast<Index>(columns.size()));
    }
    BsrMatrix general(std::move(offsets), std::move(columns), m_precision);
    Index out = 0;
    for (Index r = 0; r < n; ++r) {
        for (const auto& [c, k] : lower[at(r)])
            general.set_block(out++, block(k).transpose());
        for (Index k = m_row_offsets[at(r)]; k < m_row_offsets[at(r) + 1]; ++k)
            general.set_block(out++, block(k));
    }
    return general;
}

} // namespace coro
