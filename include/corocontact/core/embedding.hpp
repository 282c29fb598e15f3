#pragma once
/// @file embedding.hpp
/// @brief Points bound to a tet mesh by barycentric coordinates (the coupled meshes of the
/// paper, §4): each point follows the tet that contains it.

#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/core/types.hpp>

#include <array>
#include <vector>

namespace coro {

/// For every point: the 4 nodes of its tet and its barycentric weights (they sum to 1 and
/// reproduce the point: Σ w_k X_k = p, also for a point slightly outside its tet, where a
/// weight is negative).
struct Embedding {
    std::vector<std::array<Index, 4>> nodes;
    std::vector<Eigen::Vector4d> weights;

    Index num_points() const { return static_cast<Index>(nodes.size()); }
};

/// Binds each point to the tet containing it, or, for a point outside the mesh, to the tet in
/// which it is least outside (the largest smallest barycentric weight).
/// @param[in] mesh    positively oriented tets
/// @param[in] points  #P×3, in the mesh's coordinates
Embedding embed_points(const TetMesh& mesh, CRef<Positions> points);

/// Current positions of the embedded points for node positions `nodes` (#V×3): #P×3.
Positions embedded_positions(const Embedding& embedding, CRef<Positions> nodes);

} // namespace coro
