#include "contact_scenes.hpp"

#include <corocontact/contact/winding_number.hpp>
#include <corocontact/core/primitives.hpp>

#include <gtest/gtest.h>

using namespace coro;
using namespace coro::test;

TEST(WindingNumber, OneInsideZeroOutsideAClosedBox)
{
    const TetMesh box = make_box(Vec3(0, 0, 0), Vec3(1, 2, 1), {2, 3, 2});
    const Tris faces = boundary_faces(box);
    EXPECT_NEAR(winding_number(box.rest_positions, faces, Vec3(0.3, 1.1, 0.7)), 1.0, 1e-12);
    EXPECT_NEAR(winding_number(box.rest_positions, faces, Vec3(1.3, 1.1, 0.7)), 0.0, 1e-12);
    EXPECT_NEAR(winding_number(box.rest_positions, faces, Vec3(-5, 7, 9)), 0.0, 1e-12);
    // Reversed orientation: −1 inside.
    const Tris reversed = faces.rowwise().reverse();
    EXPECT_NEAR(winding_number(box.rest_positions, reversed, Vec3(0.3, 1.1, 0.7)), -1.0, 1e-12);
}

TEST(WindingNumber, TorusHoleIsOutsideTubeIsInside)
{
    const SurfaceMesh torus = make_torus(Vec3(1, 2, 3), 1.0, 0.3, 40, 20);
    EXPECT_NEAR(winding_number(torus.vertices, torus.faces, Vec3(1, 2, 3)), 0.0, 1e-12);
    EXPECT_NEAR(winding_number(torus.vertices, torus.faces, Vec3(2, 2, 3)), 1.0, 1e-12);
    EXPECT_NEAR(winding_number(torus.vertices, torus.faces, Vec3(1, 3.1, 3.1)), 1.0, 1e-12);
    EXPECT_NEAR(winding_number(torus.vertices, torus.faces, Vec3(1, 2, 3.5)), 0.0, 1e-12);
}

TEST(WindingNumber, OpenSurfaceVariesSmoothly)
{
    // One face of a cube alone: about 1/6 at the cube's centre.
    Positions v(4, 3);
    v << 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1;
    Tris f(2, 3);
    f << 0, 1, 2, 0, 2, 3;
    EXPECT_NEAR(winding_number(v, f, Vec3(0.5, 0.5, 0.5)), 1.0 / 6.0, 1e-12);
}
