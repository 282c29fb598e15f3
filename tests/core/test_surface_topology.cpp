#include <corocontact/core/primitives.hpp>
#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/core/surface_topology.hpp>

#include <gtest/gtest.h>

using namespace coro;

namespace {

/// A torus as an n × m grid of quads, two triangles each, wrapped both ways; vertex indices
/// start at `first`. V = nm, E = 3nm, F = 2nm: χ = 0.
Tris torus_faces(Index n, Index m, Index first = 0)
{
    Tris faces(2 * n * m, 3);
    const auto v = [&](Index i, Index j) { return first + (i % n) * m + (j % m); };
    Index f = 0;
    for (Index i = 0; i < n; ++i)
        for (Index j = 0; j < m; ++j) {
            faces.row(f++) << v(i, j), v(i + 1, j), v(i + 1, j + 1);
            faces.row(f++) << v(i, j), v(i + 1, j + 1), v(i, j + 1);
        }
    return faces;
}

Tris stacked(const Tris& a, const Tris& b)
{
    Tris both(a.rows() + b.rows(), 3);
    both << a, b;
    return both;
}

} // namespace

TEST(SurfaceTopology, SphereBoundaryIsOneClosedPieceOfGenusZero)
{
    const Tris faces = boundary_faces(make_sphere(Vec3::Zero(), 1.0, 6));
    const SurfaceTopology topology = surface_topology(faces);
    EXPECT_EQ(topology.faces, faces.rows());
    EXPECT_EQ(topology.vertices, static_cast<Index>(surface_vertices(faces).size()));
    EXPECT_EQ(2 * topology.edges, 3 * topology.faces); // closed: every edge in two faces
    EXPECT_EQ(topology.components, 1);
    EXPECT_EQ(topology.euler_characteristic(), 2);
    EXPECT_TRUE(topology.closed_oriented_manifold());
    EXPECT_EQ(topology.genus(), 0);
}

TEST(SurfaceTopology, TorusHasGenusOne)
{
    const SurfaceTopology topology = surface_topology(torus_faces(8, 5));
    EXPECT_EQ(topology.vertices, 40);
    EXPECT_EQ(topology.edges, 120);
    EXPECT_EQ(topology.faces, 80);
    EXPECT_EQ(topology.euler_characteristic(), 0);
    EXPECT_EQ(topology.genus(), 1);
}

TEST(SurfaceTopology, GenusAddsOverSeparatePieces)
{
    const Tris box = boundary_faces(make_box(Vec3::Zero(), Vec3::Ones(), {2, 1, 1}));
    const Index box_vertices = box.maxCoeff() + 1;
    const Tris faces = stacked(stacked(box, torus_faces(6, 4, box_vertices)), torus_faces(5, 3, box_vertices + 24));
    const SurfaceTopology topology = surface_topology(faces);
    EXPECT_EQ(topology.components, 3);
    EXPECT_EQ(topology.euler_characteristic(), 2 + 0 + 0);
    EXPECT_EQ(topology.genus(), 2);
}

TEST(SurfaceTopology, OpenSurfaceHasNoGenus)
{
    Tris faces(2, 3);
    faces << 0, 1, 2, 0, 2, 3; // a square
    const SurfaceTopology topology = surface_topology(faces);
    EXPECT_EQ(topology.vertices, 4);
    EXPECT_EQ(topology.edges, 5);
    EXPECT_EQ(topology.euler_characteristic(), 1); // a disc
    EXPECT_EQ(topology.edge_check.open_edges, 4);
    EXPECT_FALSE(topology.closed_oriented_manifold());
    EXPECT_EQ(topology.genus(), -1);
}

TEST(SurfaceTopology, TwoTetSurfacesSharingOneVertexHaveAPinchPoint)
{
    // Tets {0,1,2,3} and {3,4,5,6} touch at vertex 3: every edge is in two faces, but vertex 3
    // has two fans, so this is no 2-manifold (χ = 3 would give genus −1/2).
    TetMesh mesh;
    mesh.rest_positions.resize(7, 3);
    mesh.rest_positions << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1, 0, 0, 2;
    mesh.tets.resize(2, 4);
    mesh.tets << 0, 1, 2, 3, 3, 4, 5, 6;
    const SurfaceTopology topology = surface_topology(boundary_faces(mesh));
    EXPECT_TRUE(topology.edge_check.closed_and_oriented());
    EXPECT_EQ(topology.nonmanifold_vertices, 1);
    EXPECT_EQ(topology.components, 2);
    EXPECT_EQ(topology.euler_characteristic(), 3);
    EXPECT_EQ(topology.genus(), -1);
}

TEST(SurfaceTopology, FlippedFaceMakesTheSurfaceUnoriented)
{
    Tris faces = torus_faces(4, 4);
    faces.row(3) = faces.row(3).reverse().eval();
    const SurfaceTopology topology = surface_topology(faces);
    EXPECT_EQ(topology.edge_check.misoriented_edges, 3);
    EXPECT_EQ(topology.genus(), -1);
}
