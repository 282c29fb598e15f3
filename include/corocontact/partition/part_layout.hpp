#pragma once
/// @file part_layout.hpp
/// @brief Renumbering of tets and nodes so that every part's tets and interior nodes are
/// contiguous and the interface nodes (shared by several parts) come last.

#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/partition/partition.hpp>

#include <vector>

namespace coro {

/// The internal order of a partitioned body. "new" indices are internal, "old" are the input's.
struct PartLayout {
    Index num_parts = 1;
    std::vector<Index> tet_offsets;   ///< #parts+1: part p owns new tets [tet_offsets[p], tet_offsets[p+1])
    std::vector<Index> node_offsets;  ///< #parts+2: interior nodes of part p are
                                      ///< [node_offsets[p], node_offsets[p+1]); the interface
                                      ///< nodes are [node_offsets[parts], node_offsets[parts+1])
    std::vector<Index> new_to_old_tet;  ///< #T
    std::vector<Index> new_to_old_node; ///< #V
    std::vector<Index> old_to_new_node; ///< #V
    std::vector<Index> tet_part;        ///< #T, part of each new tet (ascending)

    Index first_interface_node() const { return node_offsets[static_cast<std::size_t>(num_parts)]; }
    Index num_interface_nodes() const { return node_offsets.back() - first_interface_node(); }
};

/// Orders tets by part (keeping their relative order) and nodes as: interior nodes of part 0,
/// of part 1, …, then interface nodes (touched by tets of more than one part), each group in
/// ascending old index. Nodes used by no tet count as interior nodes of part 0.
PartLayout make_part_layout(const Tets& tets, Index num_vertices, const TetPartition& partition);

/// The mesh in the layout's internal order (tets renumbered and reordered).
TetMesh reorder_mesh(const TetMesh& mesh, const PartLayout& layout);

} // namespace coro
