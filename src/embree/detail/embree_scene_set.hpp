#pragma once
/// @file embree_scene_set.hpp
/// @brief Private to coro_embree (and its benchmark): the Embree scenes behind EmbreeScenes,
/// with the build setting selectable so that the benchmark can time Embree's rebuild against
/// its refit. Plain C++: no Embree type appears here; every rtc* call is in src/embree/*.cpp.

#include <corocontact/contact/axis_ray.hpp>
#include <corocontact/contact/contact_surface.hpp>
#include <corocontact/contact/detector.hpp>
#include <corocontact/contact/winding_number.hpp>

#include <cstdint>
#include <memory>
#include <vector>

namespace coro::detail {

/// How a scene's acceleration structure follows moving vertices.
enum class EmbreeBuild {
    REFIT,          ///< scene quality LOW + RTC_SCENE_FLAG_DYNAMIC, geometry quality REFIT:
                    ///< the BVH topology is kept and only its boxes are refit (the default)
    LOW_REBUILD,    ///< scene quality LOW + DYNAMIC, geometry quality LOW: Morton rebuild
    MEDIUM_REBUILD, ///< scene quality MEDIUM, no DYNAMIC flag: full SAH rebuild every commit
};

/// What the Embree queries did (for the benchmark's rays/s).
struct EmbreeQueryCounts {
    std::int64_t axis_tests = 0; ///< axis queries (each casts one ray along its whole axis line)
    std::int64_t rays = 0;       ///< rtcIntersect1 calls
    std::int64_t hits = 0;       ///< hits recorded by the intersection filter
};

/// The inside decision from axis outcomes, as the axis-ray test's exact mode takes it
/// (coro::inside_test): axes x, y, z in order; INSIDE or OUTSIDE decide; ON_SURFACE decides
/// "not inside" with `on_surface` set; NO_HIT decides outside (a line through an inside point
/// of a closed surface always meets it); DEGENERATE tries the next axis; three degenerate axes
/// fall back to the generalized winding number (w > 0.5, DecidedBy::WINDING_NUMBER). A surface that is
/// not closed is tested by the winding number alone.
/// @param[in] axis_test  callable `AxisOutcome(int axis)`
template <class AxisTest>
InsideTest inside_from_axes(const ContactSurface& surface, const Vec3& point, const AxisTest& axis_test)
{
    InsideTest result;
    for (int axis = 0; axis < 3 && surface.closed; ++axis) {
        const AxisOutcome outcome = axis_test(axis);
        switch (outcome) {
        case AxisOutcome::INSIDE:
        case AxisOutcome::OUTSIDE:
        case AxisOutcome::NO_HIT:
        case AxisOutcome::ON_SURFACE:
            result.inside = outcome == AxisOutcome::INSIDE;
            result.on_surface = outcome == AxisOutcome::ON_SURFACE;
            result.decided_by = decided_by_axis(axis);
            return result;
        case AxisOutcome::DEGENERATE:
            break;
        }
    }
    result.inside = winding_number(surface.vertices, surface.faces, point) > 0.5;
    result.decided_by = DecidedBy::WINDING_NUMBER;
    return result;
}

/// The first hit of a plain (unfiltered) Embree ray, as Embree reports it.
struct EmbreeFirstHit {
    Index face = -1;          ///< primitive hit, −1: none
    double t = 0.0;           ///< distance along the ray
    Vec3 ng = Vec3::Zero();   ///< Embree's unnormalised geometric normal, unchanged
};

/// +1 if Embree's geometric normal Ng points along our faces' counter-clockwise winding
/// normal (x1 − x0) × (x2 − x0), −1 if against it (checked by a unit-cube test).
double embree_ng_along_winding();

/// One Embree device and one scene per surface (one triangle geometry each). All scenes use
/// RTC_SCENE_FLAG_ROBUST (watertight traversal) and the context filter function flag, so
/// that a query can gather every hit along a ray.
///
/// Precision: Embree works in float. Vertices are stored relative to a per-surface origin
/// (the centre of the surface's box at the last upload) to keep their float error small. A
/// closest hit within a float band (64 ulps of the scene's coordinate magnitude) of the query
/// point is ON_SURFACE; one within the band of an edge, of another hit, or on a face parallel
/// to the axis is DEGENERATE, and a point undecided on all three axes falls back to the
/// double-precision winding number. So a vertex within about 1e-5 (relative) of the other
/// surface is reported as on the surface (not inside) where the double-precision axis-ray test
/// may still decide it: such vertices can disagree legitimately; all others agree.
class EmbreeSceneSet {
public:
    /// @throws NumericalError with Embree's error text if the device or a scene fails, or
    ///         for non-finite vertex coordinates
    EmbreeSceneSet(const std::vector<ContactSurface>& surfaces, EmbreeBuild build);
    ~EmbreeSceneSet();
    EmbreeSceneSet(const EmbreeSceneSet&) = delete;
    EmbreeSceneSet& operator=(const EmbreeSceneSet&) = delete;

    /// Number of scenes (= surfaces at construction).
    Index size() const;

    /// Uploads the current vertex positions of every surface and recommits its scene, the
    /// scenes as parallel tasks. After it throws, some scenes may hold the new positions
    /// uncommitted: build the set again before using it.
    /// @throws InputError if the surfaces' count or sizes changed, NumericalError for an
    ///         Embree error or non-finite coordinates (the first failing surface's)
    void update(const std::vector<ContactSurface>& surfaces);

    /// See EmbreeScenes::axis_test. `counts` (optional) is incremented.
    AxisOutcome axis_test(Index s, const Vec3& point, int axis, EmbreeQueryCounts* counts = nullptr) const;

    /// axis_test that also gives, when the axis has a hit, a distance within which the surface
    /// lies from `point` (the closest hit's distance plus its float noise band).
    AxisOutcome axis_test(Index s, const Vec3& point, int axis, EmbreeQueryCounts* counts,
                          double* distance_bound) const;

    /// See EmbreeScenes::inside_test; `surface` must be the one scene `s` was built from. An
    /// inside vertex decided by an axis carries that axis's closest hit distance (plus its float
    /// noise band) as surface_distance_bound, for the depth search.
    InsideTest inside_test(const ContactSurface& surface, Index s, const Vec3& point,
                           EmbreeQueryCounts* counts = nullptr) const;

    /// The nearest point of surface `s` to `point` by an Embree point query (rtcPointQuery). The
    /// callback measures each face Embree hands it in double precision with the tree's formula
    /// (closest_point_on_triangle) and keeps the smallest (squared distance, face index); the
    /// query radius is the best distance so far widened by a float band, so that Embree's float
    /// boxes drop no face that ties. So the answer is AabbTree::nearest's, face and distance bit
    /// for bit, found by Embree's traversal instead of ours. `surface` must be the one scene
    /// `s` was built from, and the scene updated to its current vertices (Embree's boxes decide
    /// which faces are measured: stale ones give a wrong face without notice).
    /// @param[in] distance_bound  a distance within which the surface lies from `point` (+∞: none)
    NearestPoint nearest(const ContactSurface& surface, Index s, const Vec3& point, double distance_bound) const;

    /// One plain first-hit ray (no filter) from `point` along +axis: the benchmark's first-hit
    /// ray rate and the test of Embree's normal convention.
    EmbreeFirstHit first_hit(Index s, const Vec3& point, int axis) const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

/// detect_contacts_embree on a scene set; `counts` (optional) receives the Embree query counts.
std::vector<ContactPoint> detect_contacts_embree(const std::vector<ContactSurface>& surfaces,
                                                 const EmbreeSceneSet& scenes,
                                                 const DetectionSettings& settings, DetectionStats* stats,
                                                 EmbreeQueryCounts* counts);

} // namespace coro::detail
