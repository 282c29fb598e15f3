#include <corocontact/core/error.hpp>
#include <corocontact/core/primitives.hpp>
#include <corocontact/sim/divergence_check.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <cmath>
#include <limits>

using namespace coro;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

namespace {

BodySpec spec_named(const std::string& name)
{
    BodySpec spec;
    spec.name = name;
    return spec;
}

// A partitioned box, so internal and input numbering differ.
Body make_body(const std::string& name = "block")
{
    return Body(make_box(Vec3(0, 0, 0), Vec3(4, 1, 1), {8, 2, 2}), spec_named(name), 4);
}

Index internal_tet(const Body& body, Index input)
{
    for (Index t = 0; t < body.mesh().num_tets(); ++t)
        if (body.input_tet(t) == input)
            return t;
    return -1;
}

Index internal_node(const Body& body, Index input)
{
    for (Index v = 0; v < body.num_vertices(); ++v)
        if (body.input_node(v) == input)
            return v;
    return -1;
}

// Moves one node of internal tet t through its opposite face: J = −scale of the rest volume.
void invert(Body& body, Index t, double scale)
{
    VecX& x = body.positions();
    const auto corner = [&](int a) { return Vec3(x.segment<3>(3 * body.mesh().tets(t, a))); };
    const Vec3 p0 = corner(0), p1 = corner(1), p2 = corner(2), p3 = corner(3);
    // Reflect p3 through the plane of (p0, p1, p2), scaled: det changes sign.
    const Vec3 n = (p1 - p0).cross(p2 - p0).normalized();
    const double h = n.dot(p3 - p0);
    x.segment<3>(3 * body.mesh().tets(t, 3)) = p3 - (1.0 + scale) * h * n;
}

} // namespace

TEST(DivergenceCheck, RestStateAndRigidMotionPass)
{
    Body body = make_body();
    EXPECT_FALSE(find_divergence(body).found());
    for (Index v = 0; v < body.num_vertices(); ++v)
        body.positions().segment<3>(3 * v) = Vec3(-body.positions()[3 * v + 1], body.positions()[3 * v], 0.0) +
                                             Vec3(0.0, 0.0, body.positions()[3 * v + 2] + 5.0);
    EXPECT_FALSE(find_divergence(body).found());
    EXPECT_NO_THROW(check_divergence({body}));
}

TEST(DivergenceCheck, InversionThatContactProducesIsTolerated)
{
    Body body = make_body();
    invert(body, internal_tet(body, 17), 1.5); // J ≈ −1.5 for that tet (its neighbours change too)
    EXPECT_FALSE(find_divergence(body).found());
    EXPECT_TRUE(find_divergence(body, {-1.0, 30.0}).found()) << "the tet is inverted";
}

TEST(DivergenceCheck, NamesBodyAndLowestInputElement)
{
    Body body = make_body("left");
    // Displace one node far along an axis: every tet around it flips or blows up.
    const Index t = internal_tet(body, 40);
    invert(body, t, 6.0);
    const DivergenceFinding finding = find_divergence(body);
    ASSERT_TRUE(finding.found());
    EXPECT_LE(finding.volume_ratio, DivergenceLimits{}.min_volume_ratio);
    // The reported element is the lowest input index among all offenders.
    const Index moved = body.mesh().tets(t, 3);
    Index lowest = std::numeric_limits<Index>::max();
    for (Index e = 0; e < body.mesh().num_tets(); ++e)
        for (int a = 0; a < 4; ++a)
            if (body.mesh().tets(e, a) == moved) {
                const VecX& x = body.positions();
                const auto p = [&](int c) { return Vec3(x.segment<3>(3 * body.mesh().tets(e, c))); };
                const double j = (p(1) - p(0)).dot((p(2) - p(0)).cross(p(3) - p(0))) / (6.0 * body.fem().volumes()[static_cast<std::size_t>(e)]);
                if (j <= DivergenceLimits{}.min_volume_ratio || j >= DivergenceLimits{}.max_volume_ratio)
                    lowest = std::min(lowest, body.input_tet(e));
            }
    EXPECT_EQ(finding.element, lowest);
    EXPECT_THAT([&] { check_divergence({make_body("right"), body}); },
                ThrowsMessage<NumericalError>(AllOf(HasSubstr("body 'left'"),
                                                    HasSubstr("element " + std::to_string(lowest)),
                                                    HasSubstr("inverted beyond recovery: det F = -"))));
}

TEST(DivergenceCheck, BlownUpElement)
{
    Body body = make_body();
    const Index v = internal_node(body, 0); // a corner: only few tets touch it
    body.positions()[3 * v] -= 1e3;
    const DivergenceFinding finding = find_divergence(body);
    ASSERT_TRUE(finding.found());
    EXPECT_GE(finding.volume_ratio, DivergenceLimits{}.max_volume_ratio);
    EXPECT_THAT([&] { check_divergence({body}); }, ThrowsMessage<NumericalError>(HasSubstr("blown up")));
}

TEST(DivergenceCheck, NamesNonFiniteNodeInFileOrder)
{
    Body body = make_body("ball");
    body.positions()[3 * internal_node(body, 33) + 1] = std::numeric_limits<double>::infinity();
    body.positions()[3 * internal_node(body, 12) + 2] = std::nan("");
    const DivergenceFinding finding = find_divergence(body);
    EXPECT_EQ(finding.node, 12);
    EXPECT_THAT([&] { check_divergence({body}); },
                ThrowsMessage<NumericalError>(AllOf(HasSubstr("body 'ball'"), HasSubstr("node 12 "))));
}

TEST(DivergenceCheck, SameFindingForOneAndTwoThreads)
{
    Body body = make_body();
    for (const Index input : {90, 7, 150})
        invert(body, internal_tet(body, input), 5.0);
    DivergenceFinding found[2];
    for (int threads = 1; threads <= 2; ++threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
        found[threads - 1] = find_divergence(body);
    }
    ASSERT_TRUE(found[0].found());
    EXPECT_EQ(found[0].element, found[1].element);
    EXPECT_EQ(found[0].volume_ratio, found[1].volume_ratio);
}
