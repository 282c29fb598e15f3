#include "grouped_inside_tests.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <corocontact/core/error.hpp>

#include <algorithm>
#include <functional>
#include <tuple>

namespace coro::detail {

namespace {

// Tested vertices per task.
constexpr std::size_t TEST_BLOCK = 256;

} // namespace

void grouped_inside_tests(const std::vector<ContactSurface>& surfaces, const std::vector<PairCandidates>& candidates,
                          const AxisRayTolerances& tolerances, bool distance_bounds,
                          const std::function<void(std::size_t pair, const GroupedAnswers& answers)>& use)
{
    const std::size_t pairs = candidates.size();
    // The face pairs (as tree slots) of each body pair, found once for both directions:
    // candidates holds (a, b) and (b, a), the region I is the same.
    std::vector<std::vector<std::array<Index, 2>>> slot_pairs(pairs);
    std::vector<std::size_t> lower(pairs); // the direction whose body < other, for each k
    std::vector<std::size_t> walks;
    for (std::size_t k = 0; k < pairs; ++k) {
        const PairCandidates& pair = candidates[k];
        if (pair.body < pair.other)
            walks.push_back(k);
        lower[k] = k;
        if (pair.body > pair.other) { // candidates are ordered by (body, other)
            const auto reverse = std::lower_bound(candidates.begin(), candidates.end(), pair,
                                                  [](const PairCandidates& x, const PairCandidates& y) {
                                                      return std::tie(x.body, x.other) < std::tie(y.other, y.body);
                                                  });
            CORO_ASSERT(reverse != candidates.end() && reverse->body == pair.other && reverse->other == pair.body);
            lower[k] = static_cast<std::size_t>(reverse - candidates.begin());
        }
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, walks.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t w = r.begin(); w < r.end(); ++w) {
            const PairCandidates& pair = candidates[walks[w]];
            const ContactSurface& body = surfaces[static_cast<std::size_t>(pair.body)];
            const ContactSurface& other = surfaces[static_cast<std::size_t>(pair.other)];
            if (other.closed || body.closed)
                body.tree.overlapping_slots(other.tree, pair.overlap, slot_pairs[walks[w]]);
        }
    });
    // Per pair, in one task: the groups, the tests of their first vertices (blocks of them as
    // nested tasks when there are many) and their use, where the rest of each group take them.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pairs, 1), [&](const tbb::blocked_range<std::size_t>& r) {
        GroupedAnswers answers;
        std::vector<Index>& decider = answers.decider;
        std::vector<InsideTest>& answer = answers.answer;
        std::vector<Index> tested;
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const PairCandidates& pair = candidates[k];
            const ContactSurface& body = surfaces[static_cast<std::size_t>(pair.body)];
            const ContactSurface& other = surfaces[static_cast<std::size_t>(pair.other)];
            const std::size_t n = pair.vertices.size();
            if (other.closed) {
                body.tree.clear_edge_groups(body.vertices, other.tree, other.vertices, slot_pairs[lower[k]],
                                            lower[k] == k ? 0 : 1, pair.vertices, decider,
                                            distance_bounds ? &answers.path : nullptr);
            } else {
                decider.resize(n);
                for (std::size_t i = 0; i < n; ++i)
                    decider[i] = static_cast<Index>(i);
                if (distance_bounds)
                    answers.path.assign(n, 0.0);
            }
            tested.clear();
            for (std::size_t i = 0; i < n; ++i)
                if (decider[i] == static_cast<Index>(i))
                    tested.push_back(static_cast<Index>(i));

            answer.resize(n);
            const auto test_block = [&](std::size_t first, std::size_t last) {
                Vec3 points[TEST_BLOCK];
                InsideTest results[TEST_BLOCK];
                const auto count = static_cast<Index>(last - first);
                for (Index t = 0; t < count; ++t) {
                    const Index i = tested[first + static_cast<std::size_t>(t)];
                    points[t] = body.vertices.row(pair.vertices[static_cast<std::size_t>(i)]).transpose();
                }
                inside_tests(other, points, count, DetectionMode::EXACT, {}, tolerances, results);
                for (Index t = 0; t < count; ++t)
                    answer[static_cast<std::size_t>(tested[first + static_cast<std::size_t>(t)])] = results[t];
            };
            if (tested.size() <= TEST_BLOCK) {
                test_block(0, tested.size());
            } else {
                const std::size_t blocks = (tested.size() + TEST_BLOCK - 1) / TEST_BLOCK;
                tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 1),
                                  [&](const tbb::blocked_range<std::size_t>& b) {
                                      for (std::size_t j = b.begin(); j < b.end(); ++j)
                                          test_block(j * TEST_BLOCK, std::min(tested.size(), (j + 1) * TEST_BLOCK));
                                  });
            }

            use(k, answers);
        }
    });
}

} // namespace coro::detail
