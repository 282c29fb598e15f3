#pragma once
/// @file row_chunks.hpp
/// @brief The block rows (nodes) of a scene system cut into chunks, and the chunks grouped into
/// tasks.
///
/// A chunk is the leaf of every reduction: a sum over rows is formed per chunk and the chunk
/// sums are added in chunk order, so results depend on the chunks — which the bodies define —
/// and never on the thread count. A task is a run of consecutive chunks carrying enough rows to
/// pay for a TBB task, so a scene of many small bodies runs as a few dozen tasks rather than one
/// per body.

#include <corocontact/core/function_ref.hpp>
#include <corocontact/core/types.hpp>

#include <vector>

namespace coro {

struct RowChunks {
    std::vector<Index> offsets{0};      ///< #chunks+1 row boundaries, rising strictly from 0
    std::vector<Index> task_offsets{0}; ///< #tasks+1 chunk boundaries, rising strictly from 0

    Index num_chunks() const { return static_cast<Index>(offsets.size()) - 1; }
    Index num_tasks() const { return static_cast<Index>(task_offsets.size()) - 1; }
    Index num_rows() const { return offsets.back(); }

    /// Appends a chunk of `rows` rows (≥ 1).
    void append(Index rows) { offsets.push_back(offsets.back() + rows); }

    /// Groups the chunks into tasks: consecutive chunks until a task holds at least `min_rows`
    /// rows (the last task may hold fewer).
    void group_tasks(Index min_rows);
};

/// Calls `work(chunk, row_begin, row_end)` once for every chunk: tasks run in parallel, the
/// chunks of a task in ascending order.
void for_each_chunk(const RowChunks& chunks, FunctionRef<void(Index chunk, Index begin, Index end)> work);

} // namespace coro
