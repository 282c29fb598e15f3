#pragma once
/// @file aabb_tree.hpp
/// @brief Bounding-volume hierarchy of a triangle surface: built once (the topology never
/// changes), refit bottom-up each step (DESIGN.md, Contact detection: hierarchical AABBs).

#include <corocontact/contact/aabb.hpp>
#include <corocontact/contact/closest_point.hpp>

#include <array>
#include <vector>

namespace coro {

namespace detail {
struct TreeAccess;
}

/// A BVH over the faces of a triangle surface. The tree keeps the face list (in its own order)
/// but not the positions: every query takes the positions the tree was last built or refit
/// with. Queries are const and may run concurrently.
class AabbTree {
public:
    AabbTree() = default;

    /// Builds the hierarchy over `faces` at `vertices`: four children per node but at most one
    /// node per level with fewer (splits of the face centroids along the longest axis, at the
    /// median rounded to whole full subtrees of 1, 4, 16, … faces), about #F/3 nodes.
    /// @param[in] vertices  #V×3 positions
    /// @param[in] faces     #F×3 indices into vertices (copied: `faces` may go away after the call)
    /// @throws InputError for a face index out of range; NumericalError for a degenerate split
    ///         deeper than the walks' stacks allow
    void build(CRef<Positions> vertices, const Tris& faces);

    /// Recomputes every box bottom-up for new positions of the same vertices, large trees as
    /// parallel tasks; each box is a pure function of its children, so the result does not
    /// depend on the thread count. No allocation.
    /// @param[in] vertices  #V×3, the same vertices as at build()
    void refit(CRef<Positions> vertices);

    /// Box of the whole surface: exactly the box of the vertices its faces use (empty for an
    /// empty tree).
    const Aabb& bounds() const { return m_bounds; }
    Index num_faces() const { return static_cast<Index>(m_face_of_slot.size()); }

    /// Faces whose box overlaps `box` (closed intervals), ascending.
    void faces_overlapping(CRef<Positions> vertices, const Aabb& box, std::vector<Index>& out) const;

    /// Vertices used by the faces that lie in `box` (closed), in the tree's spatial order
    /// (neighbours close together, good for the cache of a following query loop), not ascending.
    void vertices_in_box(CRef<Positions> vertices, const Aabb& box, std::vector<Index>& out) const;

    /// Pairs (face of this tree, face of `other`) whose boxes overlap each other and both meet
    /// `region`, found by walking the two trees together (large trees: from node pairs a few
    /// levels down, as parallel tasks). The boxes are the trees' single precision boxes, rounded
    /// outward: every pair of faces whose exact boxes overlap is listed, and a few whose exact
    /// boxes miss by less than float rounding may be too.
    /// @param[out] pairs  each pair once, in an order that depends only on the two trees
    void overlapping_faces(const AabbTree& other, const Aabb& region, std::vector<std::array<Index, 2>>& pairs) const;

    /// The nearest point of the surface to `point`: the minimum over all faces of
    /// (squared distance by closest_point_on_triangle, face index), so of equally near faces
    /// the smallest index wins and the answer does not depend on the traversal. Branch and
    /// bound over the boxes; the detector's searches also prune by face planes
    /// (detail::NearestSearch), with the same answer.
    /// @return face −1 for an empty tree
    NearestPoint nearest(CRef<Positions> vertices, const Vec3& point) const;

private:
    friend struct detail::TreeAccess;

    /// Up to four children with their boxes in single precision, rounded outward (so they bound
    /// the exact boxes), as structure of arrays: one 4-lane register per coordinate bound.
    struct alignas(64) Node {
        float lo[3][4];  ///< [coordinate][child] box minimum
        float hi[3][4];  ///< [coordinate][child] box maximum
        Index child[4];  ///< ≥ 0: a node; < 0: the face in slot −1 − child
        Index count;     ///< children used, lanes 0 .. count − 1 (2..4; 1 for a one-face tree)
        Index face_mask; ///< bit k set: child k is a face
    };
    /// A node's own box (the union of its lanes), x, y, z and an unused fourth entry.
    struct alignas(16) NodeBox {
        float lo[4];
        float hi[4];
    };

    static constexpr int MAX_DEPTH = 60;
    Index build_node(const std::vector<Vec3>& centroids, Index begin, Index end, int depth);
    void build_slabs(CRef<Positions> vertices);
    void refit_range(const double* data, std::ptrdiff_t stride, Index first, Index last);
    void refit_node(const double* data, std::ptrdiff_t stride, Index n);
    void refit_vertex_blocks(const double* data, std::ptrdiff_t stride, std::size_t first, std::size_t last);

    // The faces are held in "slots", their order in the tree's leaves: a subtree's faces are
    // a contiguous range of slots, so walks read their corners from nearby memory.
    std::vector<Node> m_nodes;           // root at 0; every subtree is a contiguous range after its root
    std::vector<NodeBox> m_node_boxes;   // per node
    std::vector<Index> m_subtree_end;    // per node: one past the last node of its subtree
    std::vector<Index> m_node_slots;     // 2 per node: its subtree's range of slots
    std::vector<Index> m_task_roots;     // parallel refit: the subtrees refit as tasks
    std::vector<Index> m_face_of_slot;   // per slot: the face (index into the build's faces)
    std::vector<Index> m_slot_vertices;  // 3 per slot: that face's vertices
    std::vector<Index> m_vertex_order;   // used vertices, by first appearance in slot order
    std::vector<Aabb> m_vertex_blocks;   // box of each VERTEX_BLOCK consecutive m_vertex_order entries
    // Per node of at most SLAB_MAX_FACES faces: its distinct vertices and three of them spanning
    // it (at build), whose normal is the direction of the node's slab (detail/face_planes.hpp).
    std::vector<Index> m_slab_start;     // #nodes + 1; an empty range: no slab
    std::vector<Index> m_slab_vertices;
    std::vector<std::array<Index, 3>> m_slab_corners;
    Aabb m_bounds;
};

} // namespace coro
