#include <corocontact/core/error.hpp>
#include <corocontact/partition/graph_partition.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>

using namespace coro;

namespace {
// A grid of nx × ny vertices joined to their 4 neighbours, weights w(x, y).
WeightedGraph grid(Index nx, Index ny, Index (*weight)(Index, Index))
{
    WeightedGraph graph;
    for (Index y = 0; y < ny; ++y)
        for (Index x = 0; x < nx; ++x) {
            for (const auto& [dx, dy] : {std::pair{0, -1}, std::pair{-1, 0}, std::pair{1, 0}, std::pair{0, 1}})
                if (x + dx >= 0 && x + dx < nx && y + dy >= 0 && y + dy < ny)
                    graph.neighbours.push_back((y + dy) * nx + x + dx);
            graph.offsets.push_back(static_cast<Index>(graph.neighbours.size()));
            graph.vertex_weights.push_back(weight(x, y));
        }
    return graph;
}
Index unit(Index, Index) { return 1; }
Index heavy_left(Index x, Index) { return x < 4 ? 5 : 1; }

std::vector<Index> part_weights(const WeightedGraph& graph, const std::vector<Index>& parts, Index n_parts)
{
    std::vector<Index> weights(static_cast<std::size_t>(n_parts), 0);
    for (std::size_t v = 0; v < parts.size(); ++v)
        weights[static_cast<std::size_t>(parts[v])] += graph.vertex_weights[v];
    return weights;
}
} // namespace

TEST(PartitionGraph, BalancesWeightsWithinMetisTolerance)
{
    for (const auto weight : {unit, heavy_left}) {
        const WeightedGraph graph = grid(16, 12, weight);
        for (const Index n_parts : {2, 3, 5}) {
            const std::vector<Index> parts = partition_graph(graph, n_parts);
            const std::vector<Index> weights = part_weights(graph, parts, n_parts);
            const double total = std::accumulate(weights.begin(), weights.end(), 0.0);
            EXPECT_LE(*std::max_element(weights.begin(), weights.end()), 1.04 * total / n_parts) << n_parts << " parts";
        }
    }
}

TEST(PartitionGraph, CutsFewEdgesOfAGrid)
{
    // Two parts of a 16 × 12 grid: the best cut is a straight line of 12 edges.
    const WeightedGraph graph = grid(16, 12, unit);
    const std::vector<Index> parts = partition_graph(graph, 2);
    Index cut = 0;
    for (Index v = 0; v < graph.num_vertices(); ++v)
        for (Index k = graph.offsets[static_cast<std::size_t>(v)]; k < graph.offsets[static_cast<std::size_t>(v) + 1]; ++k)
            cut += parts[static_cast<std::size_t>(v)] != parts[static_cast<std::size_t>(graph.neighbours[static_cast<std::size_t>(k)])] ? 1 : 0;
    EXPECT_LE(cut / 2, 16);
}

TEST(PartitionGraph, SameGraphSameParts)
{
    const WeightedGraph graph = grid(9, 7, heavy_left);
    EXPECT_EQ(partition_graph(graph, 3), partition_graph(graph, 3));
}

TEST(PartitionGraph, FewVerticesGetOnePartEach)
{
    const WeightedGraph graph = grid(2, 1, unit);
    EXPECT_EQ(partition_graph(graph, 5), (std::vector<Index>{0, 1}));
    EXPECT_EQ(partition_graph(graph, 1), (std::vector<Index>{0, 0}));
}

TEST(PartitionGraph, RejectsZeroParts)
{
    EXPECT_THAT([] { partition_graph(grid(2, 2, unit), 0); },
                ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("0 parts requested")));
}
