#include "mesh_fixtures.hpp"

#include <corocontact/core/primitives.hpp>
#include <corocontact/core/surface_mesh.hpp>

#include <gtest/gtest.h>

using namespace coro;

TEST(BoundaryFaces, UnitTetHasFourOutwardFaces)
{
    const TetMesh mesh = test::unit_tet();
    const Tris faces = boundary_faces(mesh);
    ASSERT_EQ(faces.rows(), 4);
    const Vec3 centroid = mesh.rest_positions.colwise().mean().transpose();
    for (Index f = 0; f < faces.rows(); ++f) {
        const Vec3 a = mesh.rest_positions.row(faces(f, 0)).transpose();
        const Vec3 b = mesh.rest_positions.row(faces(f, 1)).transpose();
        const Vec3 c = mesh.rest_positions.row(faces(f, 2)).transpose();
        EXPECT_GT((b - a).cross(c - a).dot((a + b + c) / 3.0 - centroid), 0.0) << "face " << f;
    }
}

TEST(BoundaryFaces, BoxSurfaceIsClosedOrientedAndEnclosesTheVolume)
{
    const TetMesh mesh = make_box(Vec3(-1, 0, 2), Vec3(2, 1, 4), {3, 2, 4});
    const Tris faces = boundary_faces(mesh);
    // 2 triangles per boundary cell face.
    EXPECT_EQ(faces.rows(), 2 * 2 * (3 * 2 + 2 * 4 + 3 * 4));
    EXPECT_TRUE(check_surface(faces).closed_and_oriented());
    EXPECT_NEAR(enclosed_volume(mesh.rest_positions, faces), 3.0 * 1.0 * 2.0, 1e-12);
    // Interior nodes of the grid are not on the surface: (3+1)(2+1)(4+1) − (2·1·3).
    EXPECT_EQ(surface_vertices(faces).size(), 60u - 6u);
}

TEST(CheckSurface, CountsOpenAndMisorientedEdges)
{
    Tris faces(2, 3);
    faces << 0, 1, 2, 0, 2, 3; // consistent pair, open border
    SurfaceCheck check = check_surface(faces);
    EXPECT_EQ(check.open_edges, 4);
    EXPECT_EQ(check.misoriented_edges, 0);
    faces.row(1) << 0, 3, 2; // flipped: shared edge 0-2 now runs the same way twice
    check = check_surface(faces);
    EXPECT_EQ(check.misoriented_edges, 1);
    EXPECT_FALSE(check.closed_and_oriented());
}
