#include <corocontact/contact/aabb_tree.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace coro {

double AabbTree::empty_cube(CRef<Positions> vertices, const Vec3& point, double min_half_size,
                            double max_half_size, Index* hint) const
{
    if (!(max_half_size > 0.0) || !(max_half_size >= min_half_size))
        return 0.0;
    // best: the smallest L∞ distance from the point to a face box met so far, capped.
    double best = max_half_size;
    const auto box_distance = [&](std::size_t slot) {
        const Aabb fb = slot_box(vertices.data(), vertices.outerStride(), slot);
        double d = 0.0;
        for (int j = 0; j < 3; ++j)
            d = std::max({d, fb.min[j] - point[j], point[j] - fb.max[j]});
        return d;
    };
    Index nearest_slot = -1;
    if (hint && *hint >= 0 && static_cast<std::size_t>(*hint) < m_order.size()) {
        const double d = box_distance(static_cast<std::size_t>(*hint));
        if (d < best) {
            best = d;
            nearest_slot = *hint;
            if (best < min_half_size)
                return 0.0;
        }
    }
    if (!m_nodes.empty()) {
        // Float lower bounds of the L∞ distance to four boxes at once: the boxes are rounded
        // outward and the point widened to a float interval, so each bound is at most the exact
        // distance times (1 + 2⁻²⁴); a box is skipped only when its bound reaches
        // float_threshold(best) ≥ best·(1 + 2⁻¹⁸): none of its faces can lower best.
        __m128 p_lo[3], p_hi[3];
        for (int j = 0; j < 3; ++j) {
            p_lo[j] = _mm_set1_ps(detail::float_down(point[j]));
            p_hi[j] = _mm_set1_ps(detail::float_up(point[j]));
        }
        const __m128 zero = _mm_setzero_ps();
        float threshold = detail::float_threshold(best);
        Index stack[STACK_SIZE];
        float stack_gap[STACK_SIZE];
        int top = 0;
        stack[top] = 0;
        stack_gap[top++] = 0.0f;
        alignas(16) float gaps[4];
        while (top > 0) {
            --top;
            if (stack_gap[top] >= threshold)
                continue;
            const WideNode& node = m_nodes[static_cast<std::size_t>(stack[top])];
            __m128 gap = zero;
            for (int j = 0; j < 3; ++j)
                gap = _mm_max_ps(gap, _mm_max_ps(_mm_sub_ps(_mm_load_ps(node.lo[j]), p_hi[j]),
                                                 _mm_sub_ps(p_lo[j], _mm_load_ps(node.hi[j]))));
            const int mask = _mm_movemask_ps(_mm_cmplt_ps(gap, _mm_set1_ps(threshold))) & ((1 << node.count) - 1);
            if (mask == 0)
                continue;
            _mm_store_ps(gaps, gap);
            for (int m = mask & node.face_mask; m != 0; m &= m - 1) {
                const int k = __builtin_ctz(static_cast<unsigned>(m));
                const Index slot = -1 - node.child[k];
                const double d = box_distance(static_cast<std::size_t>(slot));
                if (d < best) {
                    best = d;
                    nearest_slot = slot;
                    if (best < min_half_size) {
                        if (hint)
                            *hint = slot;
                        return 0.0;
                    }
                    threshold = detail::float_threshold(best);
                }
            }
            push_children(node, mask, gaps, stack, stack_gap, top); // the nearest on top
        }
    }
    // Every face box lies at L∞ distance D ≥ best/(1 + 2⁻⁵³) (computed distances err by one
    // rounding). h stays below D by about 2⁻³⁰·D plus 2⁻⁴⁰ of the coordinates' size, more than
    // the rounding of point ± h, so the computed cube still misses the face box on the axis
    // that separates them.
    if (hint && nearest_slot >= 0)
        *hint = nearest_slot;
    const double size = std::max({std::abs(point[0]), std::abs(point[1]), std::abs(point[2]), best});
    const double h = best * (1.0 - 0x1p-30) - size * 0x1p-40;
    return h > 0.0 && h >= min_half_size ? h : 0.0;
}

} // namespace coro
