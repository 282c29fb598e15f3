#pragma once
/// @file bsr_matrix.hpp
/// @brief Block sparse row matrix with 3×3 blocks: the pattern is built once per body and
/// its values refilled every step. Either every block is stored (general), or, for a
/// symmetric matrix, only the blocks on and above the diagonal (upper storage: half the
/// memory traffic in PCG, which is bandwidth bound). The values are stored in double or in
/// single precision, chosen at construction; products and sums always run in double.

#include <corocontact/core/types.hpp>

#include <array>
#include <vector>

namespace coro {

/// Row-major 3×3 block, as a BsrMatrix stores it.
using Block3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

/// How a BsrMatrix stores its values (case file: solver.matrix_precision).
enum class MatrixPrecision {
    DOUBLE, ///< 8 bytes per value
    SINGLE, ///< 4 bytes per value (rounded to float when written): half the memory traffic of
            ///< a product, whose vectors and sums stay double
};

/// A square matrix of #N×#N blocks of 3×3 (node × node); columns sorted within each row.
///
/// Upper storage holds block (r, c) for c ≥ r only and means A_cr = A_rcᵀ. Its product runs
/// in two passes over fixed row chunks: a chunk's task multiplies its rows and applies the
/// transposes of blocks whose column lies in the same chunk; blocks reaching across chunks
/// are then gathered per row in ascending source row. The chunks are part of the matrix, so
/// the result never depends on the thread count.
class BsrMatrix {
public:
    BsrMatrix() = default;

    /// @param[in] row_offsets  #N+1 offsets into `columns` (CSR of the block pattern)
    /// @param[in] columns      block column of each stored block, ascending within a row;
    ///                         every row must hold its diagonal block
    /// @param[in] precision    how the values are stored
    /// @throws std::invalid_argument if the pattern is malformed
    BsrMatrix(std::vector<Index> row_offsets, std::vector<Index> columns,
              MatrixPrecision precision = MatrixPrecision::DOUBLE);

    /// A symmetric matrix in upper storage.
    /// @param[in] row_offsets    #N+1 offsets into `columns`
    /// @param[in] columns        block columns, ascending within a row, each ≥ its row; the
    ///                           first block of every row is its diagonal
    /// @param[in] chunk_offsets  row boundaries 0 = c_0 < c_1 < … < c_m = #N of the product's
    ///                           tasks; choose them so that most couplings stay inside a chunk
    ///                           (the METIS parts); empty: chunks of 1024 rows
    /// @param[in] precision      how the values are stored
    /// @throws std::invalid_argument if the pattern or the chunks are malformed
    static BsrMatrix symmetric_upper(std::vector<Index> row_offsets, std::vector<Index> columns,
                                     std::vector<Index> chunk_offsets = {},
                                     MatrixPrecision precision = MatrixPrecision::DOUBLE);

    MatrixPrecision precision() const { return m_precision; }

    /// True for upper storage (see symmetric_upper()).
    bool is_symmetric_upper() const { return !m_chunk_offsets.empty(); }

    Index num_block_rows() const { return static_cast<Index>(m_row_offsets.size()) - 1; }
    Index num_blocks() const { return static_cast<Index>(m_columns.size()); }
    Index num_dofs() const { return 3 * num_block_rows(); }

    const std::vector<Index>& row_offsets() const { return m_row_offsets; }
    const std::vector<Index>& columns() const { return m_columns; }
    /// Index of the diagonal block of block row `row`.
    Index diagonal(Index row) const { return m_diagonal[static_cast<std::size_t>(row)]; }
    /// Index of block (row, column), or −1 if it is not stored (binary search; in upper
    /// storage blocks below the diagonal are never stored).
    Index find(Index row, Index column) const;

    /// Adds block (row, column) of a symmetric contribution whose mirror block (column, row)
    /// is added by the same caller: general storage adds it, upper storage adds it when
    /// column ≥ row and drops it otherwise (its mirror carries it).
    /// @throws std::invalid_argument if the block is not in the pattern
    void add_symmetric_part(Index row, Index column, const Mat3& value);

    /// The value of block k (a copy, in double; const so that assigning to it does not compile:
    /// write with set_block()).
    const Block3 block(Index k) const;
    /// Sets block k (rounded to float in single precision).
    void set_block(Index k, const Block3& value);
    /// Adds to block k: in double, then stored (rounded to float in single precision).
    void add_to_block(Index k, const Block3& value);

    /// The values of a double-precision matrix: 9 per block (row-major), blocks in pattern
    /// order. Empty for a single-precision matrix.
    std::vector<double>& values() { return m_values; }
    const std::vector<double>& values() const { return m_values; }
    /// The values of a single-precision matrix, likewise. Empty for a double-precision matrix.
    std::vector<float>& single_values() { return m_single_values; }
    const std::vector<float>& single_values() const { return m_single_values; }

    /// y = A x, parallel over block rows; each row is summed in pattern order, so the result
    /// does not depend on the thread count.
    /// @param[in] x   #3N DOFs
    /// @param[out] y  #3N DOFs (must not alias x)
    void multiply(CRef<VecX> x, Eigen::Ref<VecX> y) const;

    /// Upper storage: the product chunks' row boundaries, #chunks+1 (see symmetric_upper()).
    const std::vector<Index>& chunk_offsets() const { return m_chunk_offsets; }
    /// Upper storage: true if some stored block reaches from one chunk into a later one (its
    /// mirror is then added by gather_chunk()).
    bool has_gathers() const { return !m_gather_blocks.empty(); }

    /// Upper storage, the product's first pass over one chunk: y_r = Σ A_rc x_c for the chunk's
    /// rows r, with the mirrors A_crᵀ of blocks inside the chunk added to their rows. Chunks
    /// may run in parallel; rows of other chunks are not touched.
    /// @param[in] x   #3N DOFs (this matrix's node numbering)
    /// @param[out] y  #3N DOFs (must not alias x)
    void multiply_chunk(Index chunk, const double* x, double* y) const;

    /// Upper storage, the product's second pass: adds to the rows of one chunk the mirrors of
    /// blocks stored in earlier chunks, in ascending source row. Runs after multiply_chunk() of
    /// every chunk.
    void gather_chunk(Index chunk, const double* x, double* y) const;

    /// The same matrix as an Eigen sparse matrix, every block (tests, reference paths).
    SparseMat to_sparse() const;

    /// The same matrix in general storage (itself if it is general), in the same precision.
    BsrMatrix to_general() const;

    /// The same pattern, chunks and values in another precision (values rounded to float, or
    /// widened exactly to double).
    BsrMatrix with_precision(MatrixPrecision precision) const;

private:
    void check_pattern(bool upper);
    void allocate_values();
    void multiply_upper_chunks(const double* x, double* y) const;

    std::vector<Index> m_row_offsets{0};
    std::vector<Index> m_columns;
    std::vector<Index> m_diagonal;
    MatrixPrecision m_precision = MatrixPrecision::DOUBLE;
    std::vector<double> m_values;       // DOUBLE: 9 per block
    std::vector<float> m_single_values; // SINGLE: 9 per block
    // Upper storage only: the chunks, and per row the blocks (k, source row) of earlier
    // chunks whose column is this row, ascending in source row (CSR over rows).
    std::vector<Index> m_chunk_offsets;
    std::vector<Index> m_gather_offsets;
    std::vector<std::array<Index, 2>> m_gather_blocks;
};

} // namespace coro
