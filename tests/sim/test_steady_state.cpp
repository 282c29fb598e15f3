// A time step allocates nothing once its buffers have grown to the scene (DESIGN.md, "Many
// bodies": no allocation in the steady state). Its own executable: allocation_counter.cpp
// replaces malloc for the whole process.
#include "allocation_counter.hpp"

#include <corocontact/io/case_reader.hpp>
#include <corocontact/io/scene_loader.hpp>
#include <corocontact/sim/simulation.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

using namespace coro;

namespace {
// Six bodies dropped onto a floor and into each other, with friction and contact damping.
const char* const PILE = R"toml(
[simulation]
dt = 0.004
steps = 60
gravity = [0.0, -9.81, 0.0]
[solver]
max_iterations = 30
tolerance = 1e-6
[contact]
enabled = true
stiffness = 4e4
damping = 20.0
friction = 0.4
[[body]]
name = "a"
shape = "box"
min = [-0.2, 0.0, -0.2]
max = [0.2, 0.2, 0.2]
cells = [3, 2, 3]
young = 2e4
density = 500.0
[[body]]
name = "b"
shape = "sphere"
center = [0.05, 0.33, 0.0]
radius = 0.14
resolution = 4
young = 2e4
density = 500.0
[[body]]
name = "c"
shape = "box"
min = [-0.1, 0.47, -0.1]
max = [0.1, 0.67, 0.1]
cells = [2, 2, 2]
rotate_axis = [0.3, 1.0, 0.2]
rotate_degrees = 20
young = 2e4
density = 500.0
[[body]]
name = "d"
shape = "sphere"
center = [0.45, 0.12, 0.0]
radius = 0.12
resolution = 3
young = 2e4
density = 500.0
[[body]]
name = "e"
shape = "sphere"
center = [-0.45, 0.12, 0.05]
radius = 0.12
resolution = 3
young = 2e4
density = 500.0
[[body]]
name = "f"
shape = "box"
min = [-0.6, 0.3, -0.1]
max = [-0.4, 0.5, 0.1]
cells = [2, 2, 2]
young = 2e4
density = 500.0
[[obstacle]]
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
[[obstacle]]
type = "plane"
point = [-0.62, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]
)toml";
} // namespace

TEST(SteadyState, TimeStepsWithoutContactAllocateNothing)
{
    CaseSpec spec = parse_case(PILE, "pile.toml");
    spec.contact.enabled = false;
    LoadedScene loaded = load_scene(spec);
    Simulation simulation(loaded.scene, spec);
    simulation.start();
    for (int step = 0; step < 3; ++step)
        simulation.step();
    test::AllocationCounter counter;
    ASSERT_TRUE(counter.active());
    for (int step = 0; step < 10; ++step)
        simulation.step();
    EXPECT_EQ(counter.count(), 0u);
}

TEST(SteadyState, TheCounterSeesAnAllocation)
{
    std::vector<double> grown;
    test::AllocationCounter counter;
    ASSERT_TRUE(counter.active());
    grown.resize(1000);
    EXPECT_GE(counter.count(), 1u);
}

TEST(SteadyState, TimeStepsWithContactAllocateNothing)
{
    const CaseSpec spec = parse_case(PILE, "pile.toml");
    LoadedScene loaded = load_scene(spec);
    Simulation simulation(loaded.scene, spec);
    simulation.start();
    // The buffers grow as pairs of bodies meet and contacts appear while the pile falls and
    // settles (here until step 165); then it rests on the planes with a few vertices of
    // bodies inside others, pairs parting and meeting again with the buffers they had.
    for (int step = 0; step < 200; ++step)
        simulation.step();
    const auto body_contacts = [&] {
        return std::count_if(loaded.scene.contacts.begin(), loaded.scene.contacts.end(),
                             [](const ContactPoint& point) { return point.other.is_surface(); });
    };
    ASSERT_GT(loaded.scene.contacts.size(), 20u) << "the pile should be in contact by now";
    ASSERT_GT(body_contacts(), 2) << "the bodies of the pile should be in contact with each other";
    test::AllocationCounter counter;
    ASSERT_TRUE(counter.active());
    for (int step = 0; step < 40; ++step)
        simulation.step();
    EXPECT_EQ(counter.count(), 0u);
    EXPECT_GT(body_contacts(), 2);
}
