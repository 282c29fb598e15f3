#include <corocontact/contact/plane_obstacle.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace coro {

void detect_plane_contacts(const std::vector<ContactSurface>& surfaces, Index num_bodies,
                           const std::vector<PlaneObstacle>& planes, std::vector<ContactPoint>& points,
                           std::vector<std::size_t>& offsets)
{
    // Each body's points are counted, then written at the place their counts give it, both in
    // parallel over bodies: in body order, then vertex, then plane, which is contact_order().
    const auto for_each_below = [&](Index b, const auto& f) {
        const ContactSurface& surface = surfaces[static_cast<std::size_t>(b)];
        for (Index v = 0; v < surface.vertices.rows(); ++v)
            for (std::size_t k = 0; k < planes.size(); ++k) {
                const double height = (surface.vertices.row(v).transpose() - planes[k].point).dot(planes[k].normal);
                if (!(height >= 0.0)) // NaN included: a point that is not above the plane
                    f(v, static_cast<Index>(k), height);
            }
    };
    const auto bodies = static_cast<std::size_t>(num_bodies);
    offsets.assign(bodies + 1, 0);
    tbb::parallel_for(tbb::blocked_range<Index>(0, num_bodies, 1), [&](const tbb::blocked_range<Index>& range) {
        for (Index b = range.begin(); b != range.end(); ++b) {
            std::size_t count = 0;
            for_each_below(b, [&](Index, Index, double) { ++count; });
            offsets[static_cast<std::size_t>(b) + 1] = count;
        }
    });
    for (std::size_t b = 0; b < bodies; ++b)
        offsets[b + 1] += offsets[b];
    points.resize(offsets[bodies]);
    tbb::parallel_for(tbb::blocked_range<Index>(0, num_bodies, 1), [&](const tbb::blocked_range<Index>& range) {
        for (Index b = range.begin(); b != range.end(); ++b) {
            ContactPoint* out = points.data() + offsets[static_cast<std::size_t>(b)];
            for_each_below(b, [&](Index v, Index k, double height) {
                ContactPoint& point = *out++;
                point = ContactPoint{};
                point.body = b;
                point.vertex = v;
                point.other = ContactTarget::plane(k);
                point.depth = -height;
                point.normal = planes[static_cast<std::size_t>(k)].normal;
            });
        }
    });
}

std::vector<ContactPoint> detect_plane_contacts(const std::vector<ContactSurface>& surfaces, Index num_bodies,
                                                const std::vector<PlaneObstacle>& planes)
{
    std::vector<ContactPoint> points;
    std::vector<std::size_t> offsets;
    detect_plane_contacts(surfaces, num_bodies, planes, points, offsets);
    return points;
}

} // namespace coro
