#pragma once
/// @file scene_contact.hpp
/// @brief Contact detection on a scene: one contact surface per body, kept in step with the
/// bodies, and the per-node view of the result that frames show.

#include <corocontact/contact/contact_surface.hpp>
#include <corocontact/contact/detector.hpp>
#include <corocontact/sim/case_spec.hpp>

#include <utility>
#include <vector>

namespace coro {

class Body;

/// The boundary surface of a body as contact detection sees it; source_id holds the input
/// (mesh file) node index of every surface vertex.
ContactSurface make_contact_surface(const Body& body);

/// Contact surfaces of all bodies, one per body in body order.
std::vector<ContactSurface> make_contact_surfaces(const std::vector<Body>& bodies);

struct Scene;

/// The bodies' contact surfaces (body order), then one static surface per mesh obstacle,
/// named obstacle<k> in obstacle-mesh order.
std::vector<ContactSurface> make_scene_surfaces(const Scene& scene);

/// Moves every body's surface (the first #bodies) to its body's current positions and refits
/// its tree; obstacle surfaces stay where they are.
void update_contact_surfaces(const std::vector<Body>& bodies, std::vector<ContactSurface>& surfaces);

/// The components of the scene system (SceneMatrix::set_components): bodies joined, directly or
/// through others, by overlapping boxes (the broad phase of detection, so every contact lies
/// within a component), numbered in the order of their first body.
/// @param[in] surfaces    the bodies' contact surfaces first (their trees refit), then obstacles
/// @param[in] num_bodies  how many of the surfaces are bodies
/// @param[out] component_of_body  #num_bodies
void contact_components(const std::vector<ContactSurface>& surfaces, Index num_bodies,
                        std::vector<Index>& component_of_body);
/// The same from the bodies' boxes (a distributed scene: the boxes gathered from every process).
/// @param[in] body_boxes  #bodies
/// @param[out] component_of_body  #bodies
void contact_components(const std::vector<Aabb>& body_boxes, std::vector<Index>& component_of_body);
/// The same from the broad phase a detection has done already
/// (DetectionScratch::overlapping_surfaces()): a time step reuses its pairs instead of sweeping
/// the boxes again, and allocates nothing once `component_of_body` has its size.
/// @param[in] overlapping  pairs (a, b), a < b, of surfaces whose boxes overlap; a pair with an
///                         obstacle (b ≥ num_bodies) joins nothing
/// @param[out] component_of_body  #num_bodies
void contact_components(const std::vector<std::pair<Index, Index>>& overlapping, Index num_bodies,
                        std::vector<Index>& component_of_body);

/// Detection settings from the case's [contact] table.
DetectionSettings detection_settings(const ContactSettings& contact);

/// Per-node contact state of one body in internal node order: inside (0/1) and depth [m]
/// (the deepest over the other bodies), #V each.
struct NodeContact {
    std::vector<char> inside;
    VecX depth;
};

/// Spreads detected contact points onto the nodes of every body (points of obstacle surfaces
/// are skipped).
/// @param[in] surfaces  one per body, as used for detection
/// @param[in] points    detect_contacts() output
/// @param[in] num_vertices  #V of every body
std::vector<NodeContact> node_contacts(const std::vector<ContactSurface>& surfaces,
                                       const std::vector<ContactPoint>& points,
                                       const std::vector<Index>& num_vertices);

/// The `detect` CSV: header `body,vertex,other,depth`, one row per surface vertex found inside
/// another body; `vertex` is the input node index; rows sorted by body order, then vertex,
/// then other. Depths are written with 17 significant digits.
std::string contacts_csv(const std::vector<ContactSurface>& surfaces, const std::vector<ContactPoint>& points);

} // namespace coro
