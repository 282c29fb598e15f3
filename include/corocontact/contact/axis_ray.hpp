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
    ON_SURFACE, ///< exact modes: the point lies on the surface (exactly on a face's plane and
                ///< in the closed face): reported as not inside
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
/// one of them has the point on it (exactly: where the point is within rounding of a face's
/// plane, its side is found in rational arithmetic); DEGENERATE if one is an edge or
/// parallel crossing, if their votes differ, or if only parallel faces are met; else their
/// common vote. For a closed, consistently oriented surface a decision is the exact answer.
/// @param[in] candidate_faces  faces to consider (paper mode); ignored in the exact modes, where
///                             the surface's tree (EXACT) or a scan (BRUTE_FORCE) gives every
///                             face crossing the line
AxisOutcome axis_test(const ContactSurface& surface, const Vec3& point, int axis, DetectionMode mode,
                      const std::vector<Index>& candidate_faces, const AxisRayTolerances& tolerances);

/// What decided an inside test.
enum class DecidedBy {
    NOTHING,        ///< paper mode: no axis line met a candidate face (the point is not inside)
    X_AXIS,         ///< the x axis: its closest crossing, or (exact modes) no crossing at all or
                    ///< the point on the surface
    Y_AXIS,         ///< the y axis, as X_AXIS
    Z_AXIS,         ///< the z axis, as X_AXIS
    WINDING_NUMBER, ///< the generalized winding number: a surface that is not closed
    EXACT_PARITY,   ///< exact modes, closed surface, three axes that did not decide: the exact
                    ///< parity of a segment's face crossings (or the point exactly on a face)
};

/// The axis (0, 1, 2) of DecidedBy::X_AXIS, Y_AXIS, Z_AXIS; −1 for the others.
constexpr int axis_of(DecidedBy by)
{
    return by == DecidedBy::X_AXIS ? 0 : by == DecidedBy::Y_AXIS ? 1 : by == DecidedBy::Z_AXIS ? 2 : -1;
}

/// DecidedBy of axis 0, 1 or 2.
constexpr DecidedBy decided_by_axis(int axis)
{
    return axis == 0 ? DecidedBy::X_AXIS : axis == 1 ? DecidedBy::Y_AXIS : DecidedBy::Z_AXIS;
}

/// Result of the full test of one vertex (axes x, then y, then z; then winding number in
/// exact mode).
struct InsideTest {
    bool inside = false;
    bool on_surface = false; ///< exact modes: the point lies on the surface (then not inside)
    DecidedBy decided_by = DecidedBy::NOTHING;
    /// Exact modes, decided by an axis: the distance along that axis to the closest clean face
    /// crossing plus its rounding bound, so some point of the surface lies within it (an upper
    /// bound on the depth, which starts the nearest-point search); +∞ otherwise.
    double surface_distance_bound = std::numeric_limits<double>::infinity();
    /// Exact modes, decided by an axis: the face of that closest clean crossing (−1 otherwise).
    Index crossing_face = -1;
};

/// Paper mode: axes x, y, z until one has a hit (INSIDE or OUTSIDE); no hit on all three ⇒
/// not inside (DecidedBy::NOTHING).
/// Exact modes: axes x, y, z; INSIDE, OUTSIDE or ON_SURFACE decide (a point on the surface is
/// reported as not inside, `on_surface` set); NO_HIT also decides outside (a line through an
/// inside point of a closed surface always meets it); DEGENERATE tries the next axis; three
/// degenerate axes fall back to the exact parity of the faces that a segment from the point to
/// outside the surface crosses (every orientation sign exact; DecidedBy::EXACT_PARITY).
/// A surface that is not closed is tested by the winding number alone.
/// @param[in] candidate_faces  paper mode: faces of `surface` with at least one vertex in I
InsideTest inside_test(const ContactSurface& surface, const Vec3& point, DetectionMode mode,
                       const std::vector<Index>& candidate_faces, const AxisRayTolerances& tolerances);

} // namespace coro
