#include <corocontact/sim/body_ownership.hpp>

#include <corocontact/contact/aabb.hpp>
#include <corocontact/contact/broad_phase.hpp>
#include <corocontact/core/collective.hpp>
#include <corocontact/core/error.hpp>
#include <corocontact/core/fingerprint.hpp>
#include <corocontact/partition/graph_partition.hpp>
#include <corocontact/sim/simulation.hpp>

#include <algorithm>
#include <cstring>
#include <utility>

namespace coro {

std::vector<Index> BodyOwnership::bodies_of(Index rank) const
{
    std::vector<Index> bodies;
    for (std::size_t b = 0; b < owner.size(); ++b)
        if (owner[b] == rank)
            bodies.push_back(static_cast<Index>(b));
    return bodies;
}

BodyOwnership assign_bodies(const std::vector<Body>& bodies, Index num_ranks)
{
    CORO_CHECK(num_ranks >= 1, InputError, "assign_bodies: " << num_ranks << " ranks, expected >= 1");
    const auto n = static_cast<Index>(bodies.size());
    std::vector<Aabb> boxes(bodies.size());
    double edges = 0.0;
    for (std::size_t b = 0; b < bodies.size(); ++b) {
        const VecX& x = bodies[b].positions();
        for (Index v = 0; v < bodies[b].num_vertices(); ++v)
            boxes[b].extend(Vec3(x.segment<3>(3 * v)));
        if (!boxes[b].empty())
            edges += (boxes[b].max - boxes[b].min).maxCoeff();
    }
    const double margin = n > 0 ? 0.5 * edges / n : 0.0;
    for (Aabb& box : boxes)
        if (!box.empty()) {
            box.min.array() -= margin;
            box.max.array() += margin;
        }
    const std::vector<std::pair<Index, Index>> near = overlapping_pairs(boxes);

    WeightedGraph graph;
    std::vector<Index> degree(bodies.size(), 0);
    for (const auto& [a, b] : near) {
        ++degree[static_cast<std::size_t>(a)];
        ++degree[static_cast<std::size_t>(b)];
    }
    graph.offsets.resize(bodies.size() + 1);
    for (std::size_t b = 0; b < bodies.size(); ++b)
        graph.offsets[b + 1] = graph.offsets[b] + degree[b];
    graph.neighbours.resize(static_cast<std::size_t>(graph.offsets.back()));
    std::vector<Index> filled(graph.offsets.begin(), graph.offsets.end() - 1);
    for (const auto& [a, b] : near) { // pairs ascending: every row comes out sorted
        graph.neighbours[static_cast<std::size_t>(filled[static_cast<std::size_t>(a)]++)] = b;
        graph.neighbours[static_cast<std::size_t>(filled[static_cast<std::size_t>(b)]++)] = a;
    }
    for (std::size_t b = 0; b < bodies.size(); ++b) {
        std::sort(graph.neighbours.begin() + graph.offsets[b], graph.neighbours.begin() + graph.offsets[b + 1]);
        graph.vertex_weights.push_back(std::max<Index>(1, bodies[b].mesh().num_tets()));
    }
    BodyOwnership ownership;
    ownership.num_ranks = num_ranks;
    ownership.owner = partition_graph(graph, num_ranks);
    return ownership;
}

std::vector<Index> keep_bodies_of(Scene& scene, const BodyOwnership& ownership, Index rank)
{
    CORO_ASSERT(ownership.owner.size() == scene.bodies.size());
    std::vector<Body> kept;
    std::vector<Index> ids;
    for (std::size_t b = 0; b < scene.bodies.size(); ++b)
        if (ownership.owner[b] == rank) {
            kept.push_back(std::move(scene.bodies[b]));
            ids.push_back(static_cast<Index>(b));
        }
    scene.bodies = std::move(kept);
    return ids;
}

namespace {

/// The bodies' names, rest positions and tets, in mesh file order (the internal order follows
/// the METIS parts, which follow the node's cores): what every process must have loaded alike.
std::uint64_t scene_fingerprint(const Scene& scene)
{
    std::uint64_t hash = FNV1A_START;
    for (const Body& body : scene.bodies) {
        const Positions rest = body.to_input_order(body.fem().rest_dofs());
        const Tets tets = body.input_tets();
        hash = fnv1a(body.name().data(), body.name().size(), hash);
        hash = fnv1a(rest.data(), sizeof(double) * static_cast<std::size_t>(rest.size()), hash);
        hash = fnv1a(tets.data(), sizeof(Index) * static_cast<std::size_t>(tets.size()), hash);
    }
    return hash;
}

} // namespace

SceneDistribution distribute_scene(Scene& scene, Communicator& communicator)
{
    require_same_on_every_process(&communicator, scene_fingerprint(scene),
                                  "the processes of this run loaded different bodies (a mesh file that differs "
                                  "between the nodes?): every process must read the same files");
    SceneDistribution distribution;
    distribution.communicator = &communicator;
    distribution.ownership.num_ranks = communicator.size();
    std::vector<char> owners;
    if (communicator.rank() == 0) {
        const std::vector<Index> owner = assign_bodies(scene.bodies, communicator.size()).owner;
        owners.resize(owner.size() * sizeof(Index));
        std::memcpy(owners.data(), owner.data(), owners.size());
    }
    communicator.broadcast(owners, 0);
    distribution.ownership.owner.resize(owners.size() / sizeof(Index));
    std::memcpy(distribution.ownership.owner.data(), owners.data(), owners.size());
    distribution.body_ids = keep_bodies_of(scene, distribution.ownership, communicator.rank());
    return distribution;
}

} // namespace coro
