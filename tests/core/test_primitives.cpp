#include "near.hpp"

#include <corocontact/core/error.hpp>
#include <corocontact/core/primitives.hpp>
#include <corocontact/core/surface_mesh.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

using namespace coro;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

TEST(MakeBox, SixPositiveTetsPerCellFillingTheBox)
{
    const TetMesh mesh = make_box(Vec3(0, 0, 0), Vec3(2, 3, 1), {2, 3, 4});
    EXPECT_EQ(mesh.num_tets(), 6 * 2 * 3 * 4);
    EXPECT_EQ(mesh.num_vertices(), 3 * 4 * 5);
    for (Index t = 0; t < mesh.num_tets(); ++t)
        ASSERT_NEAR(signed_volume(mesh, t), 6.0 / mesh.num_tets(), 1e-12) << "tet " << t;
    TetMesh copy = mesh;
    EXPECT_EQ(validate_and_orient(copy, "box"), 0);
}

TEST(MakeBox, RejectsBadCellsAndEmptyBox)
{
    EXPECT_THAT([] { make_box(Vec3::Zero(), Vec3::Ones(), {1, 0, 1}); },
                ThrowsMessage<InputError>(HasSubstr("cells[1] = 0")));
    EXPECT_THAT([] { make_box(Vec3::Zero(), Vec3(1, 1, 0), {1, 1, 1}); },
                ThrowsMessage<InputError>(HasSubstr("min[2]")));
}

TEST(MakeSphere, PositiveTetsAndVolumeConvergesToBall)
{
    double previous_error = 1.0;
    for (const Index resolution : {4, 8, 16}) {
        TetMesh mesh = make_sphere(Vec3(1, 2, 3), 0.5, resolution);
        EXPECT_EQ(validate_and_orient(mesh, "sphere"), 0) << "resolution " << resolution;
        const double exact = 4.0 / 3.0 * M_PI * 0.125;
        const double error = std::abs(total_volume(mesh) - exact) / exact;
        EXPECT_LT(error, previous_error) << "resolution " << resolution;
        previous_error = error;
        const Tris faces = boundary_faces(mesh);
        EXPECT_TRUE(check_surface(faces).closed_and_oriented());
        for (const Index v : surface_vertices(faces))
            ASSERT_NEAR((mesh.rest_positions.row(v) - Eigen::RowVector3d(1, 2, 3)).norm(), 0.5, 1e-12);
    }
    EXPECT_LT(previous_error, 0.01);
}

TEST(BodyTransform, ScalesRotatesThenTranslates)
{
    Positions p(1, 3);
    p << 1, 0, 0;
    BodyTransform transform;
    transform.scale = 2.0;
    transform.rotate_axis = Vec3::UnitZ();
    transform.rotate_degrees = 90.0;
    transform.translate = Vec3(0, 0, 5);
    transform.apply(p);
    EXPECT_NEAR_REL(p.row(0), Eigen::RowVector3d(0, 2, 5), 1e-14, 0.0);
}
