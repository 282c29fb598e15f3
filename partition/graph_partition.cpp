#include <corocontact/partition/graph_partition.hpp>

#include <corocontact/core/error.hpp>

#include <metis.h>

namespace coro {

namespace {
constexpr idx_t METIS_SEED = 20101025; // fixed: the same graph always gets the same parts
} // namespace

std::vector<Index> partition_graph(const WeightedGraph& graph, Index num_parts)
{
    CORO_CHECK(num_parts >= 1, InputError, "partition_graph: " << num_parts << " parts requested, expected >= 1");
    const Index n = graph.num_vertices();
    CORO_CHECK(n >= 0 && graph.vertex_weights.size() == static_cast<std::size_t>(n) &&
                   graph.offsets.front() == 0 &&
                   graph.offsets.back() == static_cast<Index>(graph.neighbours.size()),
               InputError,
               "partition_graph: " << n << " vertices, " << graph.vertex_weights.size() << " weights and "
                                   << graph.neighbours.size() << " neighbour entries do not match");
    std::vector<Index> parts(static_cast<std::size_t>(n), 0);
    if (num_parts == 1)
        return parts;
    if (n <= num_parts) {
        for (Index v = 0; v < n; ++v)
            parts[static_cast<std::size_t>(v)] = v;
        return parts;
    }
    idx_t nvtxs = n, ncon = 1, nparts = num_parts, objval = 0;
    std::vector<idx_t> xadj(graph.offsets.begin(), graph.offsets.end());
    std::vector<idx_t> adjncy(graph.neighbours.begin(), graph.neighbours.end());
    std::vector<idx_t> vwgt(graph.vertex_weights.begin(), graph.vertex_weights.end());
    std::vector<idx_t> part(static_cast<std::size_t>(n));
    idx_t options[METIS_NOPTIONS];
    METIS_SetDefaultOptions(options);
    options[METIS_OPTION_SEED] = METIS_SEED;
    options[METIS_OPTION_NUMBERING] = 0;
    const int status = METIS_PartGraphKway(&nvtxs, &ncon, xadj.data(), adjncy.data(), vwgt.data(), nullptr, nullptr,
                                           &nparts, nullptr, nullptr, options, &objval, part.data());
    CORO_CHECK(status == METIS_OK, NumericalError,
               "METIS_PartGraphKway failed (status " << status << ") for " << n << " vertices into " << num_parts
                                                      << " parts");
    for (Index v = 0; v < n; ++v)
        parts[static_cast<std::size_t>(v)] = static_cast<Index>(part[static_cast<std::size_t>(v)]);
    return parts;
}

} // namespace coro
