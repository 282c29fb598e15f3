#include "grouped_inside_tests.hpp"

#include "inside_tests.hpp"
#include "tree_access.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <corocontact/core/error.hpp>

#include <algorithm>
#include <functional>

namespace coro::detail {

namespace {

// Tested vertices per task.
constexpr std::size_t TEST_BLOCK = 256;

} // namespace

void overlapping_slot_pairs(const std::vector<ContactSurface>& surfaces,
                            const std::vector<std::pair<Index, Index>>& pairs,
                            const std::vector<PairCandidates>& candidates, const std::vector<std::size_t>& pair_of,
                            GroupingScratch& scratch, PairBuffers<PairSlots>& slot_pairs)
{
    CORO_ASSERT(pair_of.size() == candidates.size());
    std::vector<std::size_t>& count = scratch.pair_candidates;
    count.assign(pairs.size(), 0);
    for (std::size_t k = 0; k < candidates.size(); ++k)
        count[pair_of[k]] += candidates[k].vertices.size();
    std::vector<PairSlots>& out = slot_pairs.assign(pairs);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pairs.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t j = r.begin(); j < r.end(); ++j) {
            const ContactSurface& a = surfaces[static_cast<std::size_t>(pairs[j].first)];
            const ContactSurface& b = surfaces[static_cast<std::size_t>(pairs[j].second)];
            const bool closed = a.closed || b.closed;
            if (closed) { // for every pair, not only those grouped
                check_edges_and_tree(a);
                check_edges_and_tree(b);
            }
            out[j].grouped = closed && count[j] >= MIN_GROUPED_CANDIDATES;
            if (out[j].grouped)
                overlapping_slots(a.tree, b.tree, a.tree.bounds().intersection(b.tree.bounds()), out[j].pairs,
                                  out[j].walk);
            else
                out[j].pairs.clear();
        }
    });
}

void grouped_inside_tests(const std::vector<ContactSurface>& surfaces, const std::vector<PairCandidates>& candidates,
                          const std::vector<std::size_t>& pair_of, const std::vector<PairSlots>& slot_pairs,
                          const AxisRayTolerances& tolerances, bool distance_bounds, GroupingScratch& scratch,
                          const std::function<void(std::size_t pair, const GroupedAnswers& answers)>& use)
{
    const std::size_t pairs = candidates.size();
    // The face pairs of each k: those of its pair, columns swapped for body > other.
    CORO_ASSERT(pair_of.size() == pairs);
    // Per pair, in one task: the groups, the tests of their first vertices (blocks of them as
    // nested tasks when there are many) and their use, where the rest of each group take them.
    // The answers of a pair have their own buffers: while a task waits for its nested tasks, its
    // thread may take up another pair.
    scratch.keys.clear();
    for (const PairCandidates& pair : candidates)
        scratch.keys.emplace_back(pair.body, pair.other);
    std::vector<GroupedAnswers>& answers_of = scratch.answers.assign(scratch.keys);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pairs, 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            GroupedAnswers& answers = answers_of[k];
            std::vector<Index>& group = answers.group;
            std::vector<Index>& tested = answers.tested;
            std::vector<InsideTest>& answer = answers.answer;
            const PairCandidates& pair = candidates[k];
            const ContactSurface& body = surfaces[static_cast<std::size_t>(pair.body)];
            const ContactSurface& other = surfaces[static_cast<std::size_t>(pair.other)];
            const std::size_t n = pair.vertices.size();
            if (!distance_bounds)
                answers.path.clear();
            if (other.closed && slot_pairs[pair_of[k]].grouped) {
                clear_edge_groups(body, other, slot_pairs[pair_of[k]].pairs,
                                  pair.body < pair.other ? PairColumn::FIRST : PairColumn::SECOND, pair.vertices,
                                  scratch.groups.local(), group, tested, distance_bounds ? &answers.path : nullptr);
            } else {
                group.resize(n);
                for (std::size_t i = 0; i < n; ++i)
                    group[i] = static_cast<Index>(i);
                tested = group;
                if (distance_bounds)
                    answers.path.assign(n, 0.0);
            }

            answer.resize(tested.size());
            const auto test_block = [&](std::size_t first, std::size_t last) {
                Vec3 points[TEST_BLOCK];
                const auto count = static_cast<Index>(last - first);
                for (Index t = 0; t < count; ++t) {
                    const Index i = tested[first + static_cast<std::size_t>(t)];
                    points[t] = body.vertices.row(pair.vertices[static_cast<std::size_t>(i)]).transpose();
                }
                inside_tests(other, points, count, DetectionMode::EXACT, {}, tolerances, answer.data() + first);
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
