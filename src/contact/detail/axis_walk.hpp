#pragma once
/// @file axis_walk.hpp
/// @brief The faces of a tree whose boxes an axis-parallel line crosses (the bounding
/// rectangles of the paper's Eq. 4), one line at a time or a packet of parallel lines walked
/// together: the tree part of the exact axis test.

#include "simd.hpp"
#include "tree_access.hpp"

#include <limits>
#include <type_traits>

namespace coro::detail {

/// Lines per packet of faces_on_axis_lines().
constexpr int AXIS_PACKET = 8;

/// Calls `visit(face, corners)` for every face whose box is crossed by the axis-parallel line
/// through `point` along `axis` (0 = x, 1 = y, 2 = z), i.e. whose box contains `point` in the two
/// other coordinates (closed, grown by `tolerance`); `corners` are the face's three vertices in
/// the order of the surface's faces (the tree's copy, just read for the face's box: the faces
/// array need not be read again).
///
/// `visit` either returns void (every such face is visited) or a double, the largest distance
/// along the axis still of interest: subtrees whose boxes lie farther than the smallest value
/// returned so far from `point` along the axis are skipped. Child nodes are visited nearer
/// first; the order depends only on the tree and `point`.
/// @param[in] vertices  the positions the tree was last built or refit with
template <class Visit>
void faces_on_axis_line(const AabbTree& tree, CRef<Positions> vertices, const Vec3& point, int axis, double tolerance,
                        Visit&& visit)
{
    using simd::F4;
    const auto& nodes = TreeAccess::nodes(tree);
    if (nodes.empty())
        return;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double pu = point[u], pv = point[v], pa = point[axis];
    // Single precision boxes are rounded outward and the point's coordinates are widened to a
    // float interval containing them (grown by the tolerance), so no box the exact test accepts
    // is rejected; faces that pass get the exact test against their double box.
    const F4 pu_lo = F4::splat(float_down(pu - tolerance)), pu_hi = F4::splat(float_up(pu + tolerance));
    const F4 pv_lo = F4::splat(float_down(pv - tolerance)), pv_hi = F4::splat(float_up(pv + tolerance));
    const F4 pa_lo = F4::splat(float_down(pa)), pa_hi = F4::splat(float_up(pa));
    const F4 zero = F4::zero();
    double cutoff = std::numeric_limits<double>::infinity();
    float cutoff_f = std::numeric_limits<float>::infinity();
    Index stack[TreeAccess::STACK_SIZE];
    float stack_gap[TreeAccess::STACK_SIZE];
    int top = 0;
    stack[top] = 0;
    stack_gap[top++] = 0.0f;
    alignas(16) float gaps[4];
    while (top > 0) {
        --top;
        if (stack_gap[top] > cutoff_f)
            continue;
        const TreeAccess::Node& node = nodes[static_cast<std::size_t>(stack[top])];
        const auto crossed = (F4::load(node.lo[u]) <= pu_hi) & (F4::load(node.hi[u]) >= pu_lo) &
                             (F4::load(node.lo[v]) <= pv_hi) & (F4::load(node.hi[v]) >= pv_lo);
        // Lower bound of the distance along the axis from the point to each box.
        const F4 gap = max(max(F4::load(node.lo[axis]) - pa_hi, pa_lo - F4::load(node.hi[axis])), zero);
        const int mask = (crossed & (gap <= F4::splat(cutoff_f))).bits() & ((1 << node.count) - 1);
        if (mask == 0)
            continue;
        gap.store(gaps);
        // The node's faces now, in lane order; then its child nodes, nearer ones visited first.
        for (int m = mask & node.face_mask; m != 0; m &= m - 1) {
            const int k = __builtin_ctz(static_cast<unsigned>(m));
            const auto slot = static_cast<std::size_t>(-1 - node.child[k]);
            const Aabb fb = TreeAccess::slot_box(tree, vertices.data(), vertices.outerStride(), slot); // exact
            const Index* corners = TreeAccess::slot_vertices(tree, slot);
            if (pu < fb.min[u] - tolerance || pu > fb.max[u] + tolerance || pv < fb.min[v] - tolerance ||
                pv > fb.max[v] + tolerance)
                continue;
            if (static_cast<double>(gaps[k]) > cutoff * (1.0 + 0x1p-20))
                continue;
            const Index face = TreeAccess::face_of_slot(tree)[slot];
            if constexpr (std::is_void_v<decltype(visit(face, corners))>) {
                visit(face, corners);
            } else {
                const double limit = static_cast<double>(visit(face, corners));
                if (limit < cutoff) {
                    cutoff = limit;
                    cutoff_f = float_threshold(cutoff);
                }
            }
        }
        push_by_key(node, mask, gaps, stack, stack_gap, top);
    }
}

/// faces_on_axis_line() for a packet of up to AXIS_PACKET parallel lines (same `axis`), walked
/// together: at each node each line gets the child mask the single walk would give it (its own
/// float interval, its own cutoff), a child is entered if some line needs it, and
/// `visit(lane, face, corners)` is called only for the lines (lanes 0 .. count − 1 of `points`)
/// whose own mask holds the face and which pass the same exact double box test (`corners` as
/// for the single walk). `visit` returns the lane's largest distance along the axis still of
/// interest, as for the single walk. Each line meets every face that the single walk could give
/// it within its final cutoff; the order of the visits differs (children are ordered by the gaps
/// of the packet's first active line), so a visitor must not depend on it. Cheaper than count
/// single walks when the lines are close together (their paths through the tree share most
/// nodes).
/// @param[in] points  count points, 1 ≤ count ≤ AXIS_PACKET
template <class Visit>
void faces_on_axis_lines(const AabbTree& tree, CRef<Positions> vertices, const Vec3* points, int count, int axis,
                         double tolerance, Visit&& visit)
{
    using simd::F8;
    static_assert(AXIS_PACKET == F8::LANES, "a packet is one 8-float register");
    const auto& nodes = TreeAccess::nodes(tree);
    if (nodes.empty() || count <= 0)
        return;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    // Per line, the same float intervals as faces_on_axis_line; unused lanes copy line 0 and
    // are never active.
    float pu_lo[8], pu_hi[8], pv_lo[8], pv_hi[8], pa_lo[8], pa_hi[8];
    float cutoff_f[8];
    double pu[8], pv[8], cutoff[8];
    for (int q = 0; q < 8; ++q) {
        const Vec3& p = points[q < count ? q : 0];
        pu[q] = p[u];
        pv[q] = p[v];
        pu_lo[q] = float_down(pu[q] - tolerance);
        pu_hi[q] = float_up(pu[q] + tolerance);
        pv_lo[q] = float_down(pv[q] - tolerance);
        pv_hi[q] = float_up(pv[q] + tolerance);
        pa_lo[q] = float_down(p[axis]);
        pa_hi[q] = float_up(p[axis]);
        cutoff[q] = std::numeric_limits<double>::infinity();
        cutoff_f[q] = std::numeric_limits<float>::infinity();
    }
    const F8 qu_lo = F8::load(pu_lo), qu_hi = F8::load(pu_hi);
    const F8 qv_lo = F8::load(pv_lo), qv_hi = F8::load(pv_hi);
    const F8 qa_lo = F8::load(pa_lo), qa_hi = F8::load(pa_hi);
    const F8 zero = F8::zero();

    // Stack entries: a node, the lines that need it, and their gaps to its box.
    Index stack[TreeAccess::STACK_SIZE];
    unsigned stack_lines[TreeAccess::STACK_SIZE];
    float stack_gap[TreeAccess::STACK_SIZE][8];
    int top = 0;
    stack[top] = 0;
    stack_lines[top] = (1u << count) - 1u;
    zero.store(stack_gap[top++]);
    float gaps[4][8];
    unsigned lines[4];
    while (top > 0) {
        --top;
        const F8 cut = F8::load(cutoff_f);
        const unsigned active = stack_lines[top] & static_cast<unsigned>((F8::load(stack_gap[top]) <= cut).bits());
        if (active == 0)
            continue;
        const TreeAccess::Node& node = nodes[static_cast<std::size_t>(stack[top])];
        for (int k = 0; k < node.count; ++k) {
            const auto crossed = (F8::splat(node.lo[u][k]) <= qu_hi) & (F8::splat(node.hi[u][k]) >= qu_lo) &
                                 (F8::splat(node.lo[v][k]) <= qv_hi) & (F8::splat(node.hi[v][k]) >= qv_lo);
            const F8 gap = max(max(F8::splat(node.lo[axis][k]) - qa_hi, qa_lo - F8::splat(node.hi[axis][k])), zero);
            gap.store(gaps[k]);
            lines[k] = active & static_cast<unsigned>((crossed & (gap <= cut)).bits());
        }
        // The node's faces now, in lane order, each for the lines that need it; then its child
        // nodes, pushed farther first (by the gaps of the first line that needs each).
        for (int m = node.face_mask & ((1 << node.count) - 1); m != 0; m &= m - 1) {
            const int k = __builtin_ctz(static_cast<unsigned>(m));
            if (lines[k] == 0)
                continue;
            const auto slot = static_cast<std::size_t>(-1 - node.child[k]);
            const Aabb fb = TreeAccess::slot_box(tree, vertices.data(), vertices.outerStride(), slot); // exact
            const Index* corners = TreeAccess::slot_vertices(tree, slot);
            const Index face = TreeAccess::face_of_slot(tree)[slot];
            for (unsigned l = lines[k]; l != 0; l &= l - 1) {
                const int q = __builtin_ctz(l);
                if (pu[q] < fb.min[u] - tolerance || pu[q] > fb.max[u] + tolerance || pv[q] < fb.min[v] - tolerance ||
                    pv[q] > fb.max[v] + tolerance)
                    continue;
                if (static_cast<double>(gaps[k][q]) > cutoff[q] * (1.0 + 0x1p-20))
                    continue;
                const double limit = static_cast<double>(visit(q, face, corners));
                if (limit < cutoff[q]) {
                    cutoff[q] = limit;
                    cutoff_f[q] = float_threshold(limit);
                }
            }
        }
        int m = 0;
        for (int k = 0; k < node.count; ++k)
            m |= (lines[k] != 0 && !((node.face_mask >> k) & 1)) ? (1 << k) : 0;
        while (m != 0) {
            int far = __builtin_ctz(static_cast<unsigned>(m));
            float far_gap = gaps[far][__builtin_ctz(lines[far])];
            for (int rest = m & (m - 1); rest != 0; rest &= rest - 1) {
                const int k = __builtin_ctz(static_cast<unsigned>(rest));
                const float g = gaps[k][__builtin_ctz(lines[k])];
                if (g > far_gap) {
                    far = k;
                    far_gap = g;
                }
            }
            stack[top] = node.child[far];
            stack_lines[top] = lines[far];
            for (int q = 0; q < 8; ++q)
                stack_gap[top][q] = gaps[far][q];
            ++top;
            m &= ~(1 << far);
        }
    }
}

} // namespace coro::detail
