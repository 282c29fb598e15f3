#include <corocontact/solver/row_chunks.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace coro {

void RowChunks::group_tasks(Index min_rows)
{
    task_offsets.assign(1, 0);
    Index rows = 0;
    for (Index c = 0; c < num_chunks(); ++c) {
        rows += offsets[static_cast<std::size_t>(c) + 1] - offsets[static_cast<std::size_t>(c)];
        if (rows >= min_rows || c + 1 == num_chunks()) {
            task_offsets.push_back(c + 1);
            rows = 0;
        }
    }
}

void for_each_chunk(const RowChunks& chunks, FunctionRef<void(Index chunk, Index begin, Index end)> work)
{
    tbb::parallel_for(tbb::blocked_range<Index>(0, chunks.num_tasks(), 1), [&](const tbb::blocked_range<Index>& tasks) {
        for (Index task = tasks.begin(); task != tasks.end(); ++task)
            for (Index c = chunks.task_offsets[static_cast<std::size_t>(task)];
                 c < chunks.task_offsets[static_cast<std::size_t>(task) + 1]; ++c)
                work(c, chunks.offsets[static_cast<std::size_t>(c)], chunks.offsets[static_cast<std::size_t>(c) + 1]);
    });
}

} // namespace coro
