#include <corocontact/contact/closest_point.hpp>

#include <algorithm>

namespace coro {

namespace {

TrianglePoint closest_point_on_segment(const Vec3& p, const Vec3& a, const Vec3& b)
{
    const Vec3 ab = b - a;
    const double len2 = ab.squaredNorm();
    const double s = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return {a + s * ab, Vec3(1.0 - s, s, 0.0)};
}

} // namespace

TrianglePoint closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c)
{
    // Ericson, RTCD §5.1.5: find the Voronoi region of p.
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0.0 && d2 <= 0.0)
        return {a, Vec3(1, 0, 0)};
    const Vec3 bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0.0 && d4 <= d3)
        return {b, Vec3(0, 1, 0)};
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        const double s = d1 / (d1 - d3);
        return {a + s * ab, Vec3(1.0 - s, s, 0.0)};
    }
    const Vec3 cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0.0 && d5 <= d6)
        return {c, Vec3(0, 0, 1)};
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        const double s = d2 / (d2 - d6);
        return {a + s * ac, Vec3(1.0 - s, 0.0, s)};
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        const double s = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return {b + s * (c - b), Vec3(0.0, 1.0 - s, s)};
    }
    const double sum = va + vb + vc;
    if (!(sum > 0.0)) { // degenerate (collinear) triangle: the nearest of its three edges
        TrianglePoint best = closest_point_on_segment(p, a, b);
        TrianglePoint e = closest_point_on_segment(p, b, c);
        e.barycentric = Vec3(0.0, e.barycentric[0], e.barycentric[1]);
        if ((e.point - p).squaredNorm() < (best.point - p).squaredNorm())
            best = e;
        e = closest_point_on_segment(p, c, a);
        e.barycentric = Vec3(e.barycentric[1], 0.0, e.barycentric[0]);
        if ((e.point - p).squaredNorm() < (best.point - p).squaredNorm())
            best = e;
        return best;
    }
    const double v = vb / sum, w = vc / sum;
    return {a + v * ab + w * ac, Vec3(1.0 - v - w, v, w)};
}

} // namespace coro
