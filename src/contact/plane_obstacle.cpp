#include <corocontact/contact/plane_obstacle.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace coro {

std::vector<ContactPoint> detect_plane_contacts(const std::vector<ContactSurface>& surfaces, Index num_bodies,
                                                const std::vector<PlaneObstacle>& planes)
{
    // One list per body, filled in parallel and concatenated in body order.
    std::vector<std::vector<ContactPoint>> per_body(static_cast<std::size_t>(num_bodies));
    tbb::parallel_for(tbb::blocked_range<Index>(0, num_bodies, 1), [&](const tbb::blocked_range<Index>& range) {
        for (Index b = range.begin(); b != range.end(); ++b) {
            const ContactSurface& surface = surfaces[static_cast<std::size_t>(b)];
            auto& out = per_body[static_cast<std::size_t>(b)];
            for (Index v = 0; v < surface.vertices.rows(); ++v)
                for (std::size_t k = 0; k < planes.size(); ++k) {
                    const double height =
                        (surface.vertices.row(v).transpose() - planes[k].point).dot(planes[k].normal);
                    if (height >= 0.0)
                        continue;
                    ContactPoint point;
                    point.body = b;
                    point.vertex = v;
                    point.other = ContactTarget::plane(static_cast<Index>(k));
                    point.depth = -height;
                    point.normal = planes[k].normal;
                    out.push_back(point);
                }
        }
    });
    std::vector<ContactPoint> points;
    for (auto& list : per_body)
        points.insert(points.end(), list.begin(), list.end());
    std::sort(points.begin(), points.end(), contact_order);
    return points;
}

} // namespace coro
