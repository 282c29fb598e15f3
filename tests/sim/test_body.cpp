#include "beams.hpp"

#include <corocontact/core/error.hpp>
#include <corocontact/sim/body.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

using namespace coro;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

TEST(Body, LoadIsSplitEquallyOverNodesInTheBox)
{
    test::Cantilever beam;
    beam.tip_force = Vec3(0.0, -9.0, 3.0);
    const Body body = beam.body();
    // 3×3 nodes on the tip face.
    Vec3 total = Vec3::Zero();
    for (Index v = 0; v < body.num_vertices(); ++v) {
        const Vec3 f = body.load_forces().segment<3>(3 * v);
        if (body.mesh().rest_positions(v, 0) > beam.length - 1e-9)
            EXPECT_NEAR((f - Vec3(0.0, -1.0, 1.0 / 3.0)).norm(), 0.0, 1e-15);
        else
            EXPECT_EQ(f.norm(), 0.0);
        total += f;
    }
    EXPECT_NEAR((total - beam.tip_force).norm(), 0.0, 1e-14);
}

TEST(Body, FixedBoxHoldsItsNodesAndZeroesTheirVelocity)
{
    test::Cantilever beam;
    BodySpec spec = beam.spec();
    spec.velocity = Vec3(1, 2, 3);
    const Body body(make_box(spec.box_min, spec.box_max, spec.cells), spec);
    for (Index v = 0; v < body.num_vertices(); ++v) {
        const bool clamped = body.mesh().rest_positions(v, 0) == 0.0;
        EXPECT_EQ(body.fixed()[static_cast<std::size_t>(v)] != 0, clamped);
        EXPECT_EQ(body.velocities().segment<3>(3 * v), clamped ? Vec3::Zero() : Vec3(1, 2, 3));
    }
}

TEST(Body, EmptyFixedOrLoadBoxIsAnInputError)
{
    test::Cantilever beam;
    BodySpec spec = beam.spec();
    spec.location = "case.toml:12";
    spec.fixed[0].min = Vec3(100, 100, 100);
    spec.fixed[0].max = Vec3(101, 101, 101);
    EXPECT_THAT([&] { Body(make_box(spec.box_min, spec.box_max, spec.cells), spec); },
                ThrowsMessage<InputError>(HasSubstr("case.toml:12: body 'beam', [[body.fixed]] 0")));
    spec = beam.spec();
    spec.location = "case.toml:12";
    BoxLoad load;
    load.min = Vec3(-5, -5, -5);
    load.max = Vec3(-4, -4, -4);
    spec.loads.push_back(load);
    EXPECT_THAT([&] { Body(make_box(spec.box_min, spec.box_max, spec.cells), spec); },
                ThrowsMessage<InputError>(HasSubstr("[[body.load]] 0")));
}
