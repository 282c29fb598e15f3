#pragma once
/// @file closest_point.hpp
/// @brief The closest point of a triangle to a point: the measure of every nearest-point search
/// (the trees', Embree's, the brute-force references), so that they all agree bit for bit.

#include <corocontact/core/types.hpp>

namespace coro {

/// A point of a triangle and its barycentric weights.
struct TrianglePoint {
    Vec3 point = Vec3::Zero();       ///< the closest point [m]
    Vec3 barycentric = Vec3::Zero(); ///< its weights on the triangle's corners a, b, c (≥ 0, sum 1)
};

/// Closest point of triangle (a, b, c) to `p` (Ericson, Real-Time Collision Detection §5.1.5,
/// by Voronoi regions); a degenerate (collinear) triangle gives the nearest point of its edges.
TrianglePoint closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

/// The nearest point of a triangle surface to a query point.
struct NearestPoint {
    Index face = -1;                 ///< the face holding it, −1 for a surface without faces
    Vec3 point = Vec3::Zero();       ///< the point on that face [m]
    Vec3 barycentric = Vec3::Zero(); ///< its weights on the face's three vertices
    double distance = 0.0;           ///< its distance to the query point [m]
};

} // namespace coro
