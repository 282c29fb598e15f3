#pragma once
/// @file detection_state.hpp
/// @brief What a DetectionScratch holds.

#include <corocontact/contact/detector.hpp>

#include "clear_edge_groups.hpp"
#include "nearest_search.hpp"

#include <tbb/enumerable_thread_specific.h>

#include <array>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace coro::detail {

class DetectionState {
public:
    std::vector<FacePlaneCache> planes;                  ///< per surface, for its depth searches
    tbb::enumerable_thread_specific<GroupScratch> groups; ///< per thread, for clear_edge_groups()
    tbb::enumerable_thread_specific<DetectionStats> stats; ///< per thread, for the pass's counts
    std::vector<std::size_t> offsets; ///< pair k's candidate i is slot offsets[k] + i
    std::vector<unsigned char> inside; ///< per slot: 1 when inside
    std::vector<ContactPoint> slots;   ///< per slot, with contact data: the inside vertices' points
    std::vector<Index> count;          ///< per vertex of one body: the sort's counts
    std::vector<std::array<std::uint32_t, 2>> order; ///< the inside (pair, candidate) of one body, sorted
    /// Per ordered pair (body, other): per vertex of body, the face of `other` nearest to it
    /// at its last depth search (−1: none yet), where the next search starts (a start that is
    /// out of date, or from other surfaces, costs time, never the answer).
    std::map<std::pair<Index, Index>, std::vector<Index>> last_face;
};

struct ScratchAccess {
    static DetectionState& state(DetectionScratch& scratch) { return *scratch.m_state; }
};

} // namespace coro::detail
