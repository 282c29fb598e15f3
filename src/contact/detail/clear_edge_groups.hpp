#pragma once
/// @file clear_edge_groups.hpp
/// @brief Groups of candidate vertices joined by edges that meet no face of the other surface:
/// the vertices of a group are all inside the other (closed) surface or all outside it, so one
/// inside test answers for the group.

#include <corocontact/contact/contact_surface.hpp>

#include <array>
#include <vector>

namespace coro::detail {

/// Face pairs (face of one surface, face of the other), each face given by its slot in its
/// surface's tree (overlapping_slots in tree_access.hpp).
using SlotPairs = std::vector<std::array<Index, 2>>;

/// Which column of a SlotPairs holds the faces of the surface being grouped.
enum class PairColumn { FIRST, SECOND };

/// Working arrays of clear_edge_groups(), kept from call to call, as large as the largest
/// surface grouped with them. Between calls `paired` holds −1 everywhere (a call resets the
/// entries it set) and `state` holds no UNGROUPED (any other value stops the search as
/// NOT_CANDIDATE does, so stale groups need no reset). One per thread.
struct GroupScratch {
    std::vector<Index> paired;    // per slot of the grouped surface: −1, or its dense id among the paired faces
    std::vector<Index> state;     // per vertex of the grouped surface
    std::vector<Index> start, partners, next, queue;
    std::vector<double> length_to; // per vertex, valid where grouped
};

/// Throws InputError unless `surface`'s edges and tree were built with its faces and vertices,
/// as clear_edge_groups() requires of the surface it groups.
void check_edges_and_tree(const ContactSurface& surface);

/// The groups of candidate vertices of `surface`: vertices joined by a path of edges of
/// `surface` that meet no face of `other` are in one group, so for a closed `other` all inside
/// it or all outside. An edge is clear when one of its faces is in no pair of `pairs`, or when
/// each face of `other` paired with one of its faces whose box meets the edge's is shown to miss
/// the edge by signs beyond their rounding (segment_triangle.hpp). A vertex on `other`'s surface
/// meets a face with every edge, so it is a group of its own. `surface` must pass
/// check_edges_and_tree().
/// @param[in] pairs       overlapping_slots() of the two surfaces' trees over a region that
///                        holds every candidate, `surface`'s in column `column`
/// @param[in] candidates  distinct vertices of `surface` in that region
/// @param[out] group      per candidate, its group, 0 .. groups − 1, numbered in the order of
///                        their first candidates
/// @param[out] firsts     per group, the index into `candidates` of its first candidate (ascending)
/// @param[out] path       null, or per candidate an upper bound of the length of a path of clear
///                        edges from its group's first candidate (0 for that one) [m]
/// @return the number of groups
Index clear_edge_groups(const ContactSurface& surface, const ContactSurface& other, const SlotPairs& pairs,
                        PairColumn column, const std::vector<Index>& candidates, GroupScratch& scratch,
                        std::vector<Index>& group, std::vector<Index>& firsts, std::vector<double>* path);

} // namespace coro::detail
