#pragma once
// A plane obstacle as something ParaView can draw: the part of the plane over the scene.

#include <corocontact/contact/plane_obstacle.hpp>
#include <corocontact/io/vtk_series.hpp>

#include <string>

namespace coro::detail {

/// The rectangle of `plane` that covers the box [lo, hi] (the scene's bounds) seen along the
/// plane's normal, widened by 10 % of the box's largest side on each edge, as a block of four
/// points and two triangles whose normal (x1−x0)×(x2−x0) is the plane's (pointing to the body
/// side). No point or cell data.
FrameBlock plane_patch(const PlaneObstacle& plane, const Vec3& lo, const Vec3& hi, std::string name);

} // namespace coro::detail
