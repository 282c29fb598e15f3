#include "detail/plane_patch.hpp"

#include <algorithm>
#include <limits>

namespace coro::detail {

FrameBlock plane_patch(const PlaneObstacle& plane, const Vec3& lo, const Vec3& hi, std::string name)
{
    // In-plane axes u, v with u × v = n: u from the coordinate axis least aligned with n.
    const Vec3 n = plane.normal.normalized();
    Eigen::Index least = 0;
    n.cwiseAbs().minCoeff(&least);
    const Vec3 u = (Vec3::Unit(least) - n[least] * n).normalized();
    const Vec3 v = n.cross(u);

    double u_min = std::numeric_limits<double>::infinity(), u_max = -u_min, v_min = u_min, v_max = -u_min;
    for (int corner = 0; corner < 8; ++corner) {
        const Vec3 c((corner & 1) != 0 ? hi.x() : lo.x(), (corner & 2) != 0 ? hi.y() : lo.y(),
                     (corner & 4) != 0 ? hi.z() : lo.z());
        const Vec3 d = c - plane.point;
        u_min = std::min(u_min, d.dot(u));
        u_max = std::max(u_max, d.dot(u));
        v_min = std::min(v_min, d.dot(v));
        v_max = std::max(v_max, d.dot(v));
    }
    const double margin = 0.1 * (hi - lo).maxCoeff();
    u_min -= margin;
    u_max += margin;
    v_min -= margin;
    v_max += margin;

    FrameBlock block;
    block.name = std::move(name);
    block.points.resize(4, 3);
    block.points.row(0) = (plane.point + u_min * u + v_min * v).transpose();
    block.points.row(1) = (plane.point + u_max * u + v_min * v).transpose();
    block.points.row(2) = (plane.point + u_max * u + v_max * v).transpose();
    block.points.row(3) = (plane.point + u_min * u + v_max * v).transpose();
    block.tris.resize(2, 3);
    block.tris << 0, 1, 2, 0, 2, 3;
    return block;
}

} // namespace coro::detail
