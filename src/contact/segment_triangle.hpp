#pragma once
/// @file segment_triangle.hpp
/// @brief Whether a segment misses a triangle, shown by orientation signs beyond their rounding
/// (internal: AabbTree::segment_clear and AabbTree::clear_edge_groups share it).

#include "orientation.hpp"

#include <cmath>

namespace coro::detail {

struct SignedVolume {
    double value, bound; ///< the sign of value is exact when |value| > bound
};

/// det[r, x, y] = r·(x × y), with its rounding bound.
inline __attribute__((always_inline)) SignedVolume volume(const double* r, const double* x, const double* y)
{
    const double m0 = x[1] * y[2], m1 = x[2] * y[1];
    const double m2 = x[2] * y[0], m3 = x[0] * y[2];
    const double m4 = x[0] * y[1], m5 = x[1] * y[0];
    const double value = r[0] * (m0 - m1) + r[1] * (m2 - m3) + r[2] * (m4 - m5);
    const double permanent = std::abs(r[0]) * (std::abs(m0) + std::abs(m1)) +
                             std::abs(r[1]) * (std::abs(m2) + std::abs(m3)) +
                             std::abs(r[2]) * (std::abs(m4) + std::abs(m5));
    return {value, ORIENT3D_BOUND * permanent};
}

inline bool positive(const SignedVolume& s) { return s.value > s.bound; }
inline bool negative(const SignedVolume& s) { return s.value < -s.bound; }

/// Whether the closed segment [p, q] and the closed triangle (a, b, c) are shown disjoint by
/// signs beyond their rounding: both ends strictly on one side of the triangle's plane, or the
/// segment's line strictly on the left of one edge and strictly on the right of another (a line
/// through a point of the triangle has all three edge volumes of one sign or zero).
inline bool segment_misses_triangle(const double* p, const double* q, const double* a, const double* b, const double* c)
{
    // Plane side: n·(x − a), n = (b − a) × (c − a), for x = p and q, n's products shared.
    const FaceNormal normal = face_normal(a, b, c);
    const double* n = normal.n;
    const double* perm = normal.permanent;
    const auto side = [&](const double* x) {
        const double d[3] = {x[0] - a[0], x[1] - a[1], x[2] - a[2]};
        return SignedVolume{n[0] * d[0] + n[1] * d[1] + n[2] * d[2],
                            ORIENT3D_BOUND *
                                (perm[0] * std::abs(d[0]) + perm[1] * std::abs(d[1]) + perm[2] * std::abs(d[2]))};
    };
    const SignedVolume side_p = side(p);
    if (positive(side_p) || negative(side_p)) {
        const SignedVolume side_q = side(q);
        if (positive(side_p) ? positive(side_q) : negative(side_q))
            return true;
    }
    // Edge sides of the line: det[q − p, x − p, y − p] for the edges (x, y) = ab, bc, ca.
    const double r[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    const double ap[3] = {a[0] - p[0], a[1] - p[1], a[2] - p[2]};
    const double bp[3] = {b[0] - p[0], b[1] - p[1], b[2] - p[2]};
    const double cp[3] = {c[0] - p[0], c[1] - p[1], c[2] - p[2]};
    const SignedVolume e0 = volume(r, ap, bp), e1 = volume(r, bp, cp);
    if ((positive(e0) && negative(e1)) || (negative(e0) && positive(e1)))
        return true;
    const SignedVolume e2 = volume(r, cp, ap);
    return ((positive(e0) || positive(e1)) && negative(e2)) || ((negative(e0) || negative(e1)) && positive(e2));
}

} // namespace coro::detail
