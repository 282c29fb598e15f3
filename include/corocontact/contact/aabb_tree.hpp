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
    void refit_node(CRef<Positions> vertices, Index n);

    std::vector<Node> m_nodes;      // root at 0, depth-first preorder
    std::vector<Index> m_order;     // faces in leaf order
    std::vector<Index> m_levels;    // nodes grouped by height (leaves first) for the parallel refit
    std::vector<Index> m_level_offsets;
    std::vector<Index> m_vertex_order;  // used vertices, first appearance in leaf order
    std::vector<Aabb> m_vertex_blocks;  // box of each VERTEX_BLOCK consecutive m_vertex_order entries
    Tris m_faces;
};

template <class Visit>
void AabbTree::faces_on_axis_line(const Vec3& point, int axis, double tolerance, Visit&& visit) const
{
    if (m_nodes.empty())
        return;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double pu = point[u], pv = point[v], pa = point[axis];
    double cutoff = std::numeric_limits<double>::infinity();
    const auto gap = [&](const Aabb& b) { return std::max({b.min[axis] - pa, pa - b.max[axis], 0.0}); };
    Index stack[96];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& node = m_nodes[static_cast<std::size_t>(stack[--top])];
        const Aabb& b = node.box;
        if (pu < b.min[u] - tolerance || pu > b.max[u] + tolerance || pv < b.min[v] - tolerance ||
            pv > b.max[v] + tolerance || gap(b) > cutoff)
            continue;
        if (node.left < 0) {
            for (Index i = node.begin; i < node.end; ++i) {
                const Index face = m_order[static_cast<std::size_t>(i)];
                if constexpr (std::is_void_v<decltype(visit(face))>)
                    visit(face);
                else
                    cutoff = std::min(cutoff, static_cast<double>(visit(face)));
            }
            continue;
        }
        const double gl = gap(m_nodes[static_cast<std::size_t>(node.left)].box);
        const double gr = gap(m_nodes[static_cast<std::size_t>(node.right)].box);
        if (gl <= gr) { // nearer child on top of the stack
            stack[top++] = node.right;
            stack[top++] = node.left;
        } else {
            stack[top++] = node.left;
            stack[top++] = node.right;
        }
    }
}

} // namespace coro
