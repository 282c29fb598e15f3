#pragma once
/// @file detector.hpp
/// @brief Contact detection over all bodies: broad phase, mid phase, narrow phase.

#include <corocontact/contact/axis_ray.hpp>
#include <corocontact/contact/contact_surface.hpp>

#include <vector>

namespace coro {

/// A surface vertex of one body found inside another body.
struct ContactPoint {
    Index body = -1;        ///< index of the body the vertex belongs to
    Index vertex = -1;      ///< surface vertex index in that body's ContactSurface
    Index other = -1;       ///< the body it is inside
    double depth = 0.0;     ///< distance to the nearest point of the other surface [m], ≥ 0
    Vec3 normal = Vec3::Zero(); ///< outward unit normal of the other surface at that point
    Index face = -1;        ///< the other surface's face holding the nearest point
    Vec3 barycentric = Vec3::Zero(); ///< nearest point's weights on that face
};

/// What a detection pass counted.
struct DetectionStats {
    Index pairs = 0;             ///< overlapping body pairs (broad phase)
    Index candidate_vertices = 0; ///< vertex queries done (both directions)
    Index inside = 0;
    Index winding_fallbacks = 0; ///< exact mode: vertices undecided on all three axes
};

struct DetectionSettings {
    DetectionMode mode = DetectionMode::EXACT;
    AxisRayTolerances tolerances;
};

/// Detects every surface vertex of every body that lies inside another body, for all
/// overlapping pairs in both directions. Pairs and the vertices of large pairs run as TBB
/// tasks; the result is sorted by (body, vertex, other), so it does not depend on scheduling.
/// @param[in] surfaces  one per body, trees refit to the current positions
std::vector<ContactPoint> detect_contacts(const std::vector<ContactSurface>& surfaces,
                                          const DetectionSettings& settings, DetectionStats* stats = nullptr);

} // namespace coro
