#include <corocontact/partition/element_loop.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace coro {

void for_each_part(Index num_parts, const std::function<void(Index part)>& work)
{
    tbb::parallel_for(tbb::blocked_range<Index>(0, num_parts, 1), [&](const tbb::blocked_range<Index>& range) {
        for (Index p = range.begin(); p != range.end(); ++p)
            work(p);
    });
}

} // namespace coro
