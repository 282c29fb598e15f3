#pragma once
/// @file embree_detector.hpp
/// @brief Embree 3 as a second detection backend and as a cross-check of the axis-ray test.
/// Only src/embree/ includes Embree headers; this header is plain C++.

#include <corocontact/contact/contact_surface.hpp>
#include <corocontact/contact/detector.hpp>

#include <memory>
#include <vector>

namespace coro {

/// One Embree scene per surface over the same triangles (RTC_SCENE_FLAG_ROBUST |
/// RTC_SCENE_FLAG_DYNAMIC, RTC_BUILD_QUALITY_LOW so that updates refit), committed again
/// after every update.
class EmbreeScenes {
public:
    /// @throws NumericalError with Embree's error text if the device or a scene fails
    explicit EmbreeScenes(const std::vector<ContactSurface>& surfaces);
    ~EmbreeScenes();
    EmbreeScenes(const EmbreeScenes&) = delete;
    EmbreeScenes& operator=(const EmbreeScenes&) = delete;

    /// Uploads the surfaces' current vertex positions and recommits (refit), the scenes as
    /// parallel tasks. After it throws, build the scenes again before using them.
    /// @throws InputError if the surfaces' count or sizes changed, NumericalError for non-finite
    ///         coordinates or an Embree error (the first failing surface's)
    void update(const std::vector<ContactSurface>& surfaces);

    /// The axis-ray test of one point against surface `s` with Embree rays: all hits along the
    /// axis line gathered with an intersection filter, sorted by (t, prim); the closest decides
    /// by the sign of d·n. Returns INSIDE, OUTSIDE, NO_HIT, or DEGENERATE when the closest hits
    /// coincide (an edge or vertex is hit).
    AxisOutcome axis_test(Index s, const Vec3& point, int axis) const;

    /// The full inside test (axes x, y, z in order; winding number when undecided).
    InsideTest inside_test(Index s, const Vec3& point) const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
    const std::vector<ContactSurface>* m_surfaces = nullptr;

    friend std::vector<ContactPoint> detect_contacts_embree(const std::vector<ContactSurface>& surfaces,
                                                            const EmbreeScenes& scenes,
                                                            const DetectionSettings& settings, DetectionStats* stats);
};

/// Detection with Embree as the narrow-phase backend (same broad and mid phase, same output).
/// With settings.contact_data, depth and normal come from Embree point queries (rtcPointQuery)
/// that measure each face in double precision as AabbTree::nearest does, so they equal the
/// axis-ray detector's bit for bit; each query's starting radius is the deciding Embree hit's
/// distance, as the axis-ray test's search starts from its crossing.
std::vector<ContactPoint> detect_contacts_embree(const std::vector<ContactSurface>& surfaces,
                                                 const EmbreeScenes& scenes, const DetectionSettings& settings,
                                                 DetectionStats* stats = nullptr);

/// Vertices on which Embree and the axis-ray detector disagree about inside/outside. Points
/// whose other is a plane obstacle are left out of both lists: a run's contacts hold them too,
/// and Embree, which traces surfaces only, never finds them.
struct Disagreement {
    Index body = -1;
    Index vertex = -1;
    Index other = -1; ///< the surface
    bool axis_ray_inside = false;
    bool embree_inside = false;
};
std::vector<Disagreement> cross_check(const std::vector<ContactPoint>& axis_ray,
                                      const std::vector<ContactPoint>& embree);

/// Vertices both found inside whose nearest face or depth differ (Embree's point queries and
/// the tree's search must give the same, bit for bit). Both lists sorted by contact_order(), as
/// the detectors return them.
Index depth_disagreements(const std::vector<ContactPoint>& axis_ray, const std::vector<ContactPoint>& embree);

} // namespace coro
