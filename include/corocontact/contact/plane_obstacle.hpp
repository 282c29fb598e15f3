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

/// Every surface vertex below a plane: depth = −(x − point)·normal, normal = the plane's,
/// face = −1, other = ContactTarget::plane(k). Sorted by contact_order().
/// @param[in] surfaces  contact surfaces; only the first `num_bodies` are tested
std::vector<ContactPoint> detect_plane_contacts(const std::vector<ContactSurface>& surfaces, Index num_bodies,
                                                const std::vector<PlaneObstacle>& planes);

} // namespace coro
