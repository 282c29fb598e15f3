// Run under mpirun (ctest: -np 2 and -np 3). Every test compares what the processes compute
// together with what one process computes alone, bit for bit: the reference is rank 0 running
// the whole case without a communicator.

#include "mpi_test_env.hpp"

#include <corocontact/core/collective.hpp>
#include <corocontact/core/error.hpp>
#include <corocontact/io/case_reader.hpp>
#include <corocontact/io/scene_loader.hpp>
#include <corocontact/sim/body_ownership.hpp>
#include <corocontact/sim/simulation.hpp>
#include <corocontact/solver/rank_exchange.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

using namespace coro;
using coro::test::world;

namespace {

std::size_t at(Index i) { return static_cast<std::size_t>(i); }

// Every body's positions, velocities and contact forces in the case's order, as one process
// holds them.
struct State {
    std::vector<VecX> positions, velocities, contact_forces;
};

std::vector<char> pack(const std::vector<Index>& ids, const Scene& scene)
{
    std::vector<char> bytes;
    const auto put = [&](const void* data, std::size_t size) {
        const char* c = static_cast<const char*>(data);
        bytes.insert(bytes.end(), c, c + size);
    };
    for (std::size_t l = 0; l < ids.size(); ++l) {
        const Body& body = scene.bodies[l];
        const std::size_t n = static_cast<std::size_t>(3 * body.num_vertices());
        put(&ids[l], sizeof(Index));
        put(body.positions().data(), n * sizeof(double));
        put(body.velocities().data(), n * sizeof(double));
        const VecX forces = l < scene.contact_forces.size() ? scene.contact_forces[l] : VecX::Zero(3 * body.num_vertices());
        put(forces.data(), n * sizeof(double));
    }
    return bytes;
}

// The state of the distributed scene, on rank 0 (gathered); empty elsewhere.
State gather_state(const std::vector<Index>& ids, const Scene& scene, const std::vector<Index>& sizes)
{
    const std::vector<std::vector<char>> all = world().gather(pack(ids, scene), 0);
    State state;
    if (all.empty())
        return state;
    state.positions.resize(sizes.size());
    state.velocities.resize(sizes.size());
    state.contact_forces.resize(sizes.size());
    for (const std::vector<char>& bytes : all) {
        std::size_t at_byte = 0;
        while (at_byte < bytes.size()) {
            Index id = 0;
            std::memcpy(&id, bytes.data() + at_byte, sizeof(Index));
            at_byte += sizeof(Index);
            for (std::vector<VecX>* target : {&state.positions, &state.velocities, &state.contact_forces}) {
                VecX& v = (*target)[at(id)];
                v.resize(3 * sizes[at(id)]);
                std::memcpy(v.data(), bytes.data() + at_byte, static_cast<std::size_t>(v.size()) * sizeof(double));
                at_byte += static_cast<std::size_t>(v.size()) * sizeof(double);
            }
        }
    }
    return state;
}

State state_of(const Scene& scene)
{
    State state;
    for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
        state.positions.push_back(scene.bodies[b].positions());
        state.velocities.push_back(scene.bodies[b].velocities());
        state.contact_forces.push_back(b < scene.contact_forces.size() ? scene.contact_forces[b]
                                                                        : VecX::Zero(3 * scene.bodies[b].num_vertices()));
    }
    return state;
}

bool bitwise_equal(const VecX& a, const VecX& b)
{
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), static_cast<std::size_t>(a.size()) * sizeof(double)) == 0;
}

void expect_same_state(const State& distributed, const State& alone, const std::string& when)
{
    ASSERT_EQ(distributed.positions.size(), alone.positions.size());
    for (std::size_t b = 0; b < alone.positions.size(); ++b) {
        EXPECT_TRUE(bitwise_equal(distributed.positions[b], alone.positions[b])) << when << ": positions of body " << b;
        EXPECT_TRUE(bitwise_equal(distributed.velocities[b], alone.velocities[b])) << when << ": velocities of body " << b;
        EXPECT_TRUE(bitwise_equal(distributed.contact_forces[b], alone.contact_forces[b]))
            << when << ": contact forces of body " << b;
    }
}

struct Outcome {
    RunSummary summary;
    RankStats stats;
    BodyOwnership ownership;
};

// Runs `steps` steps of `text` distributed over the world and, on rank 0, alone; compares the
// states after every step. `after_step(step, scene)` sees the scene of the one process (rank 0).
Outcome run_both(const std::string& text, Index steps,
                 const std::function<void(Index step, const Scene& alone)>& after_step = {})
{
    const CaseSpec spec = parse_case(text, "distributed.toml");
    LoadedScene loaded = load_scene(spec);
    std::vector<Index> sizes;
    for (const Body& body : loaded.scene.bodies)
        sizes.push_back(body.num_vertices());
    SceneDistribution distribution;
    distribution.communicator = &world();
    distribution.ownership = assign_bodies(loaded.scene.bodies, world().size());
    distribution.body_ids = keep_bodies_of(loaded.scene, distribution.ownership, world().rank());

    Simulation simulation(loaded.scene, spec, &distribution);
    std::unique_ptr<LoadedScene> alone_scene;
    std::unique_ptr<Simulation> alone;
    if (world().rank() == 0) {
        alone_scene = std::make_unique<LoadedScene>(load_scene(spec));
        alone = std::make_unique<Simulation>(alone_scene->scene, spec);
        alone->start();
    }
    simulation.start();
    for (Index step = 1; step <= steps; ++step) {
        simulation.step();
        if (alone)
            alone->step();
        const State state = gather_state(distribution.body_ids, loaded.scene, sizes);
        if (alone) {
            expect_same_state(state, state_of(alone_scene->scene), "step " + std::to_string(step));
            if (after_step)
                after_step(step, alone_scene->scene);
        }
    }
    Outcome outcome{simulation.summary(), simulation.rank_stats(), distribution.ownership};
    if (alone) {
        const RunSummary one = alone->summary();
        EXPECT_EQ(outcome.summary.contacts_mean, one.contacts_mean);
        EXPECT_EQ(outcome.summary.max_contact_depth, one.max_contact_depth);
        EXPECT_EQ(outcome.summary.cg_iterations_mean, one.cg_iterations_mean);
        EXPECT_EQ(outcome.summary.cg_residual_mean, one.cg_residual_mean);
    }
    return outcome;
}

// Two layers of small boxes that start slightly overlapping their neighbours, on a floor: every
// box touches others from the first step, across whatever cut the ownership makes.
std::string touching_boxes(int per_row)
{
    std::string text = R"toml([simulation]
dt = 0.004
steps = 20
gravity = [0.0, -9.81, 0.0]
[solver]
max_iterations = 60
tolerance = 1e-8
preconditioner = "block_jacobi"
[contact]
enabled = true
stiffness = 2e5
damping = 50.0
friction = 0.3
[[obstacle]]
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
)toml";
    for (int layer = 0; layer < 2; ++layer)
        for (int i = 0; i < per_row; ++i) {
            const double x = 0.19 * i + 0.095 * layer, y = 0.11 + 0.19 * layer;
            text += "[[body]]\nname = \"box" + std::to_string(layer) + "_" + std::to_string(i) + "\"\n";
            text += i % 3 == 2 ? "shape = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 0.105\nresolution = 2\n"
                               : "shape = \"box\"\nmin = [-0.1, -0.1, -0.1]\nmax = [0.1, 0.1, 0.1]\ncells = [1, 1, 2]\n";
            text += "translate = [" + std::to_string(x) + ", " + std::to_string(y) + ", " +
                    std::to_string(0.01 * (i % 2)) + "]\n";
            text += "young = 1e5\npoisson = 0.3\ndensity = 500.0\nrayleigh_mass = 0.5\n\n";
        }
    return text;
}

} // namespace

TEST(RankExchange, SumsChunksPerComponentInTheGlobalOrder)
{
    // Chunks of bodies dealt to the ranks round robin: the global order interleaves the ranks,
    // and the components interleave the bodies.
    const int ranks = world().size(), me = world().rank();
    const std::vector<Index> component_of_body = {0, 0, 1, 0, 2, 1, 2};
    const auto bodies = static_cast<Index>(component_of_body.size());
    std::vector<Index> mine;
    std::vector<double> partials;
    std::vector<double> expected(2 * 3, 0.0); // one process: chunk order, two values per chunk
    for (Index b = 0; b < bodies; ++b)
        for (Index c = 0; c <= b % 3; ++c) {
            const double value = 1.0 / (3.0 + b) + 1e-17 * c - 0.1 * (b % 2); // sums depend on the order
            const std::size_t k = at(component_of_body[at(b)]);
            expected[2 * k] += value;
            expected[2 * k + 1] += -value / 7.0;
            if (b % ranks == me) {
                mine.push_back(b);
                partials.push_back(value);
                partials.push_back(-value / 7.0);
            }
        }
    RankExchange exchange(world(), mine, 0);
    EXPECT_EQ(exchange.num_components(), bodies) << "every body its own component until set";
    exchange.set_components(component_of_body);
    ASSERT_EQ(exchange.num_components(), 3);
    std::vector<double> totals(expected.size(), -1.0);
    exchange.sum_by_component(partials.data(), 2, totals.data());
    EXPECT_EQ(totals, expected);
}

TEST(RankExchange, FillsGhostRowsWithTheOwnersValues)
{
    // Each rank owns 4 rows with values 100 r + row; it holds as ghosts rows 1 and 3 of every other rank.
    const int ranks = world().size(), me = world().rank();
    RankExchange exchange(world(), {me}, 4);
    RankExchange::Halo halo;
    for (int r = 0; r < ranks; ++r) {
        if (r == me)
            continue;
        halo.ranks.push_back(r);
        halo.send_rows.push_back({1, 3});
        halo.ghost_rows.push_back({halo.num_ghosts, halo.num_ghosts + 1});
        halo.num_ghosts += 2;
    }
    exchange.set_halo(halo);
    std::vector<double> x(static_cast<std::size_t>(3 * (4 + exchange.num_ghost_rows())), -1.0);
    for (int row = 0; row < 4; ++row)
        for (int d = 0; d < 3; ++d)
            x[static_cast<std::size_t>(3 * row + d)] = 100.0 * me + row + 0.1 * d;
    exchange.update_ghosts(x.data());
    std::size_t k = 0;
    for (int r = 0; r < ranks; ++r) {
        if (r == me)
            continue;
        for (const int row : {1, 3}) {
            for (int d = 0; d < 3; ++d)
                EXPECT_EQ(x[static_cast<std::size_t>(3 * (4 + k)) + static_cast<std::size_t>(d)], 100.0 * r + row + 0.1 * d);
            ++k;
        }
    }
}

TEST(RunCollectively, EveryRankThrowsTheLowestFailingRanksError)
{
    const int last = world().size() - 1;
    EXPECT_THAT(
        [&] {
            run_collectively(&world(), [&] {
                if (world().rank() == last)
                    CORO_THROW(NumericalError, "rank " << world().rank() << " diverged");
            });
        },
        ::testing::ThrowsMessage<NumericalError>(::testing::HasSubstr("rank " + std::to_string(last) + " diverged")));
    EXPECT_NO_THROW(run_collectively(&world(), [] {}));
}

TEST(DistributedScene, TouchingBoxesStepBitwiseAsOneProcess)
{
    const Outcome outcome = run_both(touching_boxes(6), 20);
    EXPECT_EQ(outcome.stats.ranks, world().size());
    EXPECT_GT(outcome.stats.cross_rank_contacts_mean, 1.0) << "the case must have contact between ranks";
    EXPECT_GT(outcome.stats.mpi_bytes_per_step, 0.0);
}

TEST(DistributedScene, BodyMovingFromALocalToARemoteContactStepsBitwiseAsOneProcess)
{
    // A small box slides off a heavy box it starts in contact with, crosses a gap and hits a
    // second heavy box. On two processes the heavy boxes have different owners (the tets
    // balance), so the small one's contact moves from its own process to the other.
    const std::string text = R"toml([simulation]
dt = 0.005
gravity = [0.0, 0.0, 0.0]
[solver]
max_iterations = 80
tolerance = 1e-9
[contact]
enabled = true
stiffness = 1e5
damping = 20.0
[[body]]
name = "from"
shape = "box"
min = [-0.45, -0.15, -0.15]
max = [-0.15, 0.15, 0.15]
cells = [2, 2, 2]
young = 1e5
density = 500.0
[[body]]
name = "mover"
shape = "box"
min = [-0.16, -0.05, -0.05]
max = [-0.06, 0.05, 0.05]
cells = [1, 1, 1]
velocity = [1.5, 0.0, 0.0]
young = 1e5
density = 500.0
[[body]]
name = "to"
shape = "box"
min = [0.15, -0.15, -0.15]
max = [0.45, 0.15, 0.15]
cells = [2, 2, 2]
young = 1e5
density = 500.0
)toml";
    Index touched_from = 0, touched_to_only = 0;
    const auto touches = [](const Scene& scene, Index a, Index b) {
        for (const ContactPoint& point : scene.contacts)
            if ((point.body == a && point.other == ContactTarget::surface(b)) ||
                (point.body == b && point.other == ContactTarget::surface(a)))
                return true;
        return false;
    };
    const Outcome outcome = run_both(text, 70, [&](Index, const Scene& alone) {
        touched_from += touches(alone, 0, 1) ? 1 : 0;
        touched_to_only += touches(alone, 1, 2) && !touches(alone, 0, 1) ? 1 : 0;
    });
    if (world().rank() == 0) {
        EXPECT_GT(touched_from, 0) << "the mover starts in contact with 'from'";
        EXPECT_GT(touched_to_only, 0) << "the mover reaches 'to'";
    }
    if (world().size() == 2) {
        EXPECT_NE(outcome.ownership.owner[0], outcome.ownership.owner[2]);
    }
}

TEST(DistributedScene, ANonFiniteValueIsNamedAsInOneProcess)
{
    // NaN velocities in two bodies, which on 2 or 3 processes lie on different ones: every
    // process names the first of them in case order, as one process does.
    const CaseSpec spec = parse_case(touching_boxes(3), "distributed.toml");
    LoadedScene loaded = load_scene(spec);
    SceneDistribution distribution;
    distribution.communicator = &world();
    distribution.ownership = assign_bodies(loaded.scene.bodies, world().size());
    ASSERT_NE(distribution.ownership.owner[1], distribution.ownership.owner[5]);
    distribution.body_ids = keep_bodies_of(loaded.scene, distribution.ownership, world().rank());
    for (std::size_t b = 0; b < distribution.body_ids.size(); ++b)
        if (distribution.body_ids[b] == 1 || distribution.body_ids[b] == 5)
            loaded.scene.bodies[b].velocities().setConstant(std::numeric_limits<double>::quiet_NaN());
    Simulation simulation(loaded.scene, spec, &distribution);
    simulation.start();
    const auto message_of_step = [](Simulation& run) {
        try {
            run.step();
        } catch (const NumericalError& error) {
            return std::string(error.what());
        }
        return std::string("no NumericalError");
    };
    const std::string distributed = message_of_step(simulation);

    LoadedScene alone = load_scene(spec);
    for (const Index b : {1, 5})
        alone.scene.bodies[at(b)].velocities().setConstant(std::numeric_limits<double>::quiet_NaN());
    Simulation one(alone.scene, spec);
    one.start();
    const std::string expected = message_of_step(one);
    EXPECT_THAT(expected, ::testing::EndsWith("; first non-finite value: body 'box0_1': velocity of node 0 (mesh file "
                                              "order) is nan"));
    EXPECT_EQ(distributed, expected);
}
