#pragma once
/// @file coupling_blocks.hpp
/// @brief Explicit 3×3 blocks added to a scene matrix, sorted by (row, column) with repeated
/// blocks summed: the contact coupling written out (ContactCoupling::blocks) for a copy of the
/// matrix's entries.

#include <corocontact/solver/bsr_matrix.hpp>

#include <vector>

namespace coro {

/// Blocks A_rc in scene rows. Capacity is kept between refills: once the list has held as many
/// entries as a refill needs, it allocates nothing.
class CouplingBlocks {
public:
    /// One contribution: block (row, column) of the scene matrix, in scene rows (nodes).
    struct Entry {
        Index row = 0, column = 0;
        Block3 value = Block3::Zero();
    };

    /// Empties the list and makes room for `count` contributions, to be set with entry().
    void reset(Index count);
    /// Contribution `i` of the `count` given to reset().
    Entry& entry(Index i) { return m_entries[static_cast<std::size_t>(i)]; }

    /// Sorts the contributions by (row, column) and sums repeated blocks in contribution order
    /// (so the result depends only on that order). Must be called after the entries are written
    /// and before any other query. Takes O(#contributions + num_rows): a counting sort by row,
    /// then the few blocks of a row by column.
    /// @param[in] num_rows  every entry's row is below it
    void finish(Index num_rows);

    /// Distinct blocks after finish(), sorted by (row, column).
    Index size() const { return m_size; }
    const Entry& block(Index k) const { return m_entries[static_cast<std::size_t>(k)]; }

private:
    std::vector<Entry> m_entries;
    std::vector<Entry> m_sorted;      // finish()'s output buffer
    std::vector<Index> m_row_offsets; // finish(): contributions per row, #rows+1
    std::vector<Index> m_order;       // finish(): contributions sorted by (row, column, order)
    Index m_size = 0;
};

} // namespace coro
