#pragma once
/// @file inside_tests.hpp
/// @brief Inside tests of many points against one surface, the x axes of neighbouring points
/// walked through the tree together.

#include <corocontact/contact/axis_ray.hpp>

namespace coro::detail {

/// inside_test() of `count` points against the same surface, results[i] for points[i], equal to
/// inside_test() field for field. In exact mode, for a closed surface, the x axes of up to
/// AXIS_PACKET consecutive points are tested in one tree walk (faces_on_axis_lines), which pays
/// when the points are close together (e.g. in the order of AabbTree::vertices_in_box); the
/// points that x does not decide continue alone.
/// @param[in]  points   `count` points
/// @param[out] results  `count` results
void inside_tests(const ContactSurface& surface, const Vec3* points, Index count, DetectionMode mode,
                  const std::vector<Index>& candidate_faces, const AxisRayTolerances& tolerances,
                  InsideTest* results);

} // namespace coro::detail
