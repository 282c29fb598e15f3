#include <corocontact/contact/plane_obstacle.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace coro {

namespace {

/// Bit k set unless every point of `box` lies above plane k (k < 32; later planes are always
/// set). Above means by more than the rounding of a vertex's height, so a vertex in the box
/// whose computed height is negative never belongs to a plane whose bit is clear.
std::uint32_t planes_near(const Aabb& box, const std::vector<PlaneObstacle>& planes)
{
    std::uint32_t near = 0;
    for (std::size_t k = 0; k < planes.size(); ++k) {
        if (k >= 32) {
            near = ~0U;
            break;
        }
        const PlaneObstacle& plane = planes[k];
        double lowest = 0.0, scale = 0.0;
        for (int i = 0; i < 3; ++i) {
            const double n = plane.normal[i];
            lowest += ((n >= 0.0 ? box.min[i] : box.max[i]) - plane.point[i]) * n;
            scale += (std::max(std::abs(box.min[i]), std::abs(box.max[i])) + std::abs(plane.point[i])) * std::abs(n);
        }
        // Not (lowest > margin): an empty or non-finite box is near every plane.
        if (!(lowest > 1e-12 * scale) || !std::isfinite(scale))
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
            const std::uint32_t near = planes_near(surface.tree.bounds(), planes);
            if (near == 0)
                continue;
            for (Index v = 0; v < surface.vertices.rows(); ++v)
                for (std::size_t k = 0; k < planes.size(); ++k) {
                    if (k < 32 && !((near >> k) & 1U))
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
