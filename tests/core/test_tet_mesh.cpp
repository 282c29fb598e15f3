#include "mesh_fixtures.hpp"

#include <corocontact/core/error.hpp>
#include <corocontact/core/primitives.hpp>
#include <corocontact/core/tet_mesh.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

using namespace coro;
using ::testing::AllOf;
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

TEST(FindDuplicateTet, FindsTheEarliestRepeatInAnyNodeOrder)
{
    TetMesh mesh = make_box(Vec3::Zero(), Vec3::Ones(), {2, 1, 1});
    EXPECT_FALSE(find_duplicate_tet(mesh.tets).has_value());
    const Index n = mesh.num_tets();
    Tets tets(n + 2, 4);
    tets.topRows(n) = mesh.tets;
    tets.row(n) << mesh.tets(7, 3), mesh.tets(7, 1), mesh.tets(7, 0), mesh.tets(7, 2); // tet 7 again
    tets.row(n + 1) = mesh.tets.row(2);                                                    // tet 2 again
    const auto duplicate = find_duplicate_tet(tets);
    ASSERT_TRUE(duplicate.has_value());
    EXPECT_EQ(duplicate->first, 7);
    EXPECT_EQ(duplicate->second, n);
}

TEST(ValidateAndOrient, RejectsATetListedTwiceNamingBoth)
{
    TetMesh mesh = make_box(Vec3::Zero(), Vec3::Ones(), {1, 1, 1});
    mesh.tets.conservativeResize(7, 4);
    mesh.tets.row(6) << mesh.tets(4, 1), mesh.tets(4, 0), mesh.tets(4, 2), mesh.tets(4, 3); // inverted copy
    EXPECT_THAT([&] { validate_and_orient(mesh, "twice.vtu"); },
                ThrowsMessage<InputError>(HasSubstr("twice.vtu: tet 6 has the same 4 nodes as tet 4")));
}

TEST(FindOverlappingTets, NoneInGeneratedMeshes)
{
    for (const TetMesh& mesh : {make_box(Vec3::Zero(), Vec3(2, 1, 3), {3, 2, 4}),
                                make_sphere(Vec3::Zero(), 1.0, 4), test::irregular_box(3, 0.2, 7)}) {
        TetMesh oriented = mesh;
        validate_and_orient(oriented, "m");
        EXPECT_FALSE(find_overlapping_tets(oriented).has_value());
    }
}

TEST(FindOverlappingTets, FindsTetsOnTheSameSideOfTheirFace)
{
    TetMesh mesh = test::unit_tet(); // nodes 0..3 at the origin and the unit points
    mesh.rest_positions.conservativeResize(5, 3);
    mesh.rest_positions.row(4) << 0.2, 0.2, 0.2; // above face (0, 1, 2), like node 3
    mesh.tets.conservativeResize(2, 4);
    mesh.tets.row(1) << 0, 1, 2, 4;
    const auto overlap = find_overlapping_tets(mesh);
    ASSERT_TRUE(overlap.has_value());
    EXPECT_EQ(overlap->first, 0);
    EXPECT_EQ(overlap->second, 1);
    EXPECT_EQ(overlap->face, (std::array<Index, 3>{0, 1, 2}));
    EXPECT_FALSE(overlap->shared_by_more);
    EXPECT_THAT([&] { validate_and_orient(mesh, "folded.msh"); },
                ThrowsMessage<InputError>(
                    HasSubstr("folded.msh: tets 0 and 1 lie on the same side of their shared face (0, 1, 2)")));

    mesh.rest_positions.row(4) << 0.2, 0.2, -0.2; // below it: a valid two-tet mesh
    validate_and_orient(mesh, "m");
    EXPECT_FALSE(find_overlapping_tets(mesh).has_value());
}

TEST(FindOverlappingTets, FindsAFaceSharedByThreeTets)
{
    TetMesh mesh = test::unit_tet();
    mesh.rest_positions.conservativeResize(6, 3);
    mesh.rest_positions.row(4) << 0.2, 0.2, -0.5;
    mesh.rest_positions.row(5) << 0.1, 0.3, -0.7;
    mesh.tets.conservativeResize(3, 4);
    mesh.tets.row(1) << 0, 2, 1, 4;
    mesh.tets.row(2) << 0, 2, 1, 5;
    EXPECT_THAT([&] { validate_and_orient(mesh, "three.msh"); },
                ThrowsMessage<InputError>(
                    HasSubstr("three.msh: more than two tets share the face (0, 1, 2), among them tets 0 and 1")));
    const auto overlap = find_overlapping_tets(mesh); // mesh is oriented by now
    ASSERT_TRUE(overlap.has_value());
    EXPECT_TRUE(overlap->shared_by_more);
}

TEST(ValidateAndOrient, RejectsCoordinatesWhoseVolumesOverflow)
{
    TetMesh mesh = test::unit_tet();
    mesh.rest_positions *= 1e101;
    EXPECT_THAT([&] { validate_and_orient(mesh, "huge.msh"); },
                ThrowsMessage<InputError>(AllOf(HasSubstr("huge.msh: node 1 has the coordinate 1e+101"),
                                                HasSubstr("at most 1e+100"))));
}

TEST(ValidateAndOrient, RejectsEdgesWhoseVolumesUnderflow)
{
    TetMesh mesh = test::unit_tet();
    mesh.rest_positions *= 1e-110;
    EXPECT_THAT([&] { validate_and_orient(mesh, "tiny.msh"); },
                ThrowsMessage<InputError>(HasSubstr("tiny.msh: the tets' edges are")));
    mesh = test::unit_tet();
    mesh.rest_positions *= 1e-90; // small, but volumes of 1e-270 are still doubles
    EXPECT_EQ(validate_and_orient(mesh, "small.msh"), 0);
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

TEST(CoincidentVertices, PairsEveryNodeOfTetsWithTheFirstNodeAtItsPlace)
{
    // A box written twice over (the second copy's nodes after the first's), plus one more copy of
    // node 0 that no tet uses: every node of the second copy coincides with one of the first.
    const TetMesh box = make_box(Vec3(0, 0, 0), Vec3(2, 1, 1), {2, 1, 1});
    const Index n = box.num_vertices();
    TetMesh doubled;
    doubled.rest_positions.resize(2 * n + 1, 3);
    doubled.rest_positions << box.rest_positions, box.rest_positions, box.rest_positions.row(0);
    doubled.tets.resize(2 * box.num_tets(), 4);
    doubled.tets << box.tets, box.tets.array() + n;
    std::vector<std::array<Index, 2>> brute;
    for (Index w = 0; w < 2 * n; ++w)
        for (Index v = 0; v < w; ++v)
            if (doubled.rest_positions.row(v) == doubled.rest_positions.row(w)) {
                brute.push_back({v, w});
                break;
            }
    std::vector<std::array<Index, 2>> found = coincident_vertices(doubled);
    std::sort(found.begin(), found.end());
    EXPECT_EQ(found, brute);
    EXPECT_EQ(found.size(), static_cast<std::size_t>(n));
    EXPECT_TRUE(coincident_vertices(box).empty());
}
