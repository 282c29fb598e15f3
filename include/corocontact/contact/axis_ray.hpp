#pragma once
/// @file axis_ray.hpp
/// @brief The axis-oriented ray-projection inside test of one vertex against one surface
/// (paper §3, Eq. 4–6; DESIGN.md, Contact detection).

#include <corocontact/contact/contact_surface.hpp>

#include <vector>

namespace coro {

enum class DetectionMode {
    EXACT, ///< closest crossing over the whole surface through the tree; degenerate axes skipped;
           ///< undecided vertices fall back to the winding number
    PAPER, ///< closest crossing among the candidate faces only (faces with a vertex inside I)
};

/// How one axis query ended.
enum class AxisOutcome { INSIDE, OUTSIDE, NO_HIT, DEGENERATE };

/// Tolerances of the narrow phase.
struct AxisRayTolerances {
    double area_relative = 1e-9;   ///< Eq. 5/6: |A1+A2+A3 − Af| ≤ this · Af
    double edge_relative = 1e-9;   ///< exact mode: a barycentric weight below this ⇒ on an edge ⇒ degenerate
    double parallel_relative = 1e-12; ///< projected area below this · face area² ⇒ parallel ⇒ degenerate
};

/// One axis of the test: project `point` and `candidate_faces` onto the plane orthogonal to
/// `axis`, prefilter by bounding rectangles (Eq. 4), area test (Eq. 5/6), then the closest
/// crossing along the axis line decides by the sign of d·n.
/// @param[in] candidate_faces  faces to consider (paper mode); ignored in exact mode, where the
///                             surface's tree gives every face crossing the line
AxisOutcome axis_test(const ContactSurface& surface, const Vec3& point, int axis, DetectionMode mode,
                      const std::vector<Index>& candidate_faces, const AxisRayTolerances& tolerances);

/// Result of the full test of one vertex (axes x, then y, then z; then winding number in
/// exact mode).
struct InsideTest {
    bool inside = false;
    int deciding_axis = -1;        ///< 0..2, or 3 for the winding-number fallback, −1: no axis hit
};

/// @param[in] candidate_faces  paper mode: faces of `surface` with at least one vertex in I
InsideTest inside_test(const ContactSurface& surface, const Vec3& point, DetectionMode mode,
                       const std::vector<Index>& candidate_faces, const AxisRayTolerances& tolerances);

} // namespace coro
