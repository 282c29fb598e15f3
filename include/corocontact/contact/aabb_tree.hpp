#pragma once
/// @file aabb_tree.hpp
/// @brief Bounding-volume hierarchy of a triangle surface: built once (the topology never
/// changes), refit bottom-up each step (DESIGN.md, Contact detection: hierarchical AABBs).

#include <corocontact/contact/aabb.hpp>

#include <xmmintrin.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <vector>

namespace coro {

/// Closest point of triangle (a, b, c) to `p` (Ericson, Real-Time Collision Detection §5.1.5,
/// by Voronoi regions; a degenerate triangle falls back to its closest edge).
struct TrianglePoint {
    Vec3 point = Vec3::Zero();       ///< the closest point
    Vec3 barycentric = Vec3::Zero(); ///< its weights on a, b, c (≥ 0, sum 1)
};
TrianglePoint closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

class AabbTree {
public:
    AabbTree() = default;

    /// Builds the hierarchy over `faces` at `vertices`: four children per node (median splits
    /// of the face centroids along the longest axis, twice per node), one face per leaf child.
    /// @param[in] vertices  #V×3 positions
    /// @param[in] faces     #F×3 indices into vertices; the tree stores its own copy of the face
    ///                      list, so `faces` may go away after the call
    void build(CRef<Positions> vertices, const Tris& faces);

    /// Recomputes every box bottom-up for new positions of the same vertices: one pass over the
    /// nodes in reverse build order (children before parents), no recursion, no allocation; large
    /// trees refit their top subtrees as parallel tasks. Every box is a pure function of its
    /// children, so the result does not depend on the thread count.
    void refit(CRef<Positions> vertices);

    /// Computes the face planes and node slabs that let nearest() skip faces and subtrees by
    /// their distance along a normal, for the
    /// positions of the last build or refit (which leave them out of date: nearest() is exact
    /// either way, only slower without them). A cache: const, but not to be called concurrently
    /// with other queries on the same tree. Large trees compute them in parallel tasks.
    /// @param[in] vertices  the positions the tree was last built or refit with
    void update_planes(CRef<Positions> vertices) const;

    /// Box of the whole surface (empty for an empty tree).
    const Aabb& bounds() const;
    Index num_faces() const { return static_cast<Index>(m_faces.rows()); }
    const Tris& faces() const { return m_faces; }

    /// Faces whose box overlaps `box` (closed intervals), ascending.
    void faces_overlapping(const Aabb& box, std::vector<Index>& out) const;

    /// Vertices used by the faces that lie in `box` (closed), in the tree's spatial order
    /// (neighbours close together, good for the cache of a following query loop), not ascending.
    /// @param[in] vertices  the positions the tree was last built or refit with
    void vertices_in_box(CRef<Positions> vertices, const Aabb& box, std::vector<Index>& out) const;

    /// Calls `visit(face)` for every face whose box is crossed by the axis-parallel line
    /// through `point` along `axis` (0 = x, 1 = y, 2 = z), i.e. whose box contains `point`
    /// in the two other coordinates (closed, grown by `tolerance`).
    ///
    /// The face boxes are the bounding rectangles of Eq. 4 (closed here, grown by `tolerance`).
    /// `visit` either returns void (every such face is visited) or a double, the largest
    /// distance along the axis still of interest: subtrees whose boxes lie farther than the
    /// smallest value returned so far from `point` along the axis are skipped. Child nodes are
    /// visited nearer first; the order depends only on the tree and `point` (deterministic).
    template <class Visit>
    void faces_on_axis_line(const Vec3& point, int axis, double tolerance, Visit&& visit) const;

    /// Nearest point of the surface to `point`.
    struct Nearest {
        Index face = -1;
        Vec3 point = Vec3::Zero();       ///< closest point on that face
        Vec3 barycentric = Vec3::Zero(); ///< its weights on the face's 3 vertices
        double distance = 0.0;
    };
    /// Exact point–triangle distances (closest_point_on_triangle), branch and bound over the
    /// boxes, nearer children first. Of equally near faces (the same computed squared distance)
    /// the one with the smallest index wins, so the answer does not depend on the traversal.
    /// @param[in] vertices  the positions the tree was last built or refit with
    /// @return face −1 for an empty tree
    Nearest nearest(CRef<Positions> vertices, const Vec3& point) const;

    /// The same answer as nearest(vertices, point), bit for bit, found faster from hints that
    /// bound the distance from above: the search starts with that bound instead of +∞, so it
    /// skips the subtrees that cannot hold the answer. The bound is slightly inflated (relative
    /// 10⁻⁶ on the squared distance) before use, so faces tied with the nearest one are still
    /// visited and the same one wins.
    /// @param[in] distance_bound  a distance that some point of the surface is known to be within
    ///                            (e.g. a face crossing of an axis line through `point`, plus its
    ///                            rounding bound); +∞ for none
    /// @param[in] hint_face       a face likely near `point` (e.g. the previous query's answer),
    ///                            −1 for none; any valid face is correct, a near one is faster
    Nearest nearest(CRef<Positions> vertices, const Vec3& point, double distance_bound, Index hint_face) const;

    static constexpr Index MAX_LEAF_FACES = 4; ///< faces per node whose children are all faces
    static constexpr Index VERTEX_BLOCK = 32; ///< vertices per box of the vertex query

private:
    /// One node: up to four children, their boxes in single precision rounded outward (so they
    /// bound the exact boxes) as structure of arrays, one SSE register per coordinate bound.
    struct alignas(64) WideNode {
        float lo[3][4]; ///< [coordinate][child] box minimum
        float hi[3][4]; ///< [coordinate][child] box maximum
        Index child[4]; ///< ≥ 0: node index; < 0: the face in slot −1 − child of m_order
        Index count;    ///< children used (2..4; 1 only for a one-face tree), lanes 0..count−1
        Index face_mask; ///< bit k set: child k is a face
    };
    static constexpr int MAX_DEPTH = 60;
    static constexpr int STACK_SIZE = 3 * MAX_DEPTH + 4;
    Index build_node(const std::vector<Vec3>& centroids, Index begin, Index end, int depth);
    void refit_range(const double* data, std::ptrdiff_t stride, Index first, Index last);
    void refit_node(const double* data, std::ptrdiff_t stride, Index n);
    /// The planes of a node's children: unit normal u, offset and slack s such that every point
    /// x of the child (a face, or the faces of a child node) has |u·x − offset| ≤ s (s = +∞ for
    /// a degenerate face or a child whose faces' normals nearly cancel), so
    /// (|u·p − offset| − s)/|u| bounds the child's distance to p from below.
    struct alignas(16) FacePlanes {
        float normal[3][4];
        float offset[4];
        float slack[4];
    };
    static void face_plane(const double* A, const double* B, const double* C, FacePlanes& w, int k);

    std::vector<WideNode> m_nodes;  // root at 0; every subtree is a contiguous range after its root
    std::vector<Aabb> m_node_boxes; // exact box of each node (union of its children's)
    std::vector<Index> m_subtree_end; // one past the last node of each node's subtree
    std::vector<Index> m_node_slots;  // 2 per node: the range of slots (faces) of its subtree
    std::vector<Index> m_task_roots;  // parallel refit: roots of the subtrees refit as tasks
    std::vector<Index> m_order;       // face of each slot, in leaf order
    mutable std::vector<FacePlanes> m_planes; // per node; a cache filled by update_planes
    mutable bool m_planes_current = false;    // m_planes match the positions of the last refit
    std::vector<Aabb> m_face_boxes;   // exact box of the face in each slot, refit with the nodes
    std::vector<Index> m_slot_vertices; // 3 per slot: the vertices of the face in that slot
    Aabb m_bounds;
    std::vector<Index> m_vertex_order;  // used vertices, first appearance in leaf order
    std::vector<Aabb> m_vertex_blocks;  // box of each VERTEX_BLOCK consecutive m_vertex_order entries
    Tris m_faces;
};

namespace detail {
/// `x` rounded to a float no greater (down) or no smaller (up): the nearest float, then a step
/// of at least one ulp outward (a few ulps looser than needed, branch-free).
inline float float_down(double x)
{
    const float f = static_cast<float>(x);
    return f - (std::abs(f) * 0x1p-23f + 0x1p-126f);
}
inline float float_up(double x)
{
    const float f = static_cast<float>(x);
    return f + (std::abs(f) * 0x1p-23f + 0x1p-126f);
}
/// A float threshold no smaller than `x` ≥ 0, with a relative margin of 2⁻¹⁸ (covers the
/// rounding of the single precision lower bounds compared against it); +∞ from 10³⁸ on.
inline float float_threshold(double x)
{
    if (!(x < 1e38))
        return std::numeric_limits<float>::infinity();
    return static_cast<float>(x) * (1.0f + 0x1p-18f);
}
} // namespace detail

template <class Visit>
void AabbTree::faces_on_axis_line(const Vec3& point, int axis, double tolerance, Visit&& visit) const
{
    if (m_nodes.empty())
        return;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double pu = point[u], pv = point[v], pa = point[axis];
    // Single precision boxes are rounded outward and the point's coordinates are widened to a
    // float interval containing them (grown by the tolerance), so no box the exact test accepts
    // is rejected; faces that pass get the exact test against their double box.
    const __m128 pu_lo = _mm_set1_ps(detail::float_down(pu - tolerance));
    const __m128 pu_hi = _mm_set1_ps(detail::float_up(pu + tolerance));
    const __m128 pv_lo = _mm_set1_ps(detail::float_down(pv - tolerance));
    const __m128 pv_hi = _mm_set1_ps(detail::float_up(pv + tolerance));
    const __m128 pa_lo = _mm_set1_ps(detail::float_down(pa));
    const __m128 pa_hi = _mm_set1_ps(detail::float_up(pa));
    const __m128 zero = _mm_setzero_ps();
    double cutoff = std::numeric_limits<double>::infinity();
    __m128 cutoff_f = _mm_set1_ps(std::numeric_limits<float>::infinity());
    Index stack[STACK_SIZE];
    float stack_gap[STACK_SIZE];
    int top = 0;
    stack[top] = 0;
    stack_gap[top++] = 0.0f;
    alignas(16) float gaps[4];
    while (top > 0) {
        --top;
        if (stack_gap[top] > _mm_cvtss_f32(cutoff_f))
            continue;
        const WideNode& node = m_nodes[static_cast<std::size_t>(stack[top])];
        const __m128 crossed = _mm_and_ps(
            _mm_and_ps(_mm_cmple_ps(_mm_load_ps(node.lo[u]), pu_hi), _mm_cmpge_ps(_mm_load_ps(node.hi[u]), pu_lo)),
            _mm_and_ps(_mm_cmple_ps(_mm_load_ps(node.lo[v]), pv_hi), _mm_cmpge_ps(_mm_load_ps(node.hi[v]), pv_lo)));
        // Lower bound of the distance along the axis from the point to each box.
        const __m128 gap = _mm_max_ps(_mm_max_ps(_mm_sub_ps(_mm_load_ps(node.lo[axis]), pa_hi),
                                                 _mm_sub_ps(pa_lo, _mm_load_ps(node.hi[axis]))),
                                      zero);
        int mask = _mm_movemask_ps(_mm_and_ps(crossed, _mm_cmple_ps(gap, cutoff_f))) & ((1 << node.count) - 1);
        if (mask == 0)
            continue;
        _mm_store_ps(gaps, gap);
        // The node's faces now, in lane order; then its child nodes, pushed farther first so
        // that the nearer ones are visited first.
        for (int m = mask & node.face_mask; m != 0; m &= m - 1) {
            const int k = __builtin_ctz(static_cast<unsigned>(m));
            const std::size_t slot = static_cast<std::size_t>(-1 - node.child[k]);
            const Aabb& fb = m_face_boxes[slot]; // the exact test
            if (pu < fb.min[u] - tolerance || pu > fb.max[u] + tolerance || pv < fb.min[v] - tolerance ||
                pv > fb.max[v] + tolerance)
                continue;
            if (static_cast<double>(gaps[k]) > cutoff * (1.0 + 0x1p-20))
                continue;
            const Index face = m_order[slot];
            if constexpr (std::is_void_v<decltype(visit(face))>) {
                visit(face);
            } else {
                const double limit = static_cast<double>(visit(face));
                if (limit < cutoff) {
                    cutoff = limit;
                    cutoff_f = _mm_set1_ps(detail::float_threshold(cutoff));
                }
            }
        }
        for (int m = mask & ~node.face_mask; m != 0;) {
            int far = __builtin_ctz(static_cast<unsigned>(m));
            for (int rest = m & (m - 1); rest != 0; rest &= rest - 1) {
                const int k = __builtin_ctz(static_cast<unsigned>(rest));
                if (gaps[k] > gaps[far])
                    far = k;
            }
            stack[top] = node.child[far];
            stack_gap[top++] = gaps[far];
            m &= ~(1 << far);
        }
    }
}

} // namespace coro
