#pragma once
/// @file coupling_blocks.hpp
/// @brief The 3×3 blocks that contact adds between nodes of a scene system: a list refilled
/// every step, sorted by (row, column) with repeated blocks summed, never a rebuilt matrix.

#include <corocontact/solver/bsr_matrix.hpp>
#include <corocontact/solver/row_chunks.hpp>

#include <vector>

namespace coro {

/// Blocks A_rc added to a scene matrix; both (r, c) and (c, r) are stored, so a row's sum
/// needs no transposes. Capacity is kept between steps: once the list has held as many entries
/// as a step needs, refilling it allocates nothing.
class CouplingBlocks {
public:
    /// One contribution: block (row, column) of the scene matrix, in scene rows (nodes).
    struct Entry {
        Index row = 0, column = 0;
        Block3 value = Block3::Zero();
    };

    /// Empties the list and makes room for `count` contributions, to be set with entry().
    void reset(Index count);
    /// Contribution `i` of the `count` given to reset(), to be filled by its writer (entries
    /// may be written in parallel, each by one writer).
    Entry& entry(Index i) { return m_entries[static_cast<std::size_t>(i)]; }

    /// Sorts the contributions by (row, column), sums repeated blocks in contribution order (so
    /// the result depends only on that order), and indexes them by the chunks' rows. Must be
    /// called after the entries are written and before any other query. Takes O(#contributions
    /// + #rows): a counting sort by row, then the few blocks of a row by column.
    /// @param[in] column_order  null, or for every column index the key by which the blocks of a
    ///                          row are ordered (a process of a distributed run numbers its
    ///                          columns locally but orders them as one process numbers them;
    ///                          the order decides the bits of a row's product)
    void finish(const RowChunks& chunks, const std::vector<Index>* column_order = nullptr);

    /// Distinct blocks after finish(), sorted by (row, column).
    Index size() const { return m_size; }
    const Entry& block(Index k) const { return m_entries[static_cast<std::size_t>(k)]; }
    /// Blocks of chunk c's rows: [chunk_begin(c), chunk_begin(c + 1)).
    Index chunk_begin(Index chunk) const { return m_chunk_offsets[static_cast<std::size_t>(chunk)]; }

    /// y_r += Σ_c A_rc x_c for the rows of chunk `chunk`.
    /// @param[in] x   scene DOFs, #3N
    /// @param[in,out] y  scene DOFs, #3N
    void multiply_add(Index chunk, const double* x, double* y) const;

private:
    std::vector<Entry> m_entries;
    std::vector<Entry> m_sorted;      // finish()'s output buffer
    std::vector<Index> m_row_offsets; // finish(): contributions per row, #rows+1
    std::vector<Index> m_order;       // finish(): contributions sorted by (row, column, order)
    std::vector<Index> m_chunk_offsets{0, 0};
    Index m_size = 0;
};

} // namespace coro
