#pragma once
/// @file broad_phase.hpp
/// @brief Body-level broad phase: which pairs of body boxes overlap.

#include <corocontact/contact/aabb.hpp>

#include <utility>
#include <vector>

namespace coro {

/// All pairs (i, j), i < j, whose boxes overlap (Eq. 3), found by sort-and-sweep along the
/// axis of largest spread of the box centres: O(N log N + overlaps), not O(N²).
/// Empty boxes overlap nothing.
/// @param[in] boxes  one box per body
/// @param[out] pairs  sorted ascending by (i, j); its old content is replaced
/// @param[in,out] order  working memory (the boxes in sweep order). Both vectors keep their
///                       capacity, so a time loop passing the same ones allocates nothing once
///                       they have grown to the scene.
void overlapping_pairs(const std::vector<Aabb>& boxes, std::vector<std::pair<Index, Index>>& pairs,
                       std::vector<Index>& order);

/// The same, returned (for a single query).
std::vector<std::pair<Index, Index>> overlapping_pairs(const std::vector<Aabb>& boxes);

} // namespace coro
