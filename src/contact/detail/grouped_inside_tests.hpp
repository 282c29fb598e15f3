#pragma once
/// @file grouped_inside_tests.hpp
/// @brief Exact inside tests of the candidate vertices of every pair, one test per group of
/// vertices joined by clear edges.

#include <corocontact/contact/detector.hpp>

#include "clear_edge_groups.hpp"
#include "pair_buffers.hpp"
#include "tree_access.hpp"

#include <tbb/enumerable_thread_specific.h>

#include <functional>
#include <utility>
#include <vector>

namespace coro::detail {

/// The exact-mode answers of one pair's candidates, by groups: candidate i belongs to group
/// group[i], whose first candidate tested[group[i]] was tested, with answer answer[group[i]].
/// With distance bounds, path[i] is the length of a path of clear edges from candidate
/// tested[group[i]] to candidate i [m] (0 for a tested one).
struct GroupedAnswers {
    std::vector<Index> group;       ///< size n (the pair's candidates): 0 .. groups − 1
    std::vector<Index> tested;      ///< size groups: each group's first candidate, ascending
    std::vector<InsideTest> answer; ///< size groups: the test of candidate tested[g]
    std::vector<double> path;       ///< size n with distance bounds, else empty
};

/// Pairs with fewer candidate vertices (both directions together) are not grouped: there the
/// walk of the two trees for face pairs and the grouping cost more than the tests they save.
/// Small bodies in contact have a few candidates per pair; a pile of 216 bodies of 200 tets
/// detects in 15–18 % less time without grouping, and the same with 64, 256 or no limit.
constexpr std::size_t MIN_GROUPED_CANDIDATES = 64;

/// Whether a pair's candidates are grouped, with the face pairs of its two surfaces
/// (overlapping_slots()), and the working memory that finds them.
struct PairSlots {
    bool grouped = false; ///< else `pairs` is empty and every candidate is tested
    SlotPairs pairs;
    SlotWalkScratch walk;
};

/// The working memory of grouped_inside_tests(), kept from call to call.
struct GroupingScratch {
    tbb::enumerable_thread_specific<GroupScratch> groups; ///< per thread, for clear_edge_groups()
    std::vector<std::pair<Index, Index>> keys;            ///< per pair of candidates: (body, other)
    PairBuffers<GroupedAnswers> answers;                  ///< per pair of candidates
    std::vector<std::size_t> pair_candidates;             ///< per pair: candidates of both directions
};

/// For each pair (a, b) of `pairs` with MIN_GROUPED_CANDIDATES or more candidates (both
/// directions of `candidates`) and a closed surface: grouped, with overlapping_slots() of a's tree
/// and b's over the overlap of their boxes. Else not grouped. As TBB tasks.
/// @param[in] candidates   pair_candidates() of `pairs`: both directions, ordered by (body, other)
/// @param[in] pair_of      per entry of `candidates`: the index of its pair in `pairs`
/// @param[out] slot_pairs  one per pair
void overlapping_slot_pairs(const std::vector<ContactSurface>& surfaces,
                            const std::vector<std::pair<Index, Index>>& pairs,
                            const std::vector<PairCandidates>& candidates, const std::vector<std::size_t>& pair_of,
                            GroupingScratch& scratch, PairBuffers<PairSlots>& slot_pairs);

/// Exact-mode answers for every candidate vertex, handed over pair by pair: use(k, answers) for
/// candidates[k].vertices, called once per pair from that pair's TBB task (pairs run in parallel;
/// `use` may start nested tasks). Where the pair is grouped and the other surface closed, the
/// candidates of a pair are grouped by clear_edge_groups() and only the first of each group is tested; the others share
/// its answer, with shared_distance_bound() as theirs. Else every candidate is tested. The tests
/// of a pair with many groups run in nested tasks; the answers do not depend on the scheduling.
/// @param[in] pair_of     per entry of `candidates`: the index of its pair in `slot_pairs`
/// @param[in] slot_pairs  overlapping_slot_pairs() of the pairs (body < other) of `candidates`,
///                        in their order, called with the same `candidates` and `scratch`
void grouped_inside_tests(const std::vector<ContactSurface>& surfaces, const std::vector<PairCandidates>& candidates,
                          const std::vector<std::size_t>& pair_of, const std::vector<PairSlots>& slot_pairs,
                          const AxisRayTolerances& tolerances, bool distance_bounds, GroupingScratch& scratch,
                          const std::function<void(std::size_t pair, const GroupedAnswers& answers)>& use);

/// The surface distance bound of candidate i of `answers` that was not tested: the bound of its
/// group's tested candidate plus its path, rounded up by a relative 10⁻¹² (far above the
/// rounding of the two terms), so some point of the surface lies within it [m].
inline double shared_distance_bound(const GroupedAnswers& answers, std::size_t i)
{
    const InsideTest& from = answers.answer[static_cast<std::size_t>(answers.group[i])];
    return (from.surface_distance_bound + answers.path[i]) * (1.0 + 1e-12);
}

} // namespace coro::detail
