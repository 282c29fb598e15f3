#include <corocontact/contact/plane_obstacle.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace coro {

namespace {

/// Planes after the first MASKED_PLANES are tested vertex by vertex for every body.
constexpr std::size_t MASKED_PLANES = 32;
/// A box lies above a plane when its lowest corner is higher than this times the magnitudes in
/// the height's computation: far beyond the rounding of any vertex's height (a few ulps).
constexpr double HEIGHT_ROUNDING = 1e-12;

/// Bit k (k < MASKED_PLANES) set unless every vertex lies above plane k by more than the
/// rounding of its height, so that no vertex whose computed height is negative is left out
/// where the bit is clear. A non-finite vertex sets every bit.
std::uint32_t planes_near(const Positions& vertices, const std::vector<PlaneObstacle>& planes)
{
    // Every vertex row, not the tree's box: an embedded surface may keep vertices no face uses.
    // One pass through the rows (Eigen's column-wise reductions walk them three times).
    if (vertices.rows() == 0)
        return 0;
    double low[3], high[3];
    const double* x = vertices.data();
    for (int i = 0; i < 3; ++i)
        low[i] = high[i] = x[i];
    bool finite = true;
    for (Index v = 0; v < vertices.rows(); ++v, x += 3)
        for (int i = 0; i < 3; ++i) {
            finite = finite && std::abs(x[i]) <= std::numeric_limits<double>::max();
            low[i] = std::min(low[i], x[i]);
            high[i] = std::max(high[i], x[i]);
        }
    if (!finite)
        return ~0U;
    std::uint32_t near = 0;
    for (std::size_t k = 0; k < std::min(planes.size(), MASKED_PLANES); ++k) {
        const PlaneObstacle& plane = planes[k];
        double lowest = 0.0, scale = 0.0;
        for (int i = 0; i < 3; ++i) {
            const double n = plane.normal[i];
            lowest += ((n >= 0.0 ? low[i] : high[i]) - plane.point[i]) * n;
            scale += (std::max(std::abs(low[i]), std::abs(high[i])) + std::abs(plane.point[i])) * std::abs(n);
        }
        // Not (lowest > margin), so that a NaN from the plane counts as near too.
        if (!(lowest > HEIGHT_ROUNDING * scale + std::numeric_limits<double>::min()))
            near |= 1U << k;
    }
    return near;
}

} // namespace

void detect_plane_contacts(const std::vector<ContactSurface>& surfaces, Index num_bodies,
                           const std::vector<PlaneObstacle>& planes, std::vector<ContactPoint>& points,
                           PlaneContactScratch& scratch)
{
    // One list per body, filled in parallel and joined in body order: by body, then vertex, then
    // plane, which is contact_order().
    std::vector<std::vector<ContactPoint>>& per_body = scratch.per_body;
    if (per_body.size() < static_cast<std::size_t>(num_bodies))
        per_body.resize(static_cast<std::size_t>(num_bodies));
    tbb::parallel_for(tbb::blocked_range<Index>(0, num_bodies, 1), [&](const tbb::blocked_range<Index>& range) {
        for (Index b = range.begin(); b != range.end(); ++b) {
            const ContactSurface& surface = surfaces[static_cast<std::size_t>(b)];
            std::vector<ContactPoint>& out = per_body[static_cast<std::size_t>(b)];
            out.clear();
            const std::uint32_t near = planes_near(surface.vertices, planes);
            if (near == 0 && planes.size() <= MASKED_PLANES)
                continue;
            for (Index v = 0; v < surface.vertices.rows(); ++v)
                for (std::size_t k = 0; k < planes.size(); ++k) {
                    if (k < MASKED_PLANES && !((near >> k) & 1U))
                        continue;
                    const double height =
                        (surface.vertices.row(v).transpose() - planes[k].point).dot(planes[k].normal);
                    if (height >= 0.0)
                        continue;
                    ContactPoint& point = out.emplace_back();
                    point.body = b;
                    point.vertex = v;
                    point.other = ContactTarget::plane(static_cast<Index>(k));
                    point.depth = -height;
                    point.normal = planes[k].normal;
                }
        }
    });
    points.clear();
    for (Index b = 0; b < num_bodies; ++b) {
        const std::vector<ContactPoint>& list = per_body[static_cast<std::size_t>(b)];
        points.insert(points.end(), list.begin(), list.end());
    }
}

std::vector<ContactPoint> detect_plane_contacts(const std::vector<ContactSurface>& surfaces, Index num_bodies,
                                                const std::vector<PlaneObstacle>& planes)
{
    std::vector<ContactPoint> points;
    PlaneContactScratch scratch;
    detect_plane_contacts(surfaces, num_bodies, planes, points, scratch);
    return points;
}

} // namespace coro
