#pragma once
/// @file surface_topology.hpp
/// @brief Counts, connected pieces, Euler characteristic and genus of a triangle surface.

#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/core/types.hpp>

namespace coro {

/// What `corocontact info` reports about a surface's topology.
struct SurfaceTopology {
    Index vertices = 0;             ///< distinct vertices used by the faces (unused ones not counted)
    Index edges = 0;                ///< distinct undirected edges
    Index faces = 0;                ///< triangles
    Index components = 0;           ///< pieces connected through shared edges
    Index nonmanifold_vertices = 0; ///< vertices whose faces form more than one fan (pinch points)
    SurfaceCheck edge_check;        ///< open, non-manifold and misoriented edges

    /// χ = V − E + F.
    Index euler_characteristic() const { return vertices - edges + faces; }

    /// Closed (every edge in exactly two faces), consistently oriented, no pinch points: a
    /// closed orientable 2-manifold, for which genus() is defined.
    bool closed_oriented_manifold() const
    {
        return edge_check.closed_and_oriented() && nonmanifold_vertices == 0;
    }

    /// Sum of the genera (handles) of the components, from χ = Σ (2 − 2 g_i) = 2·components −
    /// 2·genus (a sphere 0, a torus 1); −1 when the surface is not closed_oriented_manifold().
    Index genus() const
    {
        return closed_oriented_manifold() ? (2 * components - euler_characteristic()) / 2 : -1;
    }
};

/// The topology of a triangle set.
/// @param[in] faces  #F×3 vertex indices ≥ 0 (faces that repeat a vertex are not expected)
SurfaceTopology surface_topology(const Tris& faces);

} // namespace coro
