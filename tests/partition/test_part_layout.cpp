#include <corocontact/core/primitives.hpp>
#include <corocontact/partition/part_layout.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <set>

using namespace coro;

namespace {
bool is_permutation_of_iota(std::vector<Index> v)
{
    std::sort(v.begin(), v.end());
    std::vector<Index> iota(v.size());
    std::iota(iota.begin(), iota.end(), 0);
    return v == iota;
}
} // namespace

TEST(PartLayout, RenumberingIsAPermutationWithContiguousPartsAndInterfaceLast)
{
    const TetMesh mesh = make_sphere(Vec3::Zero(), 1.0, 10);
    const TetPartition partition = partition_tets(mesh.tets, mesh.num_vertices(), 7);
    const PartLayout layout = make_part_layout(mesh.tets, mesh.num_vertices(), partition);
    ASSERT_TRUE(is_permutation_of_iota(layout.new_to_old_tet));
    ASSERT_TRUE(is_permutation_of_iota(layout.new_to_old_node));
    for (Index v = 0; v < mesh.num_vertices(); ++v)
        ASSERT_EQ(layout.old_to_new_node[static_cast<std::size_t>(layout.new_to_old_node[static_cast<std::size_t>(v)])], v);

    // Tets of part p are exactly the new range [tet_offsets[p], tet_offsets[p+1]).
    for (Index p = 0; p < layout.num_parts; ++p)
        for (Index t = layout.tet_offsets[static_cast<std::size_t>(p)]; t < layout.tet_offsets[static_cast<std::size_t>(p) + 1]; ++t)
            ASSERT_EQ(partition.tet_part[static_cast<std::size_t>(layout.new_to_old_tet[static_cast<std::size_t>(t)])], p);

    // Which parts touch each (new) node.
    const TetMesh reordered = reorder_mesh(mesh, layout);
    std::vector<std::set<Index>> parts_of_node(static_cast<std::size_t>(mesh.num_vertices()));
    for (Index t = 0; t < reordered.num_tets(); ++t)
        for (int a = 0; a < 4; ++a)
            parts_of_node[static_cast<std::size_t>(reordered.tets(t, a))].insert(layout.tet_part[static_cast<std::size_t>(t)]);
    for (Index p = 0; p < layout.num_parts; ++p)
        for (Index v = layout.node_offsets[static_cast<std::size_t>(p)]; v < layout.node_offsets[static_cast<std::size_t>(p) + 1]; ++v)
            ASSERT_EQ(parts_of_node[static_cast<std::size_t>(v)], std::set<Index>{p}) << "interior node " << v;
    EXPECT_GT(layout.num_interface_nodes(), 0);
    for (Index v = layout.first_interface_node(); v < mesh.num_vertices(); ++v)
        ASSERT_GT(parts_of_node[static_cast<std::size_t>(v)].size(), 1u) << "interface node " << v;
}

TEST(PartLayout, ReorderedMeshIsTheSameMesh)
{
    const TetMesh mesh = make_box(Vec3::Zero(), Vec3(3, 1, 1), {9, 3, 3});
    const PartLayout layout = make_part_layout(mesh.tets, mesh.num_vertices(), partition_tets(mesh.tets, mesh.num_vertices(), 4));
    const TetMesh reordered = reorder_mesh(mesh, layout);
    for (Index t = 0; t < mesh.num_tets(); ++t)
        for (int a = 0; a < 4; ++a) {
            const Index old_tet = layout.new_to_old_tet[static_cast<std::size_t>(t)];
            const Index new_node = reordered.tets(t, a);
            ASSERT_EQ(reordered.rest_positions.row(new_node), mesh.rest_positions.row(mesh.tets(old_tet, a)));
        }
}
