#include <corocontact/contact/plane_obstacle.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace coro {

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
            for (Index v = 0; v < surface.vertices.rows(); ++v)
                for (std::size_t k = 0; k < planes.size(); ++k) {
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
