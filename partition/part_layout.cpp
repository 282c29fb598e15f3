#include <corocontact/partition/part_layout.hpp>

#include <algorithm>
#include <numeric>

namespace coro {

namespace {
std::size_t at(Index i) { return static_cast<std::size_t>(i); }
constexpr Index NO_PART = -1;
constexpr Index SHARED = -2;
} // namespace

PartLayout make_part_layout(const Tets& tets, Index num_vertices, const TetPartition& partition)
{
    PartLayout layout;
    const Index n_tets = static_cast<Index>(tets.rows());
    const Index parts = partition.num_parts;
    layout.num_parts = parts;

    // Tets: stable sort by part.
    layout.new_to_old_tet.resize(at(n_tets));
    std::iota(layout.new_to_old_tet.begin(), layout.new_to_old_tet.end(), 0);
    std::stable_sort(layout.new_to_old_tet.begin(), layout.new_to_old_tet.end(), [&](Index a, Index b) {
        return partition.tet_part[at(a)] < partition.tet_part[at(b)];
    });
    layout.tet_part.resize(at(n_tets));
    layout.tet_offsets.assign(at(parts) + 1, 0);
    for (Index t = 0; t < n_tets; ++t) {
        const Index p = partition.tet_part[at(layout.new_to_old_tet[at(t)])];
        layout.tet_part[at(t)] = p;
        ++layout.tet_offsets[at(p) + 1];
    }
    std::partial_sum(layout.tet_offsets.begin(), layout.tet_offsets.end(), layout.tet_offsets.begin());

    // Nodes: the part owning each node, or SHARED.
    std::vector<Index> owner(at(num_vertices), NO_PART);
    for (Index t = 0; t < n_tets; ++t)
        for (int a = 0; a < 4; ++a) {
            Index& o = owner[at(tets(t, a))];
            const Index p = partition.tet_part[at(t)];
            o = (o == NO_PART || o == p) ? p : SHARED;
        }
    for (Index& o : owner)
        if (o == NO_PART)
            o = 0;
    const auto group = [&](Index v) { return owner[at(v)] == SHARED ? parts : owner[at(v)]; };
    layout.new_to_old_node.resize(at(num_vertices));
    std::iota(layout.new_to_old_node.begin(), layout.new_to_old_node.end(), 0);
    std::stable_sort(layout.new_to_old_node.begin(), layout.new_to_old_node.end(),
                     [&](Index a, Index b) { return group(a) < group(b); });
    layout.node_offsets.assign(at(parts) + 2, 0);
    for (Index v = 0; v < num_vertices; ++v)
        ++layout.node_offsets[at(group(v)) + 1];
    std::partial_sum(layout.node_offsets.begin(), layout.node_offsets.end(), layout.node_offsets.begin());
    layout.old_to_new_node.resize(at(num_vertices));
    for (Index v = 0; v < num_vertices; ++v)
        layout.old_to_new_node[at(layout.new_to_old_node[at(v)])] = v;
    return layout;
}

TetMesh reorder_mesh(const TetMesh& mesh, const PartLayout& layout)
{
    TetMesh reordered;
    reordered.rest_positions.resize(mesh.num_vertices(), 3);
    for (Index v = 0; v < mesh.num_vertices(); ++v)
        reordered.rest_positions.row(v) = mesh.rest_positions.row(layout.new_to_old_node[at(v)]);
    reordered.tets.resize(mesh.num_tets(), 4);
    for (Index t = 0; t < mesh.num_tets(); ++t)
        for (int a = 0; a < 4; ++a)
            reordered.tets(t, a) = layout.old_to_new_node[at(mesh.tets(layout.new_to_old_tet[at(t)], a))];
    return reordered;
}

} // namespace coro
