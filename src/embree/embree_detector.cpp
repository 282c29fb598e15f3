// Embree as a detection backend and as a cross-check of the axis-ray test: the public
// EmbreeScenes over detail::EmbreeSceneSet, detection through the contact library's pipeline
// with Embree deciding inside/outside, and the comparison of two results. No rtc* call here:
// they all live in detail/embree_scene_set.cpp.
#include <corocontact/embree/embree_detector.hpp>

#include "detail/embree_scene_set.hpp"

#include <corocontact/core/error.hpp>

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cstddef>
#include <tuple>
#include <utility>

namespace coro {

namespace detail {

std::vector<ContactPoint> detect_contacts_embree(const std::vector<ContactSurface>& surfaces,
                                                 const EmbreeSceneSet& scenes, const DetectionSettings& settings,
                                                 DetectionStats* stats, EmbreeQueryCounts* counts)
{
    CORO_CHECK(static_cast<Index>(surfaces.size()) == scenes.size(), InputError,
               "Embree detection: " << surfaces.size() << " surfaces, but " << scenes.size() << " Embree scenes");
    // The depths by Embree's point queries too, so that the backend is Embree's throughout.
    tbb::enumerable_thread_specific<EmbreeQueryCounts> local;
    CustomNarrowPhase narrow;
    narrow.inside = [&](Index other, const Vec3& p) {
        return scenes.inside_test(surfaces[static_cast<std::size_t>(other)], other, p,
                                  counts != nullptr ? &local.local() : nullptr);
    };
    narrow.nearest = [&](Index other, const Vec3& p, double distance_bound) {
        return scenes.nearest(surfaces[static_cast<std::size_t>(other)], other, p, distance_bound);
    };
    std::vector<ContactPoint> points = detect_contacts(surfaces, narrow, settings.contact_data, stats);
    if (counts == nullptr)
        return points;
    *counts = EmbreeQueryCounts{};
    for (const EmbreeQueryCounts& c : local) {
        counts->axis_tests += c.axis_tests;
        counts->rays += c.rays;
        counts->hits += c.hits;
    }
    return points;
}

} // namespace detail

struct EmbreeScenes::Impl {
    explicit Impl(const std::vector<ContactSurface>& surfaces) : scenes(surfaces, detail::EmbreeBuild::REFIT) {}
    detail::EmbreeSceneSet scenes;
};

EmbreeScenes::EmbreeScenes(const std::vector<ContactSurface>& surfaces)
    : m_impl(std::make_unique<Impl>(surfaces)), m_surfaces(&surfaces)
{
}

EmbreeScenes::~EmbreeScenes() = default;

void EmbreeScenes::update(const std::vector<ContactSurface>& surfaces)
{
    m_impl->scenes.update(surfaces);
    m_surfaces = &surfaces;
}

AxisOutcome EmbreeScenes::axis_test(Index s, const Vec3& point, int axis) const
{
    CORO_CHECK(s >= 0 && s < m_impl->scenes.size(), InputError,
               "Embree axis test: surface " << s << " of " << m_impl->scenes.size());
    CORO_CHECK(axis >= 0 && axis < 3, InputError, "Embree axis test: axis " << axis << ", expected 0, 1 or 2");
    return m_impl->scenes.axis_test(s, point, axis);
}

InsideTest EmbreeScenes::inside_test(Index s, const Vec3& point) const
{
    CORO_CHECK(s >= 0 && s < m_impl->scenes.size(), InputError,
               "Embree inside test: surface " << s << " of " << m_impl->scenes.size());
    return m_impl->scenes.inside_test((*m_surfaces)[static_cast<std::size_t>(s)], s, point);
}

std::vector<ContactPoint> detect_contacts_embree(const std::vector<ContactSurface>& surfaces,
                                                 const EmbreeScenes& scenes, const DetectionSettings& settings,
                                                 DetectionStats* stats)
{
    // The contact library's pipeline (broad phase, mid phase, depth and normal, sorted output,
    // stats) with Embree's axis rays for the inside decision; Embree always searches the whole
    // surface, as exact mode does, so the settings' mode and tolerances do not apply (their
    // contact_data does).
    return detail::detect_contacts_embree(surfaces, scenes.m_impl->scenes, settings, stats, nullptr);
}

std::vector<Disagreement> cross_check(const std::vector<ContactPoint>& axis_ray,
                                      const std::vector<ContactPoint>& embree)
{
    using Key = std::tuple<Index, Index, Index>;
    const auto keys = [](const std::vector<ContactPoint>& points) {
        std::vector<Key> k;
        k.reserve(points.size());
        for (const ContactPoint& c : points)
            if (c.other.is_surface()) // Embree sees surfaces only, not plane obstacles
                k.emplace_back(c.body, c.vertex, c.other.index);
        std::sort(k.begin(), k.end());
        k.erase(std::unique(k.begin(), k.end()), k.end());
        return k;
    };
    const std::vector<Key> a = keys(axis_ray), e = keys(embree);
    std::vector<Disagreement> out;
    const auto add = [&](const Key& k, bool in_axis_ray) {
        Disagreement d;
        std::tie(d.body, d.vertex, d.other) = k;
        d.axis_ray_inside = in_axis_ray;
        d.embree_inside = !in_axis_ray;
        out.push_back(d);
    };
    std::size_t i = 0, j = 0;
    while (i < a.size() || j < e.size()) {
        if (j == e.size() || (i < a.size() && a[i] < e[j]))
            add(a[i++], true);
        else if (i == a.size() || e[j] < a[i])
            add(e[j++], false);
        else {
            ++i;
            ++j;
        }
    }
    return out;
}

Index depth_disagreements(const std::vector<ContactPoint>& axis_ray, const std::vector<ContactPoint>& embree)
{
    const auto key = [](const ContactPoint& c) { return std::tie(c.body, c.vertex, c.other); };
    Index count = 0;
    std::size_t i = 0, j = 0;
    while (i < axis_ray.size() && j < embree.size()) {
        if (key(axis_ray[i]) < key(embree[j]))
            ++i;
        else if (key(embree[j]) < key(axis_ray[i]))
            ++j;
        else {
            count += axis_ray[i].face != embree[j].face || axis_ray[i].depth != embree[j].depth ? 1 : 0;
            ++i;
            ++j;
        }
    }
    return count;
}

} // namespace coro
