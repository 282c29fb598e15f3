#pragma once
/// @file plane_obstacle.hpp
/// @brief Rigid, static half-space obstacles: a point and an outward normal.

#include <corocontact/contact/contact_surface.hpp>
#include <corocontact/contact/detector.hpp>

#include <vector>

namespace coro {

/// The half-space below a plane; the body side is where (x − point)·normal > 0.
struct PlaneObstacle {
    Vec3 point = Vec3::Zero();
    Vec3 normal = Vec3::UnitY(); ///< unit
};

/// Encodes plane obstacle k as a ContactPoint::other value (negative, so it never collides
/// with a surface index).
inline Index plane_other(Index k) { return -1 - k; }
/// The plane index of a ContactPoint::other value that plane_other() made, or −1.
inline Index plane_of_other(Index other) { return other < 0 ? -1 - other : -1; }

/// Every surface vertex below a plane: depth = −(x − point)·normal, normal = the plane's,
/// face = −1, other = plane_other(k). Sorted by (body, vertex, other).
/// @param[in] surfaces  contact surfaces; only the first `num_bodies` are tested
std::vector<ContactPoint> detect_plane_contacts(const std::vector<ContactSurface>& surfaces, Index num_bodies,
                                                const std::vector<PlaneObstacle>& planes);

} // namespace coro
