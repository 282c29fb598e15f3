// Embree as a detection backend and as a cross-check of the axis-ray test: the public
// EmbreeScenes over detail::EmbreeSceneSet, the detection loop and the comparison of results.
// No rtc* call here: they all live in detail/embree_scene_set.cpp.
#include <corocontact/embree/embree_detector.hpp>

#include "detail/embree_scene_set.hpp"

#include <corocontact/contact/aabb.hpp>
#include <corocontact/contact/broad_phase.hpp>
#include <corocontact/core/error.hpp>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <tuple>
#include <utility>

namespace coro {

namespace {

/// Outward unit normal of face `f` of `surface` (counter-clockwise winding), zero if degenerate.
Vec3 face_normal(const ContactSurface& surface, Index f)
{
    const Vec3 x0 = surface.vertices.row(surface.faces(f, 0)).transpose();
    const Vec3 x1 = surface.vertices.row(surface.faces(f, 1)).transpose();
    const Vec3 x2 = surface.vertices.row(surface.faces(f, 2)).transpose();
    const Vec3 n = (x1 - x0).cross(x2 - x0);
    const double length = n.norm();
    return length > 0.0 ? Vec3(n / length) : Vec3::Zero();
}

/// What one thread found.
struct LocalResult {
    std::vector<ContactPoint> points;
    Index candidates = 0;
    Index inside = 0;
    Index fallbacks = 0;
    detail::EmbreeQueryCounts counts;
};

/// Broad phase (body boxes, Eq. 2/3, sort-and-sweep), mid phase (candidate vertices of A =
/// vertices of A inside I = box(A) ∩ box(B), both directions of each pair) and the narrow
/// phase through `inside(other, point, counts)`; depth and normal from the other surface's
/// AABB tree (nearest point), as in the axis-ray detector. Sorted by (body, vertex, other).
template <class InsideFn>
std::vector<ContactPoint> detect(const std::vector<ContactSurface>& surfaces, DetectionStats* stats,
                                 detail::EmbreeQueryCounts* counts, const InsideFn& inside)
{
    std::vector<Aabb> boxes;
    boxes.reserve(surfaces.size());
    for (const ContactSurface& surface : surfaces)
        boxes.push_back(bounding_box(surface.vertices));
    const std::vector<std::pair<Index, Index>> pairs = overlapping_pairs(boxes);

    // Directed pairs (body, other): the vertices of `body` tested against `other`.
    std::vector<std::pair<Index, Index>> directed;
    directed.reserve(2 * pairs.size());
    for (const auto& [a, b] : pairs) {
        directed.emplace_back(a, b);
        directed.emplace_back(b, a);
    }

    constexpr Index VERTEX_GRAIN = 256;
    tbb::enumerable_thread_specific<LocalResult> local;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, directed.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const auto [body, other] = directed[k];
            const ContactSurface& a = surfaces[static_cast<std::size_t>(body)];
            const ContactSurface& b = surfaces[static_cast<std::size_t>(other)];
            const Aabb box = boxes[static_cast<std::size_t>(body)].intersection(boxes[static_cast<std::size_t>(other)]);
            tbb::parallel_for(
                tbb::blocked_range<Index>(0, static_cast<Index>(a.vertices.rows()), VERTEX_GRAIN),
                [&](const tbb::blocked_range<Index>& vr) {
                    LocalResult& mine = local.local();
                    for (Index v = vr.begin(); v < vr.end(); ++v) {
                        const Vec3 p = a.vertices.row(v).transpose();
                        if (!box.contains(p))
                            continue;
                        ++mine.candidates;
                        const InsideTest test = inside(other, p, &mine.counts);
                        if (test.deciding_axis == 3)
                            ++mine.fallbacks;
                        if (!test.inside)
                            continue;
                        ++mine.inside;
                        const AabbTree::Nearest nearest = b.tree.nearest(b.vertices, p);
                        ContactPoint c;
                        c.body = body;
                        c.vertex = v;
                        c.other = other;
                        c.depth = nearest.distance;
                        c.face = nearest.face;
                        c.barycentric = nearest.barycentric;
                        c.normal = nearest.face >= 0 ? face_normal(b, nearest.face) : Vec3::Zero();
                        mine.points.push_back(c);
                    }
                });
        }
    });

    std::vector<ContactPoint> points;
    DetectionStats totals;
    totals.pairs = static_cast<Index>(pairs.size());
    detail::EmbreeQueryCounts query_totals;
    std::size_t n = 0;
    for (const LocalResult& l : local)
        n += l.points.size();
    points.reserve(n);
    for (const LocalResult& l : local) {
        points.insert(points.end(), l.points.begin(), l.points.end());
        totals.candidate_vertices += l.candidates;
        totals.inside += l.inside;
        totals.winding_fallbacks += l.fallbacks;
        query_totals.axis_tests += l.counts.axis_tests;
        query_totals.rays += l.counts.rays;
        query_totals.hits += l.counts.hits;
    }
    std::sort(points.begin(), points.end(), [](const ContactPoint& x, const ContactPoint& y) {
        return std::tie(x.body, x.vertex, x.other) < std::tie(y.body, y.vertex, y.other);
    });
    if (stats != nullptr)
        *stats = totals;
    if (counts != nullptr)
        *counts = query_totals;
    return points;
}

} // namespace

namespace detail {

std::vector<ContactPoint> detect_contacts_embree(const std::vector<ContactSurface>& surfaces,
                                                 const EmbreeSceneSet& scenes, const DetectionSettings& /*settings*/,
                                                 DetectionStats* stats, EmbreeQueryCounts* counts)
{
    CORO_CHECK(static_cast<Index>(surfaces.size()) == scenes.size(), InputError,
               "Embree detection: " << surfaces.size() << " surfaces, but " << scenes.size() << " Embree scenes");
    return detect(surfaces, stats, counts, [&](Index other, const Vec3& p, EmbreeQueryCounts* c) {
        return scenes.inside_test(surfaces[static_cast<std::size_t>(other)], other, p, c);
    });
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
    (void)settings; // Embree always searches the whole surface (as exact mode does)
    return detect(surfaces, stats, nullptr, [&](Index other, const Vec3& p, detail::EmbreeQueryCounts*) {
        return detail::inside_from_axes(surfaces[static_cast<std::size_t>(other)], p,
                                        [&](int axis) { return scenes.axis_test(other, p, axis); });
    });
}

std::vector<Disagreement> cross_check(const std::vector<ContactPoint>& axis_ray,
                                      const std::vector<ContactPoint>& embree)
{
    using Key = std::tuple<Index, Index, Index>;
    const auto keys = [](const std::vector<ContactPoint>& points) {
        std::vector<Key> k;
        k.reserve(points.size());
        for (const ContactPoint& c : points)
            k.emplace_back(c.body, c.vertex, c.other);
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

} // namespace coro
