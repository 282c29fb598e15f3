#pragma once
/// @file graph_partition.hpp
/// @brief METIS partition of a weighted graph, e.g. bodies joined by proximity into the parts
/// that processes own (sim/body_ownership.hpp).

#include <corocontact/core/types.hpp>

#include <vector>

namespace coro {

/// An undirected graph in compressed rows: the neighbours of vertex v are
/// neighbours[offsets[v] .. offsets[v + 1]), every edge listed from both ends, no self loops.
struct WeightedGraph {
    std::vector<Index> offsets{0};     ///< #V+1, rising from 0
    std::vector<Index> neighbours;     ///< #2E
    std::vector<Index> vertex_weights; ///< #V, each ≥ 1

    Index num_vertices() const { return static_cast<Index>(offsets.size()) - 1; }
};

/// Splits the vertices into `num_parts` parts of about equal total weight (METIS'
/// default tolerance, 3 %) that cut few edges: METIS_PartGraphKway with a fixed seed, so the same
/// graph always gets the same parts. With one part every vertex goes to part 0; with no more
/// vertices than parts, vertex v to part v.
/// @param[in] num_parts  ≥ 1
/// @return #V part indices in [0, num_parts); a part may be empty
/// @throws InputError if num_parts < 1 or the graph is malformed; NumericalError if METIS fails
std::vector<Index> partition_graph(const WeightedGraph& graph, Index num_parts);

} // namespace coro
