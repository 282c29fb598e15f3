#pragma once
/// @file surface_mesh.hpp
/// @brief Triangle surfaces and the extraction of a tet mesh's boundary.

#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/core/types.hpp>

#include <vector>

namespace coro {

/// A triangulated surface.
struct SurfaceMesh {
    Positions vertices; ///< #V×3 vertex coordinates.
    Tris faces;         ///< #F×3 vertex indices, counter-clockwise seen from outside.
};

/// Boundary faces of a tet mesh: the faces that belong to exactly one tet, oriented so that
/// their normal (x1−x0)×(x2−x0) points out of that tet.
/// @param[in] mesh  positively oriented tets (see validate_and_orient)
/// @return #F×3 indices into mesh.rest_positions, sorted by (tet, local face)
Tris boundary_faces(const TetMesh& mesh);

/// The distinct vertices used by `faces`, ascending.
std::vector<Index> surface_vertices(const Tris& faces);

/// Result of checking that a surface is closed and consistently oriented.
struct SurfaceCheck {
    Index open_edges = 0;      ///< edges used by one face only
    Index nonmanifold_edges = 0; ///< edges used by more than two faces
    Index misoriented_edges = 0; ///< edges traversed in the same direction by both faces
    bool closed_and_oriented() const
    {
        return open_edges == 0 && nonmanifold_edges == 0 && misoriented_edges == 0;
    }
};

/// Counts open, non-manifold and inconsistently oriented edges of a triangle set.
SurfaceCheck check_surface(const Tris& faces);

/// Signed volume enclosed by a closed surface (positive when its normals point outward), summed
/// about a vertex of the surface, so that its rounding scales with the body's size and not with
/// its distance from the origin.
double enclosed_volume(CRef<Positions> vertices, const Tris& faces);

} // namespace coro
