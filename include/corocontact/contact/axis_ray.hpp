#pragma once
/// @file axis_ray.hpp
/// @brief The axis-oriented ray-projection inside test of one vertex against one surface
/// (paper §3, Eq. 4–6; DESIGN.md, Contact detection).

#include <corocontact/contact/contact_surface.hpp>

#include <limits>
#include <vector>

namespace coro {

enum class DetectionMode {
    EXACT, ///< closest crossing over the whole surface through the tree; degenerate axes skipped;
           ///< undecided vertices fall back to the winding number
    PAPER, ///< closest crossing among the candidate faces only (faces with a vertex inside I)
    BRUTE_FORCE, ///< reference for tests and benchmarks: EXACT's classification against every
                 ///< face of the surface, no tree
};

/// How one axis query ended.
enum class AxisOutcome {
    INSIDE,
    OUTSIDE,
    NO_HIT,     ///< the axis line meets no (candidate) face
    DEGENERATE, ///< exact modes: the closest contact is an edge, a vertex, a parallel face, or
                ///< competing crossings disagree: this axis does not decide
    ON_SURFACE, ///< exact modes: the point lies on the surface (on a face's plane, within the
                ///< rounding bound, and inside its projection): reported as not inside
};

/// Tolerances of the narrow phase. The exact modes add to each a bound of the floating-point
/// rounding of the quantity tested, so a decision is never taken on a sign rounding can flip.
struct AxisRayTolerances {
    double area_relative = 1e-9;   ///< paper mode, Eq. 5/6: inside when |A1|+|A2|+|A3| ≤ (1 + this)·|Af|
    double edge_relative = 1e-9;   ///< exact modes: a barycentric weight A_i/Af below this ⇒ on an edge
                                   ///< or vertex ⇒ degenerate
    double parallel_relative = 1e-12; ///< exact modes: |projected area| ≤ this · face area ⇒ the face
                                      ///< is parallel to the axis ⇒ degenerate when it is met
    double tie_relative = 1e-9;    ///< exact modes: crossings within (1 + this) of the closest one
                                   ///< (plus rounding bounds) compete; any disagreement ⇒ degenerate
};

/// One axis of the test: project `point` and `candidate_faces` onto the plane orthogonal to
/// `axis`, prefilter by bounding rectangles (Eq. 4), area test (Eq. 5/6), then the closest
/// crossing along the axis line (either direction) decides by the sign of d·n, d the unit vector
/// from `point` toward the crossing, n the face's outward normal: d·n > 0 ⇒ inside.
///
/// Paper mode: strict Eq. 4, Eq. 5/6 with `area_relative`; faces with zero projected area are
/// skipped; of equally close crossings the first candidate wins; d·n = 0 (a point on the face)
/// counts as outside. Never returns DEGENERATE or ON_SURFACE.
///
/// Exact modes: every face whose projection contains the point's, closed and within the
/// rounding bound, is a crossing; one within `edge_relative` of an edge is an edge crossing; a
/// face with |n_axis| ≤ `parallel_relative`·|n| is parallel (its distance is that of its extent
/// along the axis). Let R be the smallest distance of a crossing plus its rounding bound; the
/// crossings whose distance minus bound is within (1 + `tie_relative`)·R compete. ON_SURFACE if
/// one of them has the point on its plane (within rounding); DEGENERATE if one is an edge or
/// parallel crossing, if their votes differ, or if only parallel faces are met; else their
/// common vote. For a closed, consistently oriented surface a decision is the exact answer.
/// @param[in] candidate_faces  faces to consider (paper mode); ignored in the exact modes, where
///                             the surface's tree (EXACT) or a scan (BRUTE_FORCE) gives every
///                             face crossing the line
AxisOutcome axis_test(const ContactSurface& surface, const Vec3& point, int axis, DetectionMode mode,
                      const std::vector<Index>& candidate_faces, const AxisRayTolerances& tolerances);

/// Result of the full test of one vertex (axes x, then y, then z; then winding number in
/// exact mode).
struct InsideTest {
    bool inside = false;
    /// 0..2, or 3 for the winding-number fallback, −1: no axis hit; DECIDED_BY_NEIGHBOUR: the
    /// answer of another point joined to it by segments that meet no face (inside_tests_shared():
    /// an empty cube or AabbTree::segment_clear)
    int deciding_axis = -1;
    bool on_surface = false;       ///< exact modes: the point lies on the surface (then not inside)
    /// Exact modes, decided by an axis: the distance along that axis to the closest clean face
    /// crossing plus its rounding bound, so some point of the surface lies within it (an upper
    /// bound on the depth, used to start the nearest-point search); +∞ otherwise.
    double surface_distance_bound = std::numeric_limits<double>::infinity();
    /// Exact modes, decided by an axis: the face of that closest clean crossing (−1 otherwise).
    Index crossing_face = -1;
};

/// InsideTest::deciding_axis of a point that took a neighbour's answer (inside_tests_shared();
/// the detector's clear-edge groups count theirs in DetectionStats::by_neighbour).
constexpr int DECIDED_BY_NEIGHBOUR = 4;

/// Paper mode: axes x, y, z until one has a hit (INSIDE or OUTSIDE); no hit on all three ⇒
/// outside (deciding_axis −1).
/// Exact modes: axes x, y, z; INSIDE, OUTSIDE or ON_SURFACE decide (a point on the surface is
/// reported as not inside, `on_surface` set); NO_HIT also decides outside (a line through an
/// inside point of a closed surface always meets it); DEGENERATE tries the next axis; three
/// degenerate axes fall back to the generalized winding number (w > 0.5, deciding_axis 3).
/// A surface that is not closed is tested by the winding number alone (deciding_axis 3).
/// @param[in] candidate_faces  paper mode: faces of `surface` with at least one vertex in I
InsideTest inside_test(const ContactSurface& surface, const Vec3& point, DetectionMode mode,
                       const std::vector<Index>& candidate_faces, const AxisRayTolerances& tolerances);

/// inside_test() of `count` points against the same surface, results[i] for points[i], equal to
/// inside_test() field for field. In exact mode, for a closed surface, the x axes of up to
/// AabbTree::AXIS_PACKET consecutive points are tested in one tree walk
/// (AabbTree::faces_on_axis_lines), which pays when the points are close together (e.g. in the
/// order of AabbTree::vertices_in_box); the points x does not decide continue alone.
/// @param[in]  points   `count` points
/// @param[out] results  `count` results
void inside_tests(const ContactSurface& surface, const Vec3* points, Index count, DetectionMode mode,
                  const std::vector<Index>& candidate_faces, const AxisRayTolerances& tolerances,
                  InsideTest* results);

/// inside_tests() in exact mode for points that come close together (e.g. a block of
/// AabbTree::vertices_in_box), sharing the work between neighbours: a point joined to an earlier
/// one by a segment that meets no face of the surface takes that point's answer. Walking the
/// points in order, a point takes the answer of
///  - the centre of an earlier empty cube that holds it (AabbTree::empty_cube: a box that no face
///    box meets, so every point of it is joined to its centre without crossing the surface);
///  - else the previous point, when its own empty cube (walked for when it would reach the
///    previous point or one of the next ones) holds that point, or AabbTree::segment_clear shows
///    that the segment between them meets no face;
///  - else it is tested (inside_tests(), in packets).
/// For a closed surface the answers equal inside_test()'s: `inside` everywhere, and every field
/// for the tested points.
/// A point that took a neighbour's answer gets deciding_axis DECIDED_BY_NEIGHBOUR, on_surface
/// false (it lies off the surface), the neighbour's crossing_face and, as surface_distance_bound,
/// the neighbour's plus their distance (some point of the surface lies within it).
/// Another mode, or a surface that is not closed: inside_tests() as it is.
/// @param[in]  points   `count` points
/// @param[out] results  `count` results
/// @return the number of points that took a neighbour's answer
Index inside_tests_shared(const ContactSurface& surface, const Vec3* points, Index count, DetectionMode mode,
                          const std::vector<Index>& candidate_faces, const AxisRayTolerances& tolerances,
                          InsideTest* results);

} // namespace coro
