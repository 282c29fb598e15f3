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

/// The working memory of detect_plane_contacts(), kept from call to call: each body's points
/// (its vectors never shrink).
struct PlaneContactScratch {
    std::vector<std::vector<ContactPoint>> per_body;
};

/// Every surface vertex below a plane: depth = −(x − point)·normal, normal = the plane's,
/// face = −1, other = ContactTarget::plane(k). Sorted by contact_order(). A surface whose
/// vertices' box lies wholly above a plane is not tested against it vertex by vertex.
/// @param[in] surfaces  contact surfaces; every vertex row of the first `num_bodies` is tested
/// @param[out] points   the contact points; its old content is replaced, its capacity kept (a
///                      time loop passing the same vector and scratch allocates nothing once
///                      they have grown to the scene's contacts)
/// @param[in,out] scratch  working memory
void detect_plane_contacts(const std::vector<ContactSurface>& surfaces, Index num_bodies,
                           const std::vector<PlaneObstacle>& planes, std::vector<ContactPoint>& points,
                           PlaneContactScratch& scratch);

/// The same, returned (for a single detection).
std::vector<ContactPoint> detect_plane_contacts(const std::vector<ContactSurface>& surfaces, Index num_bodies,
                                                const std::vector<PlaneObstacle>& planes);

} // namespace coro
