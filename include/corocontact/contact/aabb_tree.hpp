#pragma once
/// @file aabb_tree.hpp
/// @brief Bounding-volume hierarchy of a triangle surface: built once (the topology never
/// changes), refit bottom-up each step (DESIGN.md, Contact detection: hierarchical AABBs).

#include <corocontact/contact/aabb.hpp>

#include <xmmintrin.h>
#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <array>
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

    /// Builds the hierarchy over `faces` at `vertices`: four children per node but at most one
    /// per level (splits of the face centroids along the longest axis, at the median rounded to
    /// whole full subtrees of 1, 4, 16, … faces), one face per leaf child: about #F/3 nodes.
    /// @param[in] vertices  #V×3 positions
    /// @param[in] faces     #F×3 indices into vertices; the tree stores its own copy of the face
    ///                      list, so `faces` may go away after the call
    void build(CRef<Positions> vertices, const Tris& faces);

    /// Recomputes every box bottom-up for new positions of the same vertices: one pass over the
    /// nodes in reverse build order (children before parents), no recursion, no allocation; large
    /// trees refit their top subtrees as parallel tasks. Every box is a pure function of its
    /// children, so the result does not depend on the thread count. Only the single precision
    /// node boxes are stored: a query that needs a face's exact box computes it from `vertices`
    /// (writing a double box per face was most of a cold refit's memory traffic).
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
    /// Nodes of the hierarchy (each holds up to four children, faces or nodes).
    Index num_nodes() const { return static_cast<Index>(m_nodes.size()); }
    const Tris& faces() const { return m_faces; }
    /// The face in `slot`, its place in the tree's leaf order (0 ≤ slot < num_faces()).
    Index slot_face(Index slot) const { return m_order[static_cast<std::size_t>(slot)]; }

    /// Faces whose box overlaps `box` (closed intervals), ascending.
    /// @param[in] vertices  the positions the tree was last built or refit with
    void faces_overlapping(CRef<Positions> vertices, const Aabb& box, std::vector<Index>& out) const;

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
    /// @param[in] vertices  the positions the tree was last built or refit with
    template <class Visit>
    void faces_on_axis_line(CRef<Positions> vertices, const Vec3& point, int axis, double tolerance,
                            Visit&& visit) const;

    /// Queries per packet of faces_on_axis_lines().
    static constexpr int AXIS_PACKET = 8;

    /// faces_on_axis_line() for a packet of up to AXIS_PACKET parallel lines (same `axis`),
    /// walked together: at each node each line gets the child mask the single walk would give
    /// it (its own float interval, its own cutoff), a child is entered if some line needs it,
    /// and `visit(lane, face)` is called only for the lines (lanes 0..count−1 of `points`) whose
    /// own mask holds the face and which pass the same exact double box test. `visit` returns
    /// the lane's largest distance along the axis still of interest, as for the single walk.
    /// Each line meets every face that the single walk could give it within its final cutoff;
    /// the order of the visits differs (children are ordered by the gaps of the packet's first
    /// active line), so a visitor must not depend on it. Cheaper than count single walks when
    /// the lines are close together (their paths through the tree share most nodes).
    /// @param[in] vertices  the positions the tree was last built or refit with
    /// @param[in] points    count points, 1 ≤ count ≤ AXIS_PACKET
    template <class Visit>
    void faces_on_axis_lines(CRef<Positions> vertices, const Vec3* points, int count, int axis, double tolerance,
                             Visit&& visit) const;

    /// Half-size h of a cube centred at `point` that meets no face box, so no point of the
    /// surface: the L∞ distance from `point` to the nearest face box, capped at `max_half_size`,
    /// lowered by a margin that covers the rounding of point ± h, so the closed box
    /// [point − h, point + h] computed in double is disjoint from every face box. Every point of
    /// that box is joined to `point` by a segment that does not meet the surface: for a closed
    /// surface it is inside exactly when `point` is.
    /// Branch and bound over the boxes, nearer children first; the walk stops, returning 0, as
    /// soon as h is known to be below `min_half_size`.
    /// @param[in] vertices       the positions the tree was last built or refit with
    /// @param[in] min_half_size  smallest useful h (≥ 0), same length unit as the positions
    /// @param[in] max_half_size  largest h wanted (≥ min_half_size); the whole walk is cheaper
    ///                           with a smaller cap
    /// @param[in,out] hint       null, or a token of a face box tried first (−1: none) that is
    ///                           set to the nearest face box met: passing it from one call to the
    ///                           next for nearby points makes the walk shorter (the answer does
    ///                           not depend on it)
    /// @return h, 0 ≤ h ≤ max_half_size, or 0
    double empty_cube(CRef<Positions> vertices, const Vec3& point, double min_half_size, double max_half_size,
                      Index* hint = nullptr) const;

    /// Whether the closed segment [p, q] is shown to meet no face of the surface: every face
    /// whose box meets the segment's box is shown disjoint from the segment by signs beyond their
    /// rounding bounds (both ends strictly on one side of the face's plane, or the segment's line
    /// strictly passing the face outside two of its edges). Then p and q are both inside or both
    /// outside a closed surface. False when that cannot be shown: the segment crosses or touches
    /// the surface, or a sign is within rounding (never true for a segment that meets a face).
    /// @param[in] vertices  the positions the tree was last built or refit with
    bool segment_clear(CRef<Positions> vertices, const Vec3& p, const Vec3& q) const;

    /// Pairs (face of this tree, face of `other`) whose boxes overlap each other (closed) and
    /// both meet `region`: a walk of the two trees together, four children against four (large
    /// trees: from node pairs a few levels down both trees, as parallel tasks). Every face of
    /// `other` that meets a face of this surface inside `region` is in a pair with it.
    /// @param[in] vertices        this surface's positions (last build or refit)
    /// @param[in] other_vertices  `other`'s positions (last build or refit)
    /// @param[out] pairs          the pairs, each once, in an order that depends only on the two
    ///                            trees
    void overlapping_faces(CRef<Positions> vertices, const AabbTree& other, CRef<Positions> other_vertices,
                           const Aabb& region, std::vector<std::array<Index, 2>>& pairs) const;
    /// The walk of overlapping_faces() with each face as its slot, its place in its tree's leaf
    /// order (what clear_edge_groups() takes: it saves two lookups per face, far apart in memory),
    /// and the faces' single precision boxes (rounded outward) in place of their exact boxes: a
    /// superset of overlapping_faces(), by pairs whose boxes meet only within float rounding.
    /// @param[out] slot_pairs  (slot in this tree, slot in `other`), each pair once
    void overlapping_slots(const AabbTree& other, const Aabb& region,
                           std::vector<std::array<Index, 2>>& slot_pairs) const;

    /// Splits candidate vertices of this surface into groups joined by edges of this surface that
    /// meet no face of `other`: the vertices of a group are all inside or all outside `other`'s
    /// closed surface. An edge is clear when one of its faces is in no pair of `slot_pairs`, or
    /// when each face of `other` paired with it whose box meets the edge's is shown to miss the
    /// edge by signs beyond their rounding (as segment_clear). A vertex on `other`'s surface
    /// meets a face with every edge, so it is a group of its own. Keeps its working arrays per
    /// thread between calls (as large as the largest surface the thread has grouped).
    /// @param[in] vertices        this surface's positions (last build or refit)
    /// @param[in] other_vertices  `other`'s positions (last build or refit)
    /// @param[in] slot_pairs      overlapping_slots() of the two trees over a region holding
    ///                            every candidate; (this slot, other slot) when `column` is 0,
    ///                            (other slot, this slot) when it is 1
    /// @param[in] candidates      distinct vertices of this surface in that region
    /// @param[out] group          per candidate, its group, 0 .. groups − 1, the groups numbered
    ///                            in the order of their first candidates
    /// @param[out] firsts         per group, the index into `candidates` of its first candidate
    ///                            (ascending)
    /// @param[out] path           per candidate, an upper bound of the length of a path of clear
    ///                            edges from its group's first candidate (0 for that one), same
    ///                            unit as positions; null: not computed
    /// @return the number of groups
    Index clear_edge_groups(CRef<Positions> vertices, const AabbTree& other, CRef<Positions> other_vertices,
                            const std::vector<std::array<Index, 2>>& slot_pairs, int column,
                            const std::vector<Index>& candidates, std::vector<Index>& group,
                            std::vector<Index>& firsts, std::vector<double>* path) const;

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
    /// Pushes the child nodes of `node` selected by `mask` with their bounds `keys` (one per
    /// lane), the largest first, so that the nearest is popped first.
    static void push_children(const WideNode& node, int mask, const float* keys, Index* stack, float* stack_keys,
                              int& top)
    {
        for (int m = mask & ~node.face_mask; m != 0;) {
            int far = __builtin_ctz(static_cast<unsigned>(m));
            for (int rest = m & (m - 1); rest != 0; rest &= rest - 1) {
                const int k = __builtin_ctz(static_cast<unsigned>(rest));
                if (keys[k] > keys[far])
                    far = k;
            }
            stack[top] = node.child[far];
            stack_keys[top++] = keys[far];
            m &= ~(1 << far);
        }
    }
    static constexpr int MAX_DEPTH = 60;
    static constexpr int STACK_SIZE = 3 * MAX_DEPTH + 4;
    Index build_node(const std::vector<Vec3>& centroids, Index begin, Index end, int depth);
    /// The lanes of `node` whose float box meets the float box [lo, hi] (one register per bound).
    int lanes_meeting(Index node, const __m128* lo, const __m128* hi) const;
    /// The node pairs (this tree, `other`) from which overlapping_slots() walks in parallel:
    /// together they lead to every pair of faces, each once, in an order fixed by the trees.
    std::vector<std::array<Index, 2>> walk_tasks(const AabbTree& other, const Aabb& region) const;
    /// overlapping_slots() below node a_root of this tree and b_root of `other`.
    void walk_overlapping(const AabbTree& other, const Aabb& region, Index a_root, Index b_root,
                          std::vector<std::array<Index, 2>>& slots) const;
    void build_edges(std::size_t vertex_count);
    /// Subtrees of more faces get no slab: computing one costs a pass over their vertices.
    static constexpr Index SLAB_MAX_FACES = 1024;
    void build_slab_vertices(std::size_t vertex_count);
    void refit_range(const double* data, std::ptrdiff_t stride, Index first, Index last);
    void refit_node(const double* data, std::ptrdiff_t stride, Index n);
    /// The exact box of the face in `slot`, its corners at data + stride·v (3 doubles each).
    Aabb slot_box(const double* data, std::ptrdiff_t stride, std::size_t slot) const
    {
        const Index* fv = &m_slot_vertices[3 * slot];
        const double* a = data + stride * fv[0];
        const double* b = data + stride * fv[1];
        const double* c = data + stride * fv[2];
        Aabb box; // in the operand order of the SIMD min/max elsewhere (the same with a NaN)
        for (int j = 0; j < 3; ++j) {
            box.min[j] = std::min(c[j], std::min(b[j], a[j]));
            box.max[j] = std::max(c[j], std::max(b[j], a[j]));
        }
        return box;
    }
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

    /// A node's box in single precision, rounded outward: x, y, z and an unused fourth lane.
    struct alignas(32) NodeBounds {
        float lo[4];
        float hi[4];
    };

    std::vector<WideNode> m_nodes;  // root at 0; every subtree is a contiguous range after its root
    std::vector<NodeBounds> m_node_bounds; // each node's box: the union of its lanes
    std::vector<Index> m_subtree_end; // one past the last node of each node's subtree
    std::vector<Index> m_node_slots;  // 2 per node: the range of slots (faces) of its subtree
    std::vector<Index> m_task_roots;  // parallel refit: roots of the subtrees refit as tasks
    std::vector<Index> m_order;       // face of each slot, in leaf order
    mutable std::vector<FacePlanes> m_planes; // per node; a cache filled by update_planes
    mutable bool m_planes_current = false;    // m_planes match the positions of the last refit
    std::vector<Index> m_slab_vertex_start;   // #nodes + 1; empty range: no slab (too many faces)
    std::vector<Index> m_slab_vertices;       // distinct vertices of each node's faces
    std::vector<Index> m_slot_vertices; // 3 per slot: the vertices of the face in that slot
    Aabb m_bounds;
    std::vector<Index> m_vertex_order;  // used vertices, first appearance in leaf order
    std::vector<Aabb> m_vertex_blocks;  // box of each VERTEX_BLOCK consecutive m_vertex_order entries
    // Each edge twice, once from either end: the edges of vertex v are k in
    // [m_edge_start[v], m_edge_start[v + 1]), to vertex m_edge_vertex[k], held by the faces in
    // slots m_edge_slots[k] (the same slot twice on a boundary edge). Apart, as the grouping
    // pass reads the slots of few of the edges it scans.
    std::vector<Index> m_edge_start;                // #V + 1
    std::vector<Index> m_edge_vertex;               // 2 × #edges
    std::vector<std::array<Index, 2>> m_edge_slots; // 2 × #edges
    Tris m_faces;
};

namespace detail {
/// `x` rounded to a float no greater (down) or no smaller (up): the nearest float, then a step
/// of at least one ulp outward (a few ulps looser than needed). A value above the float range
/// rounds down to the largest float, one below it up to the lowest (the step from ±∞ would give
/// NaN, which fmin/fmax drop).
inline float float_down(double x)
{
    const float f = static_cast<float>(x);
    return std::fmin(f - (std::abs(f) * 0x1p-23f + 0x1p-126f), std::numeric_limits<float>::max());
}
inline float float_up(double x)
{
    const float f = static_cast<float>(x);
    return std::fmax(f + (std::abs(f) * 0x1p-23f + 0x1p-126f), -std::numeric_limits<float>::max());
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
void AabbTree::faces_on_axis_line(CRef<Positions> vertices, const Vec3& point, int axis, double tolerance,
                                  Visit&& visit) const
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
            const Aabb fb = slot_box(vertices.data(), vertices.outerStride(), slot); // the exact test
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
        push_children(node, mask, gaps, stack, stack_gap, top);
    }
}

namespace detail {
/// Eight floats (one per line of a packet): one AVX register, or two SSE registers without AVX2.
#if defined(__AVX2__)
struct Float8 {
    __m256 x;
    static Float8 load(const float* p) { return {_mm256_load_ps(p)}; }
    static Float8 broadcast(const float* p) { return {_mm256_broadcast_ss(p)}; }
    void store(float* p) const { _mm256_store_ps(p, x); }
    friend Float8 operator-(Float8 a, Float8 b) { return {_mm256_sub_ps(a.x, b.x)}; }
    friend Float8 max(Float8 a, Float8 b) { return {_mm256_max_ps(a.x, b.x)}; }
    friend Float8 operator&(Float8 a, Float8 b) { return {_mm256_and_ps(a.x, b.x)}; }
    friend Float8 le(Float8 a, Float8 b) { return {_mm256_cmp_ps(a.x, b.x, _CMP_LE_OQ)}; }
    friend Float8 ge(Float8 a, Float8 b) { return {_mm256_cmp_ps(a.x, b.x, _CMP_GE_OQ)}; }
    static Float8 zero() { return {_mm256_setzero_ps()}; }
    int mask() const { return _mm256_movemask_ps(x); }
};
#else
struct Float8 {
    __m128 x0, x1;
    static Float8 load(const float* p) { return {_mm_load_ps(p), _mm_load_ps(p + 4)}; }
    static Float8 broadcast(const float* p)
    {
        const __m128 v = _mm_load1_ps(p);
        return {v, v};
    }
    void store(float* p) const
    {
        _mm_store_ps(p, x0);
        _mm_store_ps(p + 4, x1);
    }
    friend Float8 operator-(Float8 a, Float8 b) { return {_mm_sub_ps(a.x0, b.x0), _mm_sub_ps(a.x1, b.x1)}; }
    friend Float8 max(Float8 a, Float8 b) { return {_mm_max_ps(a.x0, b.x0), _mm_max_ps(a.x1, b.x1)}; }
    friend Float8 operator&(Float8 a, Float8 b) { return {_mm_and_ps(a.x0, b.x0), _mm_and_ps(a.x1, b.x1)}; }
    friend Float8 le(Float8 a, Float8 b) { return {_mm_cmple_ps(a.x0, b.x0), _mm_cmple_ps(a.x1, b.x1)}; }
    friend Float8 ge(Float8 a, Float8 b) { return {_mm_cmpge_ps(a.x0, b.x0), _mm_cmpge_ps(a.x1, b.x1)}; }
    static Float8 zero() { return {_mm_setzero_ps(), _mm_setzero_ps()}; }
    int mask() const { return _mm_movemask_ps(x0) | (_mm_movemask_ps(x1) << 4); }
};
#endif
} // namespace detail

template <class Visit>
void AabbTree::faces_on_axis_lines(CRef<Positions> vertices, const Vec3* points, int count, int axis,
                                   double tolerance, Visit&& visit) const
{
    static_assert(AXIS_PACKET == 8, "the packet walk uses 8-float registers");
    if (m_nodes.empty() || count <= 0)
        return;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    // Per line, the same float intervals as faces_on_axis_line; unused lanes copy line 0 and
    // are never active.
    alignas(32) float pu_lo[8], pu_hi[8], pv_lo[8], pv_hi[8], pa_lo[8], pa_hi[8];
    alignas(32) float cutoff_f[8];
    double pu[8], pv[8], cutoff[8];
    for (int q = 0; q < 8; ++q) {
        const Vec3& p = points[q < count ? q : 0];
        pu[q] = p[u];
        pv[q] = p[v];
        pu_lo[q] = detail::float_down(pu[q] - tolerance);
        pu_hi[q] = detail::float_up(pu[q] + tolerance);
        pv_lo[q] = detail::float_down(pv[q] - tolerance);
        pv_hi[q] = detail::float_up(pv[q] + tolerance);
        pa_lo[q] = detail::float_down(p[axis]);
        pa_hi[q] = detail::float_up(p[axis]);
        cutoff[q] = std::numeric_limits<double>::infinity();
        cutoff_f[q] = std::numeric_limits<float>::infinity();
    }
    using detail::Float8;
    const Float8 qu_lo = Float8::load(pu_lo), qu_hi = Float8::load(pu_hi);
    const Float8 qv_lo = Float8::load(pv_lo), qv_hi = Float8::load(pv_hi);
    const Float8 qa_lo = Float8::load(pa_lo), qa_hi = Float8::load(pa_hi);
    const Float8 zero = Float8::zero();

    // Stack entries: a node, the lines that need it, and their gaps to its box.
    Index stack[STACK_SIZE];
    unsigned stack_lines[STACK_SIZE];
    alignas(32) float stack_gap[STACK_SIZE][8];
    int top = 0;
    stack[top] = 0;
    stack_lines[top] = (1u << count) - 1u;
    zero.store(stack_gap[top++]);
    alignas(32) float gaps[4][8];
    unsigned lines[4];
    while (top > 0) {
        --top;
        Float8 cut = Float8::load(cutoff_f);
        const unsigned active =
            stack_lines[top] & static_cast<unsigned>(le(Float8::load(stack_gap[top]), cut).mask());
        if (active == 0)
            continue;
        const WideNode& node = m_nodes[static_cast<std::size_t>(stack[top])];
        for (int k = 0; k < node.count; ++k) {
            const Float8 crossed = (le(Float8::broadcast(&node.lo[u][k]), qu_hi) &
                                    ge(Float8::broadcast(&node.hi[u][k]), qu_lo)) &
                                   (le(Float8::broadcast(&node.lo[v][k]), qv_hi) &
                                    ge(Float8::broadcast(&node.hi[v][k]), qv_lo));
            const Float8 gap = max(max(Float8::broadcast(&node.lo[axis][k]) - qa_hi,
                                       qa_lo - Float8::broadcast(&node.hi[axis][k])),
                                   zero);
            gap.store(gaps[k]);
            lines[k] = active & static_cast<unsigned>((crossed & le(gap, cut)).mask());
        }
        // The node's faces now, in lane order, each for the lines that need it; then its child
        // nodes, pushed farther first (by the gaps of the first line that needs each).
        for (int m = node.face_mask & ((1 << node.count) - 1); m != 0; m &= m - 1) {
            const int k = __builtin_ctz(static_cast<unsigned>(m));
            if (lines[k] == 0)
                continue;
            const std::size_t slot = static_cast<std::size_t>(-1 - node.child[k]);
            const Aabb fb = slot_box(vertices.data(), vertices.outerStride(), slot); // the exact test
            const Index face = m_order[slot];
            for (unsigned l = lines[k]; l != 0; l &= l - 1) {
                const int q = __builtin_ctz(l);
                if (pu[q] < fb.min[u] - tolerance || pu[q] > fb.max[u] + tolerance ||
                    pv[q] < fb.min[v] - tolerance || pv[q] > fb.max[v] + tolerance)
                    continue;
                if (static_cast<double>(gaps[k][q]) > cutoff[q] * (1.0 + 0x1p-20))
                    continue;
                const double limit = static_cast<double>(visit(q, face));
                if (limit < cutoff[q]) {
                    cutoff[q] = limit;
                    cutoff_f[q] = detail::float_threshold(limit);
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
            Float8::load(gaps[far]).store(stack_gap[top++]);
            m &= ~(1 << far);
        }
    }
}

} // namespace coro
