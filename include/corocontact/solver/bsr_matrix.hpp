#pragma once
/// @file bsr_matrix.hpp
/// @brief Block sparse row matrix with 3×3 blocks: the pattern is built once per body and
/// its values refilled every step.

#include <corocontact/core/types.hpp>

#include <vector>

namespace coro {

/// Row-major 3×3 block as stored in a BsrMatrix.
using Block3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

/// A square matrix of #N×#N blocks of 3×3 (node × node); columns sorted within each row.
class BsrMatrix {
public:
    BsrMatrix() = default;

    /// @param[in] row_offsets  #N+1 offsets into `columns` (CSR of the block pattern)
    /// @param[in] columns      block column of each stored block, ascending within a row;
    ///                         every row must hold its diagonal block
    /// @throws std::invalid_argument if the pattern is malformed
    BsrMatrix(std::vector<Index> row_offsets, std::vector<Index> columns);

    Index num_block_rows() const { return static_cast<Index>(m_row_offsets.size()) - 1; }
    Index num_blocks() const { return static_cast<Index>(m_columns.size()); }
    Index num_dofs() const { return 3 * num_block_rows(); }

    const std::vector<Index>& row_offsets() const { return m_row_offsets; }
    const std::vector<Index>& columns() const { return m_columns; }
    /// Index of the diagonal block of block row `row`.
    Index diagonal(Index row) const { return m_diagonal[static_cast<std::size_t>(row)]; }
    /// Index of block (row, column), or −1 if it is not in the pattern (binary search).
    Index find(Index row, Index column) const;

    Eigen::Map<Block3> block(Index k) { return Eigen::Map<Block3>(m_values.data() + 9 * k); }
    Eigen::Map<const Block3> block(Index k) const
    {
        return Eigen::Map<const Block3>(m_values.data() + 9 * k);
    }
    /// All values, 9 per block, blocks in pattern order.
    std::vector<double>& values() { return m_values; }
    const std::vector<double>& values() const { return m_values; }

    /// y = A x, parallel over block rows; each row is summed in pattern order, so the result
    /// does not depend on the thread count.
    /// @param[in] x   #3N DOFs
    /// @param[out] y  #3N DOFs (must not alias x)
    void multiply(CRef<VecX> x, Eigen::Ref<VecX> y) const;

    /// y = A x and, in the same pass, x·y (PCG's pᵀAp) with a fixed reduction tree
    /// (tbb::parallel_deterministic_reduce over fixed row chunks): bitwise the same for any
    /// thread count, and y bitwise equal to multiply().
    /// @param[in] x   #3N DOFs
    /// @param[out] y  #3N DOFs (must not alias x)
    /// @return x·y (not checked for finiteness)
    double multiply_dot(CRef<VecX> x, Eigen::Ref<VecX> y) const;

    /// The same matrix as an Eigen sparse matrix (tests, reference paths).
    SparseMat to_sparse() const;

private:
    std::vector<Index> m_row_offsets{0};
    std::vector<Index> m_columns;
    std::vector<Index> m_diagonal;
    std::vector<double> m_values;
};

} // namespace coro
