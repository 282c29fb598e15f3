#pragma once
/// @file aabb_tree.hpp
/// @brief Bounding-volume hierarchy of a triangle surface: built once (the topology never
/// changes), refit bottom-up each step.

#include <corocontact/contact/aabb.hpp>

#include <functional>
#include <vector>

namespace coro {

class AabbTree {
public:
    AabbTree() = default;

    /// Builds the hierarchy over `faces` at `vertices` (median split along the longest axis,
    /// a few faces per leaf).
    /// @param[in] vertices  #V×3 positions
    /// @param[in] faces     #F×3 indices into vertices; kept by reference semantics: the tree
    ///                      stores its own copy of the face list
    void build(CRef<Positions> vertices, const Tris& faces);

    /// Recomputes every box bottom-up for new positions of the same vertices (in parallel for
    /// large trees; deterministic).
    void refit(CRef<Positions> vertices);

    /// Box of the whole surface (empty for an empty tree).
    const Aabb& bounds() const;
    Index num_faces() const { return static_cast<Index>(m_faces.rows()); }
    const Tris& faces() const { return m_faces; }

    /// Faces whose box overlaps `box`, ascending.
    void faces_overlapping(const Aabb& box, std::vector<Index>& out) const;

    /// Calls `visit(face)` for every face whose box is crossed by the axis-parallel line
    /// through `point` along `axis` (0 = x, 1 = y, 2 = z), i.e. whose box contains `point`
    /// in the two other coordinates (within `tolerance`).
    void faces_on_axis_line(const Vec3& point, int axis, double tolerance,
                            const std::function<void(Index)>& visit) const;

    /// Nearest point of the surface to `point`.
    struct Nearest {
        Index face = -1;
        Vec3 point = Vec3::Zero();       ///< closest point on that face
        Vec3 barycentric = Vec3::Zero(); ///< its weights on the face's 3 vertices
        double distance = 0.0;
    };
    /// @param[in] vertices  the positions the tree was last built or refit with
    Nearest nearest(CRef<Positions> vertices, const Vec3& point) const;

private:
    struct Node {
        Aabb box;
        Index left = -1;   ///< child node, or −1 for a leaf
        Index right = -1;
        Index begin = 0;   ///< leaf: range in m_order
        Index end = 0;
    };
    std::vector<Node> m_nodes;      // root at 0
    std::vector<Index> m_order;     // faces in leaf order
    std::vector<Index> m_levels;    // nodes grouped bottom-up for the parallel refit
    std::vector<Index> m_level_offsets;
    Tris m_faces;
};

} // namespace coro
