#pragma once
/// @file aabb_tree.hpp
/// @brief Bounding-volume hierarchy of a triangle surface: built once (the topology never
/// changes), refit bottom-up each step (DESIGN.md, Contact detection: hierarchical AABBs).

#include <corocontact/contact/aabb.hpp>

#include <algorithm>
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

    /// Builds the hierarchy over `faces` at `vertices` (median split of the face centroids
    /// along the longest axis, at most MAX_LEAF_FACES faces per leaf).
    /// @param[in] vertices  #V×3 positions
    /// @param[in] faces     #F×3 indices into vertices; the tree stores its own copy of the face
    ///                      list, so `faces` may go away after the call
    void build(CRef<Positions> vertices, const Tris& faces);

    /// Recomputes every box bottom-up for new positions of the same vertices (in parallel, level
    /// by level, for large trees; every box is a pure function of its children, so the result
    /// does not depend on the thread count).
    void refit(CRef<Positions> vertices);

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
    /// smallest value returned so far from `point` along the axis are skipped. Children are
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
    /// boxes, nearer child first; of equally near faces the first one met wins (deterministic).
    /// @param[in] vertices  the positions the tree was last built or refit with
    /// @return face −1 for an empty tree
    Nearest nearest(CRef<Positions> vertices, const Vec3& point) const;

    /// The same answer as nearest(vertices, point), bit for bit, found faster from hints that
    /// bound the distance from above: the search starts with that bound instead of +∞, so it
    /// skips the subtrees that cannot hold the answer. The bound is slightly inflated (relative
    /// 10⁻⁶ on the squared distance) before use, so faces tied with the nearest one are still
    /// visited in the same order and the same one wins.
    /// @param[in] distance_bound  a distance that some point of the surface is known to be within
    ///                            (e.g. a face crossing of an axis line through `point`, plus its
    ///                            rounding bound); +∞ for none
    /// @param[in] hint_face       a face likely near `point` (e.g. the previous query's answer),
    ///                            −1 for none; any valid face is correct, a near one is faster
    Nearest nearest(CRef<Positions> vertices, const Vec3& point, double distance_bound, Index hint_face) const;

    static constexpr Index MAX_LEAF_FACES = 4;
    static constexpr Index VERTEX_BLOCK = 32; ///< vertices per box of the vertex query

private:
    struct Node {
        Aabb box;
        Index left = -1;   ///< child node, or −1 for a leaf
        Index right = -1;
        Index begin = 0;   ///< leaf: range in m_order
        Index end = 0;
    };
    /// Traversal copy of a node in single precision, rounded outward (so it bounds the exact
    /// box); siblings sit next to each other, a pair in one cache line.
    struct alignas(32) PackedNode {
        float min[3];
        float max[3];
        Index link;  ///< internal: packed index of the left child (the right one follows);
                     ///< leaf: first slot in m_order
        Index count; ///< leaf: number of faces (> 0); internal: 0
    };
    struct PackedBox {
        float min[3];
        float max[3];
    };
    void refit_node(CRef<Positions> vertices, Index n);
    static void pack(const Aabb& box, float* min, float* max);

    std::vector<Node> m_nodes;      // root at 0; children after their parent
    std::vector<Index> m_order;     // faces in leaf order
    std::vector<Aabb> m_face_boxes; // box of face m_order[i], refit with the nodes
    std::vector<Index> m_levels;    // nodes grouped by height (leaves first) for the parallel refit
    std::vector<Index> m_level_offsets;
    std::vector<PackedNode> m_packed;   // root at 0, slot 1 unused, sibling pairs from 2 on
    std::vector<Index> m_packed_of;     // m_nodes index → m_packed index
    std::vector<PackedBox> m_packed_faces; // m_face_boxes rounded outward to float
    std::vector<Index> m_vertex_order;  // used vertices, first appearance in leaf order
    std::vector<Aabb> m_vertex_blocks;  // box of each VERTEX_BLOCK consecutive m_vertex_order entries
    Tris m_faces;
};

template <class Visit>
void AabbTree::faces_on_axis_line(const Vec3& point, int axis, double tolerance, Visit&& visit) const
{
    if (m_packed.empty())
        return;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double pu = point[u], pv = point[v], pa = point[axis];
    // Branch-free tests: their outcomes are hard to predict. Single precision boxes are rounded
    // outward, so they never reject what the exact box would accept.
    const auto crossed = [&](const float* lo, const float* hi) {
        return (pu >= lo[u] - tolerance) & (pu <= hi[u] + tolerance) & (pv >= lo[v] - tolerance) &
               (pv <= hi[v] + tolerance);
    };
    const auto gap = [&](const float* lo, const float* hi) {
        return std::max(std::max(static_cast<double>(lo[axis]) - pa, pa - static_cast<double>(hi[axis])), 0.0);
    };
    const PackedNode& root = m_packed.front();
    if (!crossed(root.min, root.max))
        return;
    double cutoff = std::numeric_limits<double>::infinity();
    // Only nodes whose box the line crosses are pushed, with their distance along the axis.
    Index stack[96];
    double stack_gap[96];
    int top = 0;
    stack[top] = 0;
    stack_gap[top++] = gap(root.min, root.max);
    while (top > 0) {
        --top;
        if (stack_gap[top] > cutoff)
            continue;
        const PackedNode& node = m_packed[static_cast<std::size_t>(stack[top])];
        if (node.count > 0) {
            for (Index i = node.link; i < node.link + node.count; ++i) {
                const PackedBox& pb = m_packed_faces[static_cast<std::size_t>(i)];
                if (!crossed(pb.min, pb.max) || gap(pb.min, pb.max) > cutoff)
                    continue;
                const Aabb& fb = m_face_boxes[static_cast<std::size_t>(i)]; // the exact test
                if (pu < fb.min[u] - tolerance || pu > fb.max[u] + tolerance || pv < fb.min[v] - tolerance ||
                    pv > fb.max[v] + tolerance)
                    continue;
                const Index face = m_order[static_cast<std::size_t>(i)];
                if constexpr (std::is_void_v<decltype(visit(face))>)
                    visit(face);
                else
                    cutoff = std::min(cutoff, static_cast<double>(visit(face)));
            }
            continue;
        }
        const PackedNode& l = m_packed[static_cast<std::size_t>(node.link)];
        const PackedNode& r = m_packed[static_cast<std::size_t>(node.link) + 1];
        const bool cl = crossed(l.min, l.max), cr = crossed(r.min, r.max);
        const double gl = gap(l.min, l.max), gr = gap(r.min, r.max);
        // Farther child first, the nearer one on top; a child the line misses is written, not kept.
        const bool left_near = gl <= gr;
        stack[top] = left_near ? node.link + 1 : node.link;
        stack_gap[top] = left_near ? gr : gl;
        top += left_near ? cr : cl;
        stack[top] = left_near ? node.link : node.link + 1;
        stack_gap[top] = left_near ? gl : gr;
        top += left_near ? cl : cr;
    }
}

} // namespace coro
