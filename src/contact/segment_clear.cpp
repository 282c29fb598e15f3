#include <corocontact/contact/aabb_tree.hpp>

#include "segment_triangle.hpp"

namespace coro {

using detail::segment_misses_triangle;

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
            const Aabb fb = slot_box(data, stride, slot);
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
