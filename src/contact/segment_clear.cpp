#include <corocontact/contact/aabb_tree.hpp>

#include "orientation.hpp"

#include <cmath>

namespace coro {

namespace {

using detail::ORIENT3D_BOUND;

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

bool positive(const SignedVolume& s) { return s.value > s.bound; }
bool negative(const SignedVolume& s) { return s.value < -s.bound; }

/// Whether the closed segment [p, q] and the closed triangle (a, b, c) are shown disjoint by
/// signs beyond their rounding: both ends strictly on one side of the triangle's plane, or the
/// segment's line strictly on the left of one edge and strictly on the right of another (a line
/// through a point of the triangle has all three edge volumes of one sign or zero).
bool segment_misses_triangle(const double* p, const double* q, const double* a, const double* b, const double* c)
{
    // Plane side: n·(x − a), n = (b − a) × (c − a), for x = p and q, n's products shared.
    const detail::FaceNormal normal = detail::face_normal(a, b, c);
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

} // namespace

bool AabbTree::segment_clear(CRef<Positions> vertices, const Vec3& p, const Vec3& q) const
{
    if (m_nodes.empty())
        return true;
    const Vec3 lo = p.cwiseMin(q), hi = p.cwiseMax(q);
    // The float node boxes bound the exact ones and the segment's box is widened to floats, so a
    // node is skipped only when its exact box misses the segment's.
    __m128 seg_lo[3], seg_hi[3];
    for (int j = 0; j < 3; ++j) {
        seg_lo[j] = _mm_set1_ps(detail::float_down(lo[j]));
        seg_hi[j] = _mm_set1_ps(detail::float_up(hi[j]));
    }
    const double* data = vertices.data();
    const std::ptrdiff_t stride = vertices.outerStride();
    Index stack[STACK_SIZE];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const WideNode& node = m_nodes[static_cast<std::size_t>(stack[--top])];
        __m128 overlap = _mm_castsi128_ps(_mm_set1_epi32(-1));
        for (int j = 0; j < 3; ++j)
            overlap = _mm_and_ps(overlap, _mm_and_ps(_mm_cmple_ps(_mm_load_ps(node.lo[j]), seg_hi[j]),
                                                     _mm_cmpge_ps(_mm_load_ps(node.hi[j]), seg_lo[j])));
        const int mask = _mm_movemask_ps(overlap) & ((1 << node.count) - 1);
        for (int m = mask; m != 0; m &= m - 1) {
            const int k = __builtin_ctz(static_cast<unsigned>(m));
            if (!((node.face_mask >> k) & 1)) {
                stack[top++] = node.child[k];
                continue;
            }
            const std::size_t slot = static_cast<std::size_t>(-1 - node.child[k]);
            const Aabb& fb = m_face_boxes[slot];
            if (fb.min[0] > hi[0] || fb.min[1] > hi[1] || fb.min[2] > hi[2] || fb.max[0] < lo[0] ||
                fb.max[1] < lo[1] || fb.max[2] < lo[2])
                continue;
            const Index* fv = &m_slot_vertices[3 * slot];
            if (!segment_misses_triangle(p.data(), q.data(), data + stride * fv[0], data + stride * fv[1],
                                         data + stride * fv[2]))
                return false;
        }
    }
    return true;
}

} // namespace coro
