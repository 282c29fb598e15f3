#include <corocontact/io/case_reader.hpp>
#include <corocontact/io/scene_loader.hpp>
#include <corocontact/sim/body_ownership.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

using namespace coro;

namespace {
// A row of `n` boxes along x, 0.3 apart, every third one four times as many tets.
std::vector<Body> row_of_boxes(int n)
{
    std::string text = "[simulation]\ndt = 0.01\nsteps = 1\n";
    for (int i = 0; i < n; ++i)
        text += "[[body]]\nname = \"b" + std::to_string(i) + "\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.2, 0.2, 0.2]\n" +
                "cells = " + (i % 3 == 0 ? "[2, 2, 1]" : "[1, 1, 1]") + "\ntranslate = [" + std::to_string(0.3 * i) +
                ", 0.0, 0.0]\n";
    return load_scene(parse_case(text, "row.toml")).scene.bodies;
}
} // namespace

TEST(AssignBodies, BalancesTetsOverTheRanks)
{
    const std::vector<Body> bodies = row_of_boxes(24);
    Index total = 0;
    for (const Body& body : bodies)
        total += body.mesh().num_tets();
    for (const Index ranks : {2, 3, 4}) {
        const BodyOwnership ownership = assign_bodies(bodies, ranks);
        std::vector<Index> tets(static_cast<std::size_t>(ranks), 0);
        for (std::size_t b = 0; b < bodies.size(); ++b)
            tets[static_cast<std::size_t>(ownership.owner[b])] += bodies[b].mesh().num_tets();
        // Whole bodies of 6 or 24 tets: within one large body of the mean.
        EXPECT_LE(*std::max_element(tets.begin(), tets.end()), total / ranks + 24) << ranks << " ranks";
        EXPECT_GT(*std::min_element(tets.begin(), tets.end()), 0) << ranks << " ranks";
    }
}

TEST(AssignBodies, KeepsNeighboursTogether)
{
    // Along a row, near bodies share an owner: a few runs of consecutive bodies, not a mix.
    const std::vector<Body> bodies = row_of_boxes(24);
    const BodyOwnership ownership = assign_bodies(bodies, 3);
    Index changes = 0;
    for (std::size_t b = 1; b < bodies.size(); ++b)
        changes += ownership.owner[b] != ownership.owner[b - 1] ? 1 : 0;
    EXPECT_LE(changes, 3);
}

TEST(AssignBodies, SameBodiesSameOwners)
{
    const std::vector<Body> bodies = row_of_boxes(17);
    EXPECT_EQ(assign_bodies(bodies, 3).owner, assign_bodies(bodies, 3).owner);
    EXPECT_EQ(assign_bodies(bodies, 1).owner, std::vector<Index>(17, 0));
    const std::vector<Index> of_one = assign_bodies(bodies, 2).bodies_of(1);
    EXPECT_TRUE(std::is_sorted(of_one.begin(), of_one.end()));
}
