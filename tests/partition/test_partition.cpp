#include "mesh_fixtures.hpp"

#include <corocontact/core/error.hpp>
#include <corocontact/core/primitives.hpp>
#include <corocontact/partition/partition.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>
#include <string>

using namespace coro;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

namespace {
// Faces shared by two tets of different parts, counted by brute force.
Index count_cut_faces(const Tets& tets, const std::vector<Index>& part)
{
    std::map<std::array<Index, 3>, std::vector<Index>> faces;
    for (Index t = 0; t < tets.rows(); ++t)
        for (int skip = 0; skip < 4; ++skip) {
            std::array<Index, 3> key{};
            int k = 0;
            for (int a = 0; a < 4; ++a)
                if (a != skip)
                    key[static_cast<std::size_t>(k++)] = tets(t, a);
            std::sort(key.begin(), key.end());
            faces[key].push_back(t);
        }
    Index cut = 0;
    for (const auto& [key, owners] : faces)
        if (owners.size() == 2 && part[static_cast<std::size_t>(owners[0])] != part[static_cast<std::size_t>(owners[1])])
            ++cut;
    return cut;
}
} // namespace

class PartitionTetsParts : public ::testing::TestWithParam<Index> {};

TEST_P(PartitionTetsParts, CoversEveryTetOnceBalancedWithCorrectEdgeCut)
{
    const TetMesh mesh = make_box(Vec3::Zero(), Vec3(4, 2, 1), {16, 8, 4});
    const Index parts = GetParam();
    const TetPartition partition = partition_tets(mesh.tets, mesh.num_vertices(), parts);
    ASSERT_EQ(partition.num_parts, parts);
    ASSERT_EQ(partition.tet_part.size(), static_cast<std::size_t>(mesh.num_tets()));
    for (const Index p : partition.tet_part)
        ASSERT_TRUE(p >= 0 && p < parts);
    const std::vector<Index> sizes = partition.part_sizes();
    for (const Index size : sizes)
        EXPECT_GT(size, 0);
    // METIS's default load-imbalance tolerance for k-way partitions is 1.03.
    EXPECT_LE(partition.imbalance(), 1.031) << "parts " << parts;
    EXPECT_EQ(partition.edge_cut, count_cut_faces(mesh.tets, partition.tet_part));
    if (parts > 1) {
        EXPECT_GT(partition.edge_cut, 0);
    }
}

INSTANTIATE_TEST_SUITE_P(Counts, PartitionTetsParts, ::testing::Values(1, 2, 3, 8, 16),
                         [](const ::testing::TestParamInfo<Index>& param_info) { return "Parts" + std::to_string(param_info.param); });

TEST(PartitionTets, SameMeshSamePartition)
{
    const TetMesh mesh = make_sphere(Vec3::Zero(), 1.0, 8);
    const TetPartition a = partition_tets(mesh.tets, mesh.num_vertices(), 6);
    const TetPartition b = partition_tets(mesh.tets, mesh.num_vertices(), 6);
    EXPECT_EQ(a.tet_part, b.tet_part);
}

TEST(PartitionTets, ClampsPartsToTetCount)
{
    const TetMesh mesh = test::unit_tet();
    EXPECT_EQ(partition_tets(mesh.tets, mesh.num_vertices(), 5).num_parts, 1);
}

TEST(PartitionTets, RejectsZeroParts)
{
    const TetMesh mesh = test::unit_tet();
    EXPECT_THAT([&] { partition_tets(mesh.tets, mesh.num_vertices(), 0); },
                ThrowsMessage<InputError>(HasSubstr("0 parts requested")));
}

TEST(DefaultNumParts, FollowsTetCountNotThreads)
{
    EXPECT_EQ(default_num_parts(100, 4), 1);
    EXPECT_EQ(default_num_parts(3 * MIN_TETS_PER_PART, 4), 3); // at most one part per MIN_TETS_PER_PART tets
    const Index many = default_num_parts(1000000, 4);
    EXPECT_GE(many, 4);
    EXPECT_EQ(many % 4, 0); // 4 per core of the machine
}
