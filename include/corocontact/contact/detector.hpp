#pragma once
/// @file detector.hpp
/// @brief Contact detection over all bodies: broad phase, mid phase, narrow phase, and the
/// depth and normal of every vertex found inside another body. See docs/contact.md.

#include <corocontact/contact/axis_ray.hpp>
#include <corocontact/contact/contact_surface.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <tuple>
#include <utility>
#include <vector>

namespace coro {

namespace detail {
class DetectionState;
struct ScratchAccess;
} // namespace detail

/// What a surface vertex was found inside: another contact surface, or a plane obstacle
/// (detect_plane_contacts). Ordered surfaces first, then planes, each by index.
struct ContactTarget {
    enum class Kind : std::int32_t { SURFACE, PLANE };
    Kind kind = Kind::SURFACE;
    Index index = -1; ///< the surface (index into the detector's surfaces) or the plane obstacle

    static ContactTarget surface(Index s) { return {Kind::SURFACE, s}; }
    static ContactTarget plane(Index p) { return {Kind::PLANE, p}; }
    bool is_surface() const { return kind == Kind::SURFACE; }
    friend bool operator==(const ContactTarget& a, const ContactTarget& b)
    {
        return a.kind == b.kind && a.index == b.index;
    }
    friend bool operator!=(const ContactTarget& a, const ContactTarget& b) { return !(a == b); }
    friend bool operator<(const ContactTarget& a, const ContactTarget& b)
    {
        return std::tie(a.kind, a.index) < std::tie(b.kind, b.index);
    }
};

/// A surface vertex of one body found inside another body (or below a plane obstacle).
struct ContactPoint {
    Index body = -1;      ///< the surface the vertex belongs to
    Index vertex = -1;    ///< its vertex index in that surface
    ContactTarget other;  ///< what it is inside
    Index face = -1;      ///< the other surface's face holding the nearest point (−1 for a plane,
                          ///< or without contact data)
    double depth = 0.0;   ///< distance to the nearest point of the other surface [m], ≥ 0
    Vec3 normal = Vec3::Zero();      ///< outward unit normal of the other surface there
    Vec3 barycentric = Vec3::Zero(); ///< the nearest point's weights on `face`'s vertices
};

/// The order of detect_contacts()' output: by body, vertex, then what it is inside.
inline bool contact_order(const ContactPoint& a, const ContactPoint& b)
{
    return std::tie(a.body, a.vertex, a.other) < std::tie(b.body, b.vertex, b.other);
}

/// What a detection pass counted.
struct DetectionStats {
    Index pairs = 0;              ///< overlapping body pairs (broad phase)
    Index candidate_vertices = 0; ///< vertices asked about (both directions)
    Index inside = 0;
    Index undecided_by_axes = 0;  ///< exact mode: vertices no axis decided (DecidedBy::EXACT_PARITY,
                                  ///< or WINDING_NUMBER for an open surface)
    Index on_surface = 0;         ///< exact mode: vertices lying on the other surface (not inside)
    Index by_neighbour = 0;       ///< exact mode: vertices that took the answer of the first vertex
                                  ///< of their clear-edge group (DetectionSettings::share_answers)
    Index by_hull = 0;            ///< exact mode, shared answers: vertices of pairs too small to
                                  ///< group that lie outside the other surface's hull slabs (a
                                  ///< 26-sided polytope around it), outside without a test
};

struct DetectionSettings {
    DetectionMode mode = DetectionMode::EXACT;
    AxisRayTolerances tolerances;
    /// Compute depth, normal, face and barycentric weights of every inside vertex (a
    /// nearest-point search each). When false those fields keep their defaults (depth 0, face
    /// −1): enough for inside/outside counts and cross-checks.
    bool contact_data = true;
    /// Exact mode: the candidates of a pair are grouped by edges of their surface that meet no
    /// face of the other surface; the first vertex of each group is tested and the others take
    /// its answer, the same as their own tests would give. Where the other surface is not
    /// closed, or a pair has fewer than 64 candidates (where testing each costs less than
    /// finding the groups), every candidate is tested. False: every candidate is tested (for
    /// measurements and cross-checks).
    bool share_answers = true;
};

/// The working memory of detect_contacts(), kept from call to call so that a time loop does not
/// allocate it every step: the broad and mid phase's lists, the face planes of the depth
/// searches (recomputed every call, for the nodes a search reaches), the grouping's arrays, the
/// pass's buffers. Its buffers never shrink. Holds nothing a result depends on: any scratch
/// gives the same answers. One call at a time may use it.
class DetectionScratch {
public:
    DetectionScratch();
    ~DetectionScratch();
    DetectionScratch(DetectionScratch&&) noexcept;
    DetectionScratch& operator=(DetectionScratch&&) noexcept;

    /// The broad phase of the last detection with this scratch: the pairs (a, b), a < b, of
    /// surfaces whose boxes overlapped, sorted; empty before the first.
    const std::vector<std::pair<Index, Index>>& overlapping_surfaces() const;

private:
    friend struct detail::ScratchAccess;
    std::unique_ptr<detail::DetectionState> m_state;
};

/// Detects every surface vertex of every body that lies inside another body, for all
/// overlapping pairs in both directions. Pairs and the vertices of large pairs run as TBB
/// tasks; the result is sorted by contact_order(), so it does not depend on scheduling.
/// Vertices lying exactly on the other surface (touching bodies) are not inside (exact mode).
/// @param[in] surfaces  one per body, trees refit to the current positions
/// @param[in,out] scratch  working memory (see DetectionScratch)
/// @param[out] points  the contact points; its old content is replaced, its capacity kept, so
///                     that a time loop passing the same vector and scratch allocates nothing
///                     once they have grown to the scene's contacts
void detect_contacts(const std::vector<ContactSurface>& surfaces, const DetectionSettings& settings,
                     DetectionScratch& scratch, std::vector<ContactPoint>& points, DetectionStats* stats = nullptr);

/// The same, returned.
std::vector<ContactPoint> detect_contacts(const std::vector<ContactSurface>& surfaces,
                                          const DetectionSettings& settings, DetectionScratch& scratch,
                                          DetectionStats* stats = nullptr);

/// detect_contacts() of the given surface pairs only, both directions of each: the caller ran
/// the broad phase (one process of a distributed run detects the pairs it owns). The contacts
/// of a pair do not depend on the other pairs or surfaces.
/// @param[in] pairs  (a, b) with a < b, sorted ascending, no repeats
std::vector<ContactPoint> detect_contacts(const std::vector<ContactSurface>& surfaces,
                                          const std::vector<std::pair<Index, Index>>& pairs,
                                          const DetectionSettings& settings, DetectionScratch& scratch,
                                          DetectionStats* stats = nullptr);

/// The same with a scratch of its own (for a single detection).
std::vector<ContactPoint> detect_contacts(const std::vector<ContactSurface>& surfaces,
                                          const DetectionSettings& settings, DetectionStats* stats = nullptr);

/// A narrow phase supplied by the caller, e.g. the Embree backend.
struct CustomNarrowPhase {
    /// inside(other, point): whether `point` is inside surface `other` (as inside_test() in exact
    /// mode answers it). Called concurrently from several threads.
    std::function<InsideTest(Index other, const Vec3& point)> inside;
    /// nearest(other, point, distance_bound): the nearest point of surface `other` to `point`,
    /// AabbTree::nearest's answer bit for bit; `distance_bound` is the inside test's
    /// surface_distance_bound. Empty: the trees' searches. Called concurrently.
    std::function<NearestPoint(Index other, const Vec3& point, double distance_bound)> nearest;
};

/// detect_contacts() (broad phase, mid phase, parallel vertex loop, depth and normal, sorted
/// output, stats) with the inside tests, and optionally the depth searches, of `narrow`.
std::vector<ContactPoint> detect_contacts(const std::vector<ContactSurface>& surfaces,
                                          const CustomNarrowPhase& narrow, bool contact_data,
                                          DetectionStats* stats = nullptr);

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

} // namespace coro
