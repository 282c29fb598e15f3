#include "mesh_fixtures.hpp"

#include <corocontact/core/primitives.hpp>
#include <corocontact/core/surface_mesh.hpp>

#include <gtest/gtest.h>

#include <cmath>

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

TEST(EnclosedVolume, StaysAccurateForABodyFarFromTheOrigin)
{
    // A unit cube moved by 2^e·(1, −3, 1/2) (every coordinate exact). Summed about the origin,
    // the rounding of each term (~eps·|x|³) gave 1 + 9e-11 at e = 20 and −2.0e8 at e = 27: the
    // sign flipped, and correctly oriented meshes were turned inside out at load.
    const TetMesh cube = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1), {1, 1, 1});
    const Tris faces = boundary_faces(cube);
    for (int e : {0, 20, 27, 30, 40}) {
        const Vec3 shift = std::ldexp(1.0, e) * Vec3(1.0, -3.0, 0.5);
        const Positions moved = cube.rest_positions.rowwise() + shift.transpose();
        EXPECT_NEAR(enclosed_volume(moved, faces), 1.0, 1e-12) << "shift 2^" << e;
        Tris inward = faces;
        inward.col(1).swap(inward.col(2));
        EXPECT_NEAR(enclosed_volume(moved, inward), -1.0, 1e-12) << "shift 2^" << e;
    }
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
