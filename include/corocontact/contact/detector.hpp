#pragma once
/// @file detector.hpp
/// @brief Contact detection over all bodies: broad phase, mid phase, narrow phase.

#include <corocontact/contact/axis_ray.hpp>
#include <corocontact/contact/contact_surface.hpp>

#include <functional>
#include <utility>
#include <vector>

namespace coro {

/// A surface vertex of one body found inside another body.
/// The four indices come first: 72 bytes, no padding (a detection writes one per inside vertex).
struct ContactPoint {
    Index body = -1;        ///< index of the body the vertex belongs to
    Index vertex = -1;      ///< surface vertex index in that body's ContactSurface
    Index other = -1;       ///< the body it is inside
    Index face = -1;        ///< the other surface's face holding the nearest point
    double depth = 0.0;     ///< distance to the nearest point of the other surface [m], ≥ 0
    Vec3 normal = Vec3::Zero(); ///< outward unit normal of the other surface at that point
    Vec3 barycentric = Vec3::Zero(); ///< nearest point's weights on that face
};

/// What a detection pass counted.
struct DetectionStats {
    Index pairs = 0;             ///< overlapping body pairs (broad phase)
    Index candidate_vertices = 0; ///< vertex queries done (both directions)
    Index inside = 0;
    Index winding_fallbacks = 0; ///< exact mode: vertices undecided on all three axes
    Index on_surface = 0;        ///< exact mode: vertices lying on the other surface (not inside)
    Index by_neighbour = 0;      ///< exact mode: vertices that took the answer of another vertex
                                 ///< of their clear-edge group (DetectionSettings::share_answers),
                                 ///< no test of their own
};

struct DetectionSettings {
    DetectionMode mode = DetectionMode::EXACT;
    AxisRayTolerances tolerances;
    /// Compute depth, normal, face and barycentric weights of every inside vertex (a nearest-point
    /// query each). When false those fields keep their defaults (depth 0, face −1): enough for
    /// inside/outside counts and cross-checks.
    bool contact_data = true;
    /// Exact mode: candidate vertices share answers. The candidates of a pair are grouped by
    /// edges of their surface that meet no face of the other surface (AabbTree::
    /// clear_edge_groups over the face pairs of AabbTree::overlapping_slots); the first vertex
    /// of each group is tested and the others take its answer, the same as their own tests
    /// would give. Where the other surface is not closed, every candidate is tested.
    /// False: every candidate vertex is tested (for measurements and cross-checks).
    bool share_answers = true;
};

/// Detects every surface vertex of every body that lies inside another body, for all
/// overlapping pairs in both directions. Pairs and the vertices of large pairs run as TBB
/// tasks; the result is sorted by (body, vertex, other), so it does not depend on scheduling.
/// Vertices lying exactly on the other surface (touching bodies) are not inside (exact mode;
/// see inside_test).
/// With settings.contact_data it brings the face-plane cache of the surfaces that get depth
/// queries up to date (AabbTree::update_planes): two calls must not run concurrently on the
/// same surfaces.
/// @param[in] surfaces  one per body, trees refit to the current positions
std::vector<ContactPoint> detect_contacts(const std::vector<ContactSurface>& surfaces,
                                          const DetectionSettings& settings, DetectionStats* stats = nullptr);

/// detect_contacts() of the given surface pairs only, both directions of each: the caller ran
/// the broad phase (e.g. one process of a distributed run, which detects the pairs it owns).
/// The contacts of a pair do not depend on the other pairs or surfaces.
/// @param[in] pairs  (a, b) with a < b, sorted ascending, no repeats
std::vector<ContactPoint> detect_contacts(const std::vector<ContactSurface>& surfaces,
                                          const std::vector<std::pair<Index, Index>>& pairs,
                                          const DetectionSettings& settings, DetectionStats* stats = nullptr);

/// A nearest-point search supplied by the caller: nearest(other, point, distance_bound) must
/// give what surfaces[other].tree.nearest(surfaces[other].vertices, point, distance_bound, −1)
/// gives, face and distance bit for bit. `distance_bound` is the inside test's surface_distance_bound (+∞:
/// none). Called concurrently from several threads.
using NearestSearch = std::function<AabbTree::Nearest(Index other, const Vec3& point, double distance_bound)>;

/// The same pipeline (broad phase, mid phase, parallel vertex loop, depth and normal, sorted
/// output, stats) with the inside test supplied by the caller, e.g. the Embree backend.
/// @param[in] inside   inside(other, point): is `point` inside surface `other`; called
///                     concurrently from several threads
/// @param[in] nearest  the depth searches (with contact_data); empty: the surfaces' trees
std::vector<ContactPoint> detect_contacts(const std::vector<ContactSurface>& surfaces,
                                          const std::function<InsideTest(Index other, const Vec3& point)>& inside,
                                          DetectionStats* stats = nullptr, bool contact_data = true,
                                          const NearestSearch& nearest = {});

/// Mid phase of one ordered pair: the vertices of `body` to test against surface `other`.
struct PairCandidates {
    Index body = -1;
    Index other = -1;
    Aabb overlap;                ///< I = AABB(body) ∩ AABB(other)
    std::vector<Index> vertices; ///< surface vertices of `body` inside I (closed), in the tree's
                                 ///< spatial order
    std::vector<Index> faces;    ///< paper mode only: faces of `other` with at least one vertex in
                                 ///< I, ascending (the paper's candidate faces)
};

/// Broad phase (body boxes from the trees, sort-and-sweep) and mid phase of all overlapping
/// pairs, both directions, ordered by (body, other).
std::vector<PairCandidates> contact_candidates(const std::vector<ContactSurface>& surfaces, DetectionMode mode);

/// The contact data of vertex `vertex` of `body` found inside `other`: nearest point of the
/// other surface (AabbTree::nearest), its distance as depth, its face's outward unit normal.
ContactPoint make_contact_point(const std::vector<ContactSurface>& surfaces, Index body, Index vertex, Index other);

} // namespace coro
