#pragma once
/// @file contact_surface.hpp
/// @brief What contact detection sees of a body: a closed triangle surface, its tree and its
/// edges.

#include <corocontact/contact/aabb_tree.hpp>
#include <corocontact/core/types.hpp>

#include <array>
#include <string>
#include <vector>

namespace coro {

/// The edges of a triangle surface, each listed from both its ends: the edges of vertex v are
/// k in [start[v], start[v + 1]), to vertex `vertex[k]`, held by the faces `faces[k]` (the same
/// face twice on a boundary edge; two of them where more than two faces share an edge). A
/// vertex's edges are ordered by the vertex at their other end.
struct SurfaceEdges {
    std::vector<Index> start;                  ///< #V + 1
    std::vector<Index> vertex;                 ///< 2 × #edges
    std::vector<std::array<Index, 2>> faces;   ///< 2 × #edges
    /// The same faces by their places in the surface's tree (the order of its leaves, in which
    /// neighbouring faces lie close in memory): what the detector's grouping reads. Filled by
    /// ContactSurface when it builds its tree; empty from surface_edges().
    std::vector<std::array<Index, 2>> tree_slots;
};

/// The edges of `faces` (#F×3 into #V = num_vertices vertices); a face with a repeated vertex
/// has no edge between the repeats.
SurfaceEdges surface_edges(const Tris& faces, Index num_vertices);

/// The contact surface of one body (or one static obstacle mesh).
struct ContactSurface {
    std::string name;             ///< body name, for reports
    Positions vertices;           ///< #S×3 current positions of the surface vertices
    Tris faces;                   ///< #F×3 into vertices, outward (counter-clockwise from outside)
    std::vector<Index> body_node; ///< #S: the vertex's row in the body positions given to from_body/update
    std::vector<Index> source_id; ///< #S: the vertex's node index in the body's mesh file (for reports;
                                  ///< from_body sets it to body_node, callers map it to the file order)
    /// Embedded surfaces (coupled meshes): vertex i sits at Σ_k embed_weights[i][k] ·
    /// (body row embed_nodes[i][k]) instead of a body row of its own; empty otherwise.
    std::vector<std::array<Index, 4>> embed_nodes;
    std::vector<Eigen::Vector4d> embed_weights;
    bool closed = true;           ///< closed and consistently oriented (else: winding number only)
    AabbTree tree;                ///< over faces; build() once, refit() after vertices move
    SurfaceEdges edges;           ///< of faces

    /// Builds a surface from a subset of a body's nodes: `faces` index the body's nodes,
    /// are compacted to the vertices they use (ascending node index), and the tree and the
    /// edges are built.
    static ContactSurface from_body(std::string name, CRef<Positions> body_positions, const Tris& faces);

    /// A surface whose vertices follow body nodes through barycentric weights (see
    /// core/embedding.hpp); source_id is the surface file's vertex index.
    static ContactSurface from_embedding(std::string name, CRef<Positions> body_positions, const Tris& faces,
                                         std::vector<std::array<Index, 4>> nodes, std::vector<Eigen::Vector4d> weights);

    /// Copies the body's current node positions into `vertices` (through the weights for an
    /// embedded surface) and refits the tree.
    void update(CRef<Positions> body_positions);

private:
    void update_vertices(CRef<Positions> body_positions); // embedded surfaces
};

/// update() of the first positions.size() surfaces, surface b from positions[b], the surfaces
/// as parallel tasks (a large one's refit is split into tasks of its own as well). With few
/// bodies, updating them one after another leaves cores idle, as a body's refit splits well
/// only from some thousands of faces. The result does not depend on the thread count.
/// @param[in] positions  per surface, the #N×3 body node positions update() takes; at most
///                       surfaces.size() of them (InputError otherwise)
void update_surfaces(std::vector<ContactSurface>& surfaces, const std::vector<Eigen::Map<const Positions>>& positions);
/// The same with positions held as matrices.
void update_surfaces(std::vector<ContactSurface>& surfaces, const std::vector<Positions>& positions);

} // namespace coro
