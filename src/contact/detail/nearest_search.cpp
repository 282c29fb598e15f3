#include "nearest_search.hpp"

#include "simd.hpp"
#include "tree_access.hpp"

#include <algorithm>
#include <cmath>

namespace coro::detail {

namespace {

constexpr float NO_SLACK = std::numeric_limits<float>::infinity();

void no_plane(FacePlanes& w, int k)
{
    w.normal[0][k] = w.normal[1][k] = w.normal[2][k] = 0.0f;
    w.offset[k] = 0.0f;
    w.slack[k] = NO_SLACK;
}

/// The plane of face (A, B, C) into lane k.
void face_plane(const double* A, const double* B, const double* C, FacePlanes& w, int k)
{
    // In single precision: u = the normalised cross product of the edges rounded to float, the
    // offset u·A. The slack is measured: for x = A + s·e1 + t·e2 on the face, u·(x − A) =
    // s·(u·e1) + t·(u·e2) lies within max(|u·e1|, |u·e2|) of 0; the float evaluation of those
    // dot products and of the offset (from float roundings of A, e1, e2: each within 2⁻²⁴ of
    // its value) errs by less than 2⁻²¹·(|A|₁ + |e1|₁ + |e2|₁), which is added. Any error in u
    // only widens the slack; |u| ≤ 1 + 2⁻²² (correctly rounded sqrt and division).
    const float a[3] = {static_cast<float>(A[0]), static_cast<float>(A[1]), static_cast<float>(A[2])};
    const float e1[3] = {static_cast<float>(B[0] - A[0]), static_cast<float>(B[1] - A[1]), static_cast<float>(B[2] - A[2])};
    const float e2[3] = {static_cast<float>(C[0] - A[0]), static_cast<float>(C[1] - A[1]), static_cast<float>(C[2] - A[2])};
    const float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const float nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (!(nn > 1e-30f) || !(nn < 1e30f)) // degenerate (or absurd) face: never pruned by its plane
        return no_plane(w, k);
    const float inv = 1.0f / std::sqrt(nn);
    const float u[3] = {n[0] * inv, n[1] * inv, n[2] * inv};
    const float off = u[0] * a[0] + u[1] * a[1] + u[2] * a[2];
    const float s1 = std::abs(u[0] * e1[0] + u[1] * e1[1] + u[2] * e1[2]);
    const float s2 = std::abs(u[0] * e2[0] + u[1] * e2[1] + u[2] * e2[2]);
    const float magnitude = std::abs(a[0]) + std::abs(a[1]) + std::abs(a[2]) + std::abs(e1[0]) + std::abs(e1[1]) +
                            std::abs(e1[2]) + std::abs(e2[0]) + std::abs(e2[1]) + std::abs(e2[2]);
    const float slack = (std::max(s1, s2) + magnitude * 0x1p-20f) * (1.0f + 0x1p-20f) + 0x1p-120f;
    for (int j = 0; j < 3; ++j)
        w.normal[j][k] = u[j];
    w.offset[k] = off;
    // The search's margin, rounded up (two roundings of 2⁻²⁴ each, covered by the factor).
    w.slack[k] = (slack + std::abs(off) * 0x1p-20f) * (1.0f + 0x1p-22f);
}

/// The slab of child node k of `parent` into lane k: along the normal u of the child's three
/// slab corners, the range of u·x over its distinct vertices (so over its faces), as offset ±
/// slack with the float rounding of u and the offset and the double rounding of u·x covered.
void node_slab(const AabbTree& tree, const TreeAccess::Node& parent, int k, const double* data, std::ptrdiff_t stride,
               FacePlanes& w)
{
    no_plane(w, k);
    const auto node = static_cast<std::size_t>(parent.child[k]);
    const auto& start = TreeAccess::slab_start(tree);
    const auto begin = static_cast<std::size_t>(start[node]);
    const auto end = static_cast<std::size_t>(start[node + 1]);
    if (begin == end) // a subtree of many faces
        return;
    const std::array<Index, 3>& corner = TreeAccess::slab_corners(tree)[node];
    const Vec3 a(data + stride * corner[0]), b(data + stride * corner[1]), c(data + stride * corner[2]);
    const Vec3 normal = (b - a).cross(c - a);
    const double length = normal.norm();
    if (!(length > 0.0) || !std::isfinite(length))
        return;
    const float u[3] = {static_cast<float>(normal[0] / length), static_cast<float>(normal[1] / length),
                        static_cast<float>(normal[2] / length)};
    const double ud[3] = {u[0], u[1], u[2]};
    const Index* vertex = TreeAccess::slab_vertices(tree).data();
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (std::size_t i = begin; i < end; ++i) {
        const double* x = data + stride * vertex[i];
        const double t = ud[0] * x[0] + ud[1] * x[1] + ud[2] * x[2];
        lo = std::min(lo, t);
        hi = std::max(hi, t);
    }
    // Bounds |x| of every coordinate x of the node's vertices (they lie in its float box, lane k
    // of the parent, which is at hand).
    double magnitude = 0.0;
    for (int j = 0; j < 3; ++j)
        magnitude += std::abs(static_cast<double>(parent.lo[j][k])) + std::abs(static_cast<double>(parent.hi[j][k]));
    const double mid = 0.5 * (lo + hi);
    const float off = static_cast<float>(mid);
    const double slack = 0.5 * (hi - lo) + std::abs(static_cast<double>(off) - mid) + 1e-14 * magnitude;
    if (!std::isfinite(slack))
        return;
    for (int j = 0; j < 3; ++j)
        w.normal[j][k] = u[j];
    w.offset[k] = off;
    w.slack[k] = float_up(slack + std::abs(static_cast<double>(off)) * 0x1p-20);
}

} // namespace

void compute_face_planes(const AabbTree& tree, std::size_t node, const double* data, std::ptrdiff_t stride,
                         FacePlanes& planes)
{
    const TreeAccess::Node& w = TreeAccess::nodes(tree)[node];
    for (int k = 0; k < 4; ++k) {
        if (k >= w.count) {
            no_plane(planes, k);
        } else if (w.child[k] >= 0) {
            node_slab(tree, w, k, data, stride, planes);
        } else {
            const Index* fv = TreeAccess::slot_vertices(tree, static_cast<std::size_t>(-1 - w.child[k]));
            face_plane(data + stride * fv[0], data + stride * fv[1], data + stride * fv[2], planes, k);
        }
    }
}

void FacePlaneCache::reset(const AabbTree& tree)
{
    const std::size_t n = TreeAccess::nodes(tree).size();
    if (n != m_size || m_epoch >= 0x7ffffffe) { // a new size, or the stamps would wrap around
        m_planes.resize(n);
        m_stamp.reset(new std::atomic<std::uint32_t>[n]);
        for (std::size_t i = 0; i < n; ++i)
            m_stamp[i].store(0, std::memory_order_relaxed);
        m_size = n;
        m_epoch = 0;
    }
    ++m_epoch; // every stamp is now stale: below busy()
}

const FacePlanes* FacePlaneCache::claim(std::size_t node, const AabbTree& tree, const double* data,
                                        std::ptrdiff_t stride)
{
    std::uint32_t stamp = m_stamp[node].load(std::memory_order_acquire);
    if (stamp == ready())
        return &m_planes[node];
    if (stamp == busy())
        return nullptr; // another thread computes them
    if (!m_stamp[node].compare_exchange_strong(stamp, busy(), std::memory_order_acquire))
        return stamp == ready() ? &m_planes[node] : nullptr; // done meanwhile, or being done
    compute_face_planes(tree, node, data, stride, m_planes[node]);
    m_stamp[node].store(ready(), std::memory_order_release);
    return &m_planes[node];
}

NearestPoint NearestSearch::find(const Vec3& point, double distance_bound, Index hint_face, const Tris* faces) const
{
    NearestPoint best;
    const auto& nodes = TreeAccess::nodes(m_tree);
    if (nodes.empty())
        return best;
    // The best so far: the hint face (measured as every face is below), else none with the
    // bound as the squared distance to beat. Of faces with the same computed squared distance
    // the smallest index wins, so neither the start nor the traversal order changes the answer.
    // The hint face, once measured, is not measured again by the walk: it would get the same.
    double best_d2 = std::numeric_limits<double>::infinity();
    if (distance_bound < std::numeric_limits<double>::infinity())
        best_d2 = distance_bound * distance_bound * (1.0 + 1e-6) + std::numeric_limits<double>::min();
    Index measured = -1;
    if (faces != nullptr && hint_face >= 0 && hint_face < faces->rows()) {
        const auto corner = [&](int c) { return Vec3(m_data + m_stride * (*faces)(hint_face, c)); };
        const TrianglePoint q = closest_point_on_triangle(point, corner(0), corner(1), corner(2));
        const double d2 = (q.point - point).squaredNorm();
        measured = hint_face;
        if (d2 <= best_d2) {
            best_d2 = d2;
            best.face = hint_face;
            best.point = q.point;
            best.barycentric = q.barycentric;
        }
    }
    // Squared distances of the point to four single precision boxes at once. The point is
    // widened to a float interval [p_lo, p_hi] containing it, so the float result is at most the
    // exact squared distance times (1 + 2⁻²¹); a box is skipped only when that is above the
    // threshold, float_threshold(best_d2) ≥ best_d2·(1 + 2⁻¹⁸): it then lies strictly farther
    // than the best face, ties included.
    using simd::F4;
    const F4 p_lo[3] = {F4::splat(float_down(point[0])), F4::splat(float_down(point[1])),
                        F4::splat(float_down(point[2]))};
    const F4 p_hi[3] = {F4::splat(float_up(point[0])), F4::splat(float_up(point[1])), F4::splat(float_up(point[2]))};
    // The plane bound |u·p − offset| − slack is computed in float from p's rounding; the error of
    // that (a few float ulps of |p|₁ + |offset|, taken 8 times over) is subtracted: the offset's
    // part is in the slack, p's here. (1 − 2⁻¹⁸)·bound ≤ the distance (|u| ≤ 1 + 2⁻²²).
    const F4 p_f[3] = {F4::splat(static_cast<float>(point[0])), F4::splat(static_cast<float>(point[1])),
                       F4::splat(static_cast<float>(point[2]))};
    const F4 p_error = F4::splat(
        static_cast<float>((std::abs(point[0]) + std::abs(point[1]) + std::abs(point[2])) * 0x1p-20) + 0x1p-120f);
    const F4 zero = F4::zero(), shrink = F4::splat(1.0f - 0x1p-18f);
    float threshold = float_threshold(best_d2);
    F4 limit = F4::splat(threshold);
    Index stack[TreeAccess::STACK_SIZE];
    float stack_d2[TreeAccess::STACK_SIZE];
    int top = 0;
    stack[top] = 0;
    stack_d2[top++] = 0.0f;
    alignas(16) float d2[4];
    while (top > 0) {
        --top;
        if (stack_d2[top] > threshold)
            continue;
        const auto n = static_cast<std::size_t>(stack[top]);
        const TreeAccess::Node& node = nodes[n];
        F4 sum = zero;
        for (int j = 0; j < 3; ++j) {
            const F4 d = max(max(F4::load(node.lo[j]) - p_hi[j], p_lo[j] - F4::load(node.hi[j])), zero);
            sum = sum + d * d;
        }
        // A child whose slab lies beyond the threshold is skipped too: its key is the larger of
        // the two lower bounds, so that the stack pops the nearest by the tighter one first.
        if (const FacePlanes* planes = m_planes ? m_planes->get(n, m_tree, m_data, m_stride) : nullptr) {
            const F4 dot = F4::load(planes->normal[0]) * p_f[0] - F4::load(planes->offset) +
                           F4::load(planes->normal[1]) * p_f[1] + F4::load(planes->normal[2]) * p_f[2];
            const F4 lower = max(abs(dot) - F4::load(planes->slack) - p_error, zero) * shrink;
            sum = max(sum, lower * lower);
        }
        const int lanes = (sum <= limit).bits() & ((1 << node.count) - 1);
        if (lanes == 0)
            continue;
        sum.store(d2);
        // Faces first (lane order: of equally near faces the smallest index wins anyway), then
        // the child nodes, the nearest on top of the stack.
        for (int m = lanes & node.face_mask; m != 0; m &= m - 1) {
            const int k = __builtin_ctz(static_cast<unsigned>(m));
            const auto slot = static_cast<std::size_t>(-1 - node.child[k]);
            const Index f = TreeAccess::face_of_slot(m_tree)[slot];
            if (d2[k] > threshold || f == measured)
                continue;
            const Index* fv = TreeAccess::slot_vertices(m_tree, slot);
            const TrianglePoint q = closest_point_on_triangle(point, Vec3(m_data + m_stride * fv[0]),
                                                              Vec3(m_data + m_stride * fv[1]), Vec3(m_data + m_stride * fv[2]));
            const double dq = (q.point - point).squaredNorm();
            if (dq < best_d2 || (dq == best_d2 && f < best.face)) {
                best_d2 = dq;
                threshold = float_threshold(best_d2);
                limit = F4::splat(threshold);
                best.face = f;
                best.point = q.point;
                best.barycentric = q.barycentric;
            }
        }
        push_by_key(node, lanes, d2, stack, stack_d2, top);
    }
    if (best.face < 0) // a bound below the true distance: search again without it
        return distance_bound < std::numeric_limits<double>::infinity() ? find(point) : best;
    best.distance = std::sqrt(best_d2);
    return best;
}

void NearestSearch::find_packet(const Vec3* points, int count, const double* distance_bounds,
                                const Index* hint_faces, const Tris* faces, NearestPoint* out) const
{
    using simd::F8;
    static_assert(PACKET == F8::LANES, "a packet is one 8-float register");
    const auto& nodes = TreeAccess::nodes(m_tree);
    for (int q = 0; q < count; ++q)
        out[q] = NearestPoint{};
    if (nodes.empty() || count <= 0)
        return;
    // Per point, the start of find(); unused lanes copy point 0 and are never active.
    double best_d2[PACKET];
    float threshold[PACKET];
    float lo[3][PACKET], hi[3][PACKET], pf[3][PACKET], error[PACKET];
    Index measured[PACKET]; // the hint face, once measured: the walk would measure it the same
    std::fill(measured, measured + PACKET, Index{-1});
    for (int q = 0; q < PACKET; ++q) {
        const Vec3& p = points[q < count ? q : 0];
        for (int j = 0; j < 3; ++j) {
            lo[j][q] = float_down(p[j]);
            hi[j][q] = float_up(p[j]);
            pf[j][q] = static_cast<float>(p[j]);
        }
        error[q] = static_cast<float>((std::abs(p[0]) + std::abs(p[1]) + std::abs(p[2])) * 0x1p-20) + 0x1p-120f;
        best_d2[q] = std::numeric_limits<double>::infinity();
        if (q >= count)
            continue;
        if (distance_bounds[q] < std::numeric_limits<double>::infinity())
            best_d2[q] = distance_bounds[q] * distance_bounds[q] * (1.0 + 1e-6) + std::numeric_limits<double>::min();
        const Index hint = hint_faces[q];
        if (faces != nullptr && hint >= 0 && hint < faces->rows()) {
            const auto corner = [&](int c) { return Vec3(m_data + m_stride * (*faces)(hint, c)); };
            const TrianglePoint t = closest_point_on_triangle(p, corner(0), corner(1), corner(2));
            const double d2 = (t.point - p).squaredNorm();
            measured[q] = hint;
            if (d2 <= best_d2[q]) {
                best_d2[q] = d2;
                out[q].face = hint;
                out[q].point = t.point;
                out[q].barycentric = t.barycentric;
            }
        }
        threshold[q] = float_threshold(best_d2[q]);
    }
    for (int q = count; q < PACKET; ++q)
        threshold[q] = -1.0f;
    const F8 p_lo[3] = {F8::load(lo[0]), F8::load(lo[1]), F8::load(lo[2])};
    const F8 p_hi[3] = {F8::load(hi[0]), F8::load(hi[1]), F8::load(hi[2])};
    const F8 p_f[3] = {F8::load(pf[0]), F8::load(pf[1]), F8::load(pf[2])};
    const F8 p_error = F8::load(error);
    const F8 zero = F8::zero(), shrink = F8::splat(1.0f - 0x1p-18f);
    F8 limit = F8::load(threshold);

    // Stack entries: a node and the points that need it. Their bounds are not checked again
    // when the node comes off the stack: the searches start close to their answers, so the
    // thresholds hardly tighten meanwhile, and the children are bounded anyway.
    Index stack[TreeAccess::STACK_SIZE];
    unsigned stack_lanes[TreeAccess::STACK_SIZE];
    int top = 0;
    stack[top] = 0;
    stack_lanes[top++] = (1u << count) - 1u;
    // The bounds of the four children of node n for the points in `active` (an unused child's
    // box is empty: its bound is +∞), into d2[child][point]; lanes[child]: the points whose
    // bound is within their threshold. Returns bit k set when some point needs child k.
    const auto bound_children = [&](std::size_t n, unsigned active, float (&d2)[4][PACKET], unsigned (&lanes)[4]) {
        const TreeAccess::Node& node = nodes[n];
        const FacePlanes* planes = m_planes ? m_planes->get(n, m_tree, m_data, m_stride) : nullptr;
        for (int k = 0; k < 4; ++k) {
            F8 sum = zero;
            for (int j = 0; j < 3; ++j) {
                const F8 d = max(max(F8::splat(node.lo[j][k]) - p_hi[j], p_lo[j] - F8::splat(node.hi[j][k])), zero);
                sum = sum + d * d;
            }
            if (planes) {
                const F8 dot = F8::splat(planes->normal[0][k]) * p_f[0] - F8::splat(planes->offset[k]) +
                               F8::splat(planes->normal[1][k]) * p_f[1] + F8::splat(planes->normal[2][k]) * p_f[2];
                const F8 lower = max(abs(dot) - F8::splat(planes->slack[k]) - p_error, zero) * shrink;
                sum = max(sum, lower * lower);
            }
            sum.store(d2[k]);
            lanes[k] = active & static_cast<unsigned>((sum <= limit).bits());
        }
        return ((lanes[0] != 0 ? 1 : 0) | (lanes[1] != 0 ? 2 : 0) | (lanes[2] != 0 ? 4 : 0) | (lanes[3] != 0 ? 8 : 0)) &
               ((1 << node.count) - 1);
    };
    // The faces among `needed` children of `node`, each for the points that need it.
    const auto test_faces = [&](const TreeAccess::Node& node, int needed, const float (&d2)[4][PACKET],
                                const unsigned (&lanes)[4]) {
        for (int m = needed & node.face_mask; m != 0; m &= m - 1) {
            const int k = __builtin_ctz(static_cast<unsigned>(m));
            const auto slot = static_cast<std::size_t>(-1 - node.child[k]);
            const Index* fv = TreeAccess::slot_vertices(m_tree, slot);
            const Vec3 a(m_data + m_stride * fv[0]), b(m_data + m_stride * fv[1]), c(m_data + m_stride * fv[2]);
            const Index f = TreeAccess::face_of_slot(m_tree)[slot];
            bool improved = false;
            for (unsigned l = lanes[k]; l != 0; l &= l - 1) {
                const int q = __builtin_ctz(l);
                if (d2[k][q] > threshold[q] || f == measured[q])
                    continue;
                const TrianglePoint t = closest_point_on_triangle(points[q], a, b, c);
                const double dq = (t.point - points[q]).squaredNorm();
                if (dq < best_d2[q] || (dq == best_d2[q] && f < out[q].face)) {
                    best_d2[q] = dq;
                    threshold[q] = float_threshold(dq);
                    out[q].face = f;
                    out[q].point = t.point;
                    out[q].barycentric = t.barycentric;
                    improved = true;
                }
            }
            if (improved)
                limit = F8::load(threshold);
        }
    };
    while (top > 0) {
        --top;
        const unsigned active = stack_lanes[top];
        const auto n = static_cast<std::size_t>(stack[top]);
        const TreeAccess::Node& node = nodes[n];
        float d2[4][PACKET];
        unsigned lanes[4];
        const int needed = bound_children(n, active, d2, lanes);
        test_faces(node, needed, d2, lanes);
        // The child nodes: those of faces only (the last level) at once, the others onto the
        // stack, in any order (it matters little for the same reason).
        for (int m = needed & ~node.face_mask; m != 0; m &= m - 1) {
            const int k = __builtin_ctz(static_cast<unsigned>(m));
            const auto c = static_cast<std::size_t>(node.child[k]);
            if (nodes[c].face_mask == (1 << nodes[c].count) - 1) {
                float child_d2[4][PACKET];
                unsigned child_lanes[4];
                const int child_needed = bound_children(c, lanes[k], child_d2, child_lanes);
                test_faces(nodes[c], child_needed, child_d2, child_lanes);
                continue;
            }
            stack[top] = node.child[k];
            stack_lanes[top++] = lanes[k];
        }
    }
    for (int q = 0; q < count; ++q) {
        if (out[q].face < 0) { // a bound below the true distance: search again without it
            out[q] = find(points[q]);
            continue;
        }
        out[q].distance = std::sqrt(best_d2[q]);
    }
}

} // namespace coro::detail
