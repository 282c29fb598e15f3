#pragma once
/// @file segment_triangle.hpp
/// @brief Whether a segment misses a triangle (one, or four at once in AVX2 lanes), shown by
/// orientation signs beyond their rounding: the edge test of clear_edge_groups().

#include "orientation.hpp"
#include "simd.hpp"

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
    return {value, ORIENT3D_BOUND * permanent +
                       UNDERFLOW_BOUND * (1.0 + std::abs(r[0]) + std::abs(r[1]) + std::abs(r[2]))};
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
                                    (perm[0] * std::abs(d[0]) + perm[1] * std::abs(d[1]) + perm[2] * std::abs(d[2])) +
                                UNDERFLOW_BOUND * (1.0 + std::abs(d[0]) + std::abs(d[1]) + std::abs(d[2]))};
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

/// Triangles per call of segment_misses_triangles().
constexpr int TRIANGLE_LANES = 4;

#if CORO_CONTACT_AVX2
namespace lanes {

/// Four vertices' (x, y, z) as one register per coordinate, lane k from vertex k.
inline void transpose(const double* const* v, __m256d& x, __m256d& y, __m256d& z)
{
    const __m256i xyz = _mm256_setr_epi64x(-1, -1, -1, 0); // a row is 3 doubles: no load past it
    const __m256d v0 = _mm256_maskload_pd(v[0], xyz), v1 = _mm256_maskload_pd(v[1], xyz);
    const __m256d v2 = _mm256_maskload_pd(v[2], xyz), v3 = _mm256_maskload_pd(v[3], xyz);
    const __m256d xz01 = _mm256_unpacklo_pd(v0, v1), y01 = _mm256_unpackhi_pd(v0, v1);
    const __m256d xz23 = _mm256_unpacklo_pd(v2, v3), y23 = _mm256_unpackhi_pd(v2, v3);
    x = _mm256_permute2f128_pd(xz01, xz23, 0x20);
    z = _mm256_permute2f128_pd(xz01, xz23, 0x31);
    y = _mm256_permute2f128_pd(y01, y23, 0x20);
}

inline __m256d abs(__m256d v) { return _mm256_andnot_pd(_mm256_set1_pd(-0.0), v); }

/// UNDERFLOW_BOUND·(1 + Σ_j |d_j|) per lane.
inline __m256d underflow_bound(const __m256d* d)
{
    const __m256d sum = _mm256_add_pd(_mm256_add_pd(abs(d[0]), abs(d[1])), abs(d[2]));
    return _mm256_mul_pd(_mm256_set1_pd(UNDERFLOW_BOUND), _mm256_add_pd(_mm256_set1_pd(1.0), sum));
}

/// SignedVolume per lane, as masks: value > bound, value < −bound.
struct Signs {
    __m256d positive, negative;
};

inline Signs signs(__m256d value, __m256d bound)
{
    return {_mm256_cmp_pd(value, bound, _CMP_GT_OQ),
            _mm256_cmp_pd(value, _mm256_sub_pd(_mm256_setzero_pd(), bound), _CMP_LT_OQ)};
}

/// volume(r, x, y) per lane, r the same in every lane.
inline Signs volume(const __m256d* r, const __m256d* x, const __m256d* y)
{
    const __m256d m0 = _mm256_mul_pd(x[1], y[2]), m1 = _mm256_mul_pd(x[2], y[1]);
    const __m256d m2 = _mm256_mul_pd(x[2], y[0]), m3 = _mm256_mul_pd(x[0], y[2]);
    const __m256d m4 = _mm256_mul_pd(x[0], y[1]), m5 = _mm256_mul_pd(x[1], y[0]);
    const __m256d value = _mm256_add_pd(
        _mm256_add_pd(_mm256_mul_pd(r[0], _mm256_sub_pd(m0, m1)), _mm256_mul_pd(r[1], _mm256_sub_pd(m2, m3))),
        _mm256_mul_pd(r[2], _mm256_sub_pd(m4, m5)));
    const __m256d permanent =
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(abs(r[0]), _mm256_add_pd(abs(m0), abs(m1))),
                                    _mm256_mul_pd(abs(r[1]), _mm256_add_pd(abs(m2), abs(m3)))),
                      _mm256_mul_pd(abs(r[2]), _mm256_add_pd(abs(m4), abs(m5))));
    return signs(value, _mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd(ORIENT3D_BOUND), permanent), underflow_bound(r)));
}

} // namespace lanes
#endif

/// segment_misses_triangle(p, q, a[k], b[k], c[k]) for triangles k < count ≤ TRIANGLE_LANES at
/// once: bit k of the result is its answer (the same signs and bounds, evaluated in the four
/// lanes of AVX2 registers where the build has them), 1 ≤ count. a, b and c hold TRIANGLE_LANES
/// entries; with AVX2 those from `count` on are set to entry 0 (unused lanes repeat triangle 0).
inline int segment_misses_triangles(const double* p, const double* q, const double** a, const double** b,
                                    const double** c, int count)
{
#if CORO_CONTACT_AVX2
    for (int k = count; k < TRIANGLE_LANES; ++k) {
        a[k] = a[0];
        b[k] = b[0];
        c[k] = c[0];
    }
    __m256d A[3], B[3], C[3];
    lanes::transpose(a, A[0], A[1], A[2]);
    lanes::transpose(b, B[0], B[1], B[2]);
    lanes::transpose(c, C[0], C[1], C[2]);
    // Plane side (as face_normal and the side of segment_misses_triangle).
    __m256d n[3], permanent[3];
    {
        __m256d d1[3], d2[3];
        for (int j = 0; j < 3; ++j) {
            d1[j] = _mm256_sub_pd(B[j], A[j]);
            d2[j] = _mm256_sub_pd(C[j], A[j]);
        }
        for (int j = 0; j < 3; ++j) {
            const int u = (j + 1) % 3, v = (j + 2) % 3;
            const __m256d first = _mm256_mul_pd(d1[u], d2[v]), second = _mm256_mul_pd(d1[v], d2[u]);
            n[j] = _mm256_sub_pd(first, second);
            permanent[j] = _mm256_add_pd(lanes::abs(first), lanes::abs(second));
        }
    }
    const auto side = [&](const double* x) {
        __m256d d[3];
        for (int j = 0; j < 3; ++j)
            d[j] = _mm256_sub_pd(_mm256_set1_pd(x[j]), A[j]);
        const __m256d value = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(n[0], d[0]), _mm256_mul_pd(n[1], d[1])),
                                            _mm256_mul_pd(n[2], d[2]));
        const __m256d bound = _mm256_add_pd(
            _mm256_mul_pd(_mm256_set1_pd(ORIENT3D_BOUND),
                          _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(permanent[0], lanes::abs(d[0])),
                                                      _mm256_mul_pd(permanent[1], lanes::abs(d[1]))),
                                        _mm256_mul_pd(permanent[2], lanes::abs(d[2])))),
            lanes::underflow_bound(d));
        return lanes::signs(value, bound);
    };
    const lanes::Signs side_p = side(p), side_q = side(q);
    __m256d clear = _mm256_or_pd(_mm256_and_pd(side_p.positive, side_q.positive),
                                 _mm256_and_pd(side_p.negative, side_q.negative));
    // A third of the batches of clear_edge_groups are decided here: all their triangles' planes
    // leave both ends of the segment on one side.
    const int all = (1 << count) - 1;
    if ((_mm256_movemask_pd(clear) & all) == all)
        return all;
    // Edge sides of the line.
    __m256d r[3], ap[3], bp[3], cp[3];
    for (int j = 0; j < 3; ++j) {
        const __m256d pj = _mm256_set1_pd(p[j]);
        r[j] = _mm256_set1_pd(q[j] - p[j]);
        ap[j] = _mm256_sub_pd(A[j], pj);
        bp[j] = _mm256_sub_pd(B[j], pj);
        cp[j] = _mm256_sub_pd(C[j], pj);
    }
    const lanes::Signs e0 = lanes::volume(r, ap, bp), e1 = lanes::volume(r, bp, cp), e2 = lanes::volume(r, cp, ap);
    clear = _mm256_or_pd(clear, _mm256_or_pd(_mm256_and_pd(e0.positive, e1.negative),
                                             _mm256_and_pd(e0.negative, e1.positive)));
    clear = _mm256_or_pd(clear, _mm256_and_pd(_mm256_or_pd(e0.positive, e1.positive), e2.negative));
    clear = _mm256_or_pd(clear, _mm256_and_pd(_mm256_or_pd(e0.negative, e1.negative), e2.positive));
    return _mm256_movemask_pd(clear) & all;
#else
    int clear = 0;
    for (int k = 0; k < count; ++k)
        clear |= segment_misses_triangle(p, q, a[k], b[k], c[k]) ? 1 << k : 0;
    return clear;
#endif
}

} // namespace coro::detail
