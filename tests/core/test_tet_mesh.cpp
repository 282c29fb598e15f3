#include "mesh_fixtures.hpp"

#include <corocontact/core/error.hpp>
#include <corocontact/core/tet_mesh.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>

using namespace coro;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

TEST(TetMesh, SignedVolumeOfUnitTet)
{
    const TetMesh mesh = test::unit_tet();
    EXPECT_DOUBLE_EQ(signed_volume(mesh, 0), 1.0 / 6.0);
}

TEST(ValidateAndOrient, ReorientsNegativeTetsAndCountsThem)
{
    TetMesh mesh = test::unit_tet();
    std::swap(mesh.tets(0, 1), mesh.tets(0, 2));
    EXPECT_LT(signed_volume(mesh, 0), 0.0);
    EXPECT_EQ(validate_and_orient(mesh, "m"), 1);
    EXPECT_DOUBLE_EQ(signed_volume(mesh, 0), 1.0 / 6.0);
    EXPECT_EQ(validate_and_orient(mesh, "m"), 0);
}

TEST(ValidateAndOrient, RejectsZeroVolumeTetNamingIt)
{
    TetMesh mesh = test::unit_tet();
    mesh.rest_positions.row(3) << 0.5, 0.5, 0.0; // coplanar with the other three
    EXPECT_THAT([&] { validate_and_orient(mesh, "flat.msh"); },
                ThrowsMessage<InputError>(HasSubstr("flat.msh: tet 0 has zero volume")));
}

TEST(ValidateAndOrient, RejectsRepeatedNode)
{
    TetMesh mesh = test::unit_tet();
    mesh.tets(0, 3) = 1;
    EXPECT_THAT([&] { validate_and_orient(mesh, "m"); }, ThrowsMessage<InputError>(HasSubstr("repeats node 1")));
}

TEST(ValidateAndOrient, RejectsIndexOutOfRange)
{
    TetMesh mesh = test::unit_tet();
    mesh.tets(0, 2) = 7;
    EXPECT_THAT([&] { validate_and_orient(mesh, "m"); },
                ThrowsMessage<InputError>(HasSubstr("tet 0 refers to node 7")));
}

TEST(ValidateAndOrient, RejectsNonFiniteCoordinate)
{
    TetMesh mesh = test::unit_tet();
    mesh.rest_positions(2, 1) = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THAT([&] { validate_and_orient(mesh, "m"); },
                ThrowsMessage<InputError>(HasSubstr("node 2 has a non-finite coordinate")));
}

TEST(ValidateAndOrient, RejectsMeshWithoutTets)
{
    TetMesh mesh = test::unit_tet();
    mesh.tets.resize(0, 4);
    EXPECT_THAT([&] { validate_and_orient(mesh, "empty.msh"); },
                ThrowsMessage<InputError>(HasSubstr("empty.msh: the mesh has no tetrahedra")));
}

TEST(MeanRatioQuality, IsOneForRegularTetAndSmallForSliver)
{
    TetMesh mesh;
    mesh.rest_positions.resize(4, 3);
    mesh.rest_positions << 1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1;
    mesh.tets.resize(1, 4);
    mesh.tets << 0, 1, 2, 3;
    validate_and_orient(mesh, "regular");
    EXPECT_NEAR(mean_ratio_quality(mesh, 0), 1.0, 1e-12);
    mesh.rest_positions.row(3) << 0.0, 0.0, -0.9; // nearly in the plane of the others
    validate_and_orient(mesh, "sliver");
    EXPECT_LT(mean_ratio_quality(mesh, 0), 0.2);
}

TEST(UnreferencedVertices, FindsNodesInNoTet)
{
    TetMesh mesh = test::unit_tet();
    mesh.rest_positions.conservativeResize(6, 3);
    mesh.rest_positions.bottomRows(2).setOnes();
    EXPECT_EQ(unreferenced_vertices(mesh), (std::vector<Index>{4, 5}));
}
