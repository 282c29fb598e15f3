#pragma once
/// @file tet_mesh.hpp
/// @brief A tetrahedral mesh: rest positions and tets, plus load-time validation.

#include <corocontact/core/types.hpp>

#include <string>
#include <vector>

namespace coro {

/// A linear tetrahedral mesh in its rest configuration.
struct TetMesh {
    Positions rest_positions; ///< #V×3 node coordinates (length unit of the case).
    Tets tets;                ///< #T×4 node indices, positive orientation after orient_tets().

    Index num_vertices() const { return static_cast<Index>(rest_positions.rows()); }
    Index num_tets() const { return static_cast<Index>(tets.rows()); }
};

/// Signed volume det([x1−x0, x2−x0, x3−x0])/6 of one tet.
double signed_volume(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3);

/// Signed volume of tet `t` of `mesh`.
double signed_volume(const TetMesh& mesh, Index t);

/// Sum of the tets' volumes.
double total_volume(const TetMesh& mesh);

/// Validates a freshly read mesh and makes every tet positively oriented.
///
/// Checks: at least one tet, finite coordinates, indices in range, no node repeated within
/// a tet, volume above a relative threshold (1e-12 × the mean edge length cubed).
/// Negative-volume tets are reoriented (swap of nodes 2 and 3).
/// @param[in,out] mesh  the mesh, reoriented in place
/// @param[in] source    name of the input (file or body) used in messages
/// @return the number of tets that were reoriented (callers warn when it is > 0)
/// @throws InputError naming `source` and the element when a check fails
Index validate_and_orient(TetMesh& mesh, const std::string& source);

/// Mean-ratio quality of tet `t`: 12 (3V)^(2/3) / Σ edge², 1 for a regular tet, → 0 for a
/// degenerate one, negative for an inverted one.
double mean_ratio_quality(const TetMesh& mesh, Index t);

/// Nodes referenced by no tet (they carry no stiffness and no mass).
std::vector<Index> unreferenced_vertices(const TetMesh& mesh);

} // namespace coro
