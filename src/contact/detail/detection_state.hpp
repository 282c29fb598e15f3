#pragma once
/// @file detection_state.hpp
/// @brief What a DetectionScratch holds: every buffer of a detection, kept from call to call,
/// so that a time loop allocates nothing once they have grown to the scene (DESIGN.md: no
/// allocation in the steady state).

#include <corocontact/contact/detector.hpp>

#include "clear_edge_groups.hpp"
#include "grouped_inside_tests.hpp"
#include "hull_slabs.hpp"
#include "nearest_search.hpp"
#include "pair_buffers.hpp"

#include <tbb/enumerable_thread_specific.h>

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace coro::detail {

/// Candidates first .. first + count − 1 of pair `pair`: a task of a detection pass.
struct CandidateBlock {
    std::size_t pair;
    Index first, count;
};

/// Where the depth searches of the vertices of `body` inside `other` start: per vertex of body,
/// the face of `other` nearest to it at its last depth search (−1: none yet). A start that is
/// out of date, or from other surfaces, costs time, never the answer.
struct LastFaces {
    Index body = -1, other = -1;
    std::vector<Index> face;
};

class DetectionState {
public:
    // Broad and mid phase.
    std::vector<Aabb> boxes;                   ///< per surface, its tree's bounds
    std::vector<HullSlabs> hulls;              ///< per surface: its slabs, where hull_wanted
    std::vector<unsigned char> hull_wanted;    ///< per surface: tested by a pair not grouped
    std::vector<Index> dropped;                ///< per entry of `directed`: candidates outside the hull
    std::vector<Index> sweep_order;            ///< overlapping_pairs()' working memory
    std::vector<std::pair<Index, Index>> pairs; ///< the overlapping surfaces (body < other)
    std::vector<std::pair<Index, Index>> directed; ///< both directions of each pair, ascending
    std::vector<std::size_t> pair_of;          ///< per entry of `directed`: the index of its pair
    std::vector<Index> directed_offsets;       ///< pair_candidates()' working memory
    PairBuffers<PairCandidates> candidates;    ///< per entry of `directed`
    tbb::enumerable_thread_specific<std::vector<Index>> overlapping_faces; ///< per thread (paper mode)
    PairBuffers<PairSlots> slot_pairs;         ///< per entry of `pairs`: overlapping_slot_pairs()
    GroupingScratch grouping;                  ///< grouped_inside_tests()' working memory
    std::vector<CandidateBlock> blocks;        ///< the tasks of a pass without groups

    // The pass (DetectionPass).
    std::vector<FacePlaneCache> planes;                   ///< per surface, for its depth searches
    tbb::enumerable_thread_specific<DetectionStats> stats; ///< per thread, for the pass's counts
    std::vector<std::size_t> offsets; ///< pair k's candidate i is slot offsets[k] + i
    std::vector<unsigned char> inside; ///< per slot: 1 when inside
    std::vector<ContactPoint> slots;   ///< per slot, with contact data: the inside vertices' points
    std::vector<Index> count;          ///< per vertex of one body: the sort's counts
    std::vector<std::array<std::uint32_t, 2>> order; ///< the inside (pair, candidate) of one body, sorted
    /// Per entry of `directed`: where its searches start, kept while the pair lasts.
    PairBuffers<LastFaces> last_faces;
};

struct ScratchAccess {
    static DetectionState& state(DetectionScratch& scratch) { return *scratch.m_state; }
};

} // namespace coro::detail
