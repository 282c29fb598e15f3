#pragma once
/// @file brute_force_nearest.hpp
/// @brief The reference for the nearest-point searches (our trees', Embree's): every face of a
/// surface measured with closest_point_on_triangle.

#include <corocontact/contact/contact_surface.hpp>

#include <limits>

namespace coro::test {

struct BruteForceNearest {
    Index face = -1;                                          ///< −1 for a surface without faces
    double squared_distance = std::numeric_limits<double>::infinity();
};

/// The minimum over all faces of (computed squared distance, face index): of equally near
/// faces the first wins, as the searches promise.
inline BruteForceNearest brute_force_nearest(const ContactSurface& s, const Vec3& p)
{
    BruteForceNearest best;
    for (Index f = 0; f < s.faces.rows(); ++f) {
        const TrianglePoint t = closest_point_on_triangle(p, s.vertices.row(s.faces(f, 0)).transpose(),
                                                          s.vertices.row(s.faces(f, 1)).transpose(),
                                                          s.vertices.row(s.faces(f, 2)).transpose());
        const double d2 = (t.point - p).squaredNorm();
        if (d2 < best.squared_distance) {
            best.squared_distance = d2;
            best.face = f;
        }
    }
    return best;
}

} // namespace coro::test
