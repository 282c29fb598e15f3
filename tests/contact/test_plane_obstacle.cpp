#include "contact_scenes.hpp"

#include <corocontact/contact/plane_obstacle.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace coro;
using test::deformed_ball;
using test::random_point;

namespace {

/// Every vertex against every plane, as the definition says: the reference for the pruned search.
std::vector<ContactPoint> every_vertex_below(const std::vector<ContactSurface>& surfaces,
                                             const std::vector<PlaneObstacle>& planes)
{
    std::vector<ContactPoint> points;
    for (std::size_t b = 0; b < surfaces.size(); ++b)
        for (Index v = 0; v < surfaces[b].vertices.rows(); ++v)
            for (std::size_t k = 0; k < planes.size(); ++k) {
                const double height = (surfaces[b].vertices.row(v).transpose() - planes[k].point).dot(planes[k].normal);
                if (height >= 0.0)
                    continue;
                ContactPoint& point = points.emplace_back();
                point.body = static_cast<Index>(b);
                point.vertex = v;
                point.other = ContactTarget::plane(static_cast<Index>(k));
                point.depth = -height;
                point.normal = planes[k].normal;
            }
    return points;
}

void expect_same(const std::vector<ContactPoint>& found, const std::vector<ContactPoint>& expected)
{
    ASSERT_EQ(found.size(), expected.size());
    for (std::size_t i = 0; i < found.size(); ++i) {
        EXPECT_EQ(found[i].body, expected[i].body) << i;
        EXPECT_EQ(found[i].vertex, expected[i].vertex) << i;
        EXPECT_EQ(found[i].other.index, expected[i].other.index) << i;
        EXPECT_EQ(found[i].depth, expected[i].depth) << i; // bitwise: the same formula
        EXPECT_EQ(found[i].normal, expected[i].normal) << i;
    }
}

} // namespace

// Bodies wholly above a plane skip it; the answers stay those of every vertex against every
// plane, for planes that miss, cut or hold every body, 40 planes (past the 32 a mask tracks).
TEST(PlaneContacts, EqualEveryVertexAgainstEveryPlane)
{
    std::mt19937 rng(7);
    std::vector<ContactSurface> surfaces;
    for (int b = 0; b < 6; ++b)
        surfaces.push_back(deformed_ball(random_point(Vec3(-1, -1, -1), Vec3(1, 1, 1), rng), 0.3, 2, 0.1,
                                         "ball" + std::to_string(b)));
    std::normal_distribution<double> n;
    std::vector<PlaneObstacle> planes;
    for (int k = 0; k < 40; ++k) {
        PlaneObstacle plane;
        plane.normal = Vec3(n(rng), n(rng), n(rng)).normalized();
        plane.point = random_point(Vec3(-1.5, -1.5, -1.5), Vec3(1.5, 1.5, 1.5), rng);
        planes.push_back(plane);
    }
    std::vector<ContactPoint> found;
    PlaneContactScratch scratch;
    detect_plane_contacts(surfaces, static_cast<Index>(surfaces.size()), planes, found, scratch);
    const std::vector<ContactPoint> expected = every_vertex_below(surfaces, planes);
    EXPECT_GT(expected.size(), 100U);
    expect_same(found, expected);

    // The first 32 planes only: each body's mask decides alone.
    planes.resize(32);
    detect_plane_contacts(surfaces, static_cast<Index>(surfaces.size()), planes, found, scratch);
    expect_same(found, every_vertex_below(surfaces, planes));
}

// A plane through a body's lowest vertex, or just under or over it: only a vertex strictly below
// is in contact, whatever the box around the body says.
TEST(PlaneContacts, PlaneAtTheLowestVertexWithinRounding)
{
    std::vector<ContactSurface> surfaces{deformed_ball(Vec3(0.1, 0.7, -0.2), 0.3, 2, 0.1, "ball")};
    Index lowest = 0;
    const Positions& x = surfaces[0].vertices;
    for (Index v = 1; v < x.rows(); ++v)
        if (x(v, 1) < x(lowest, 1))
            lowest = v;
    const double y = x(lowest, 1);
    for (const double offset : {std::nextafter(y, -1.0), y, std::nextafter(y, 1.0), y + 1e-9, y - 1e-9}) {
        PlaneObstacle floor;
        floor.point = Vec3(0.0, offset, 0.0);
        floor.normal = Vec3::UnitY();
        const std::vector<ContactPoint> found = detect_plane_contacts(surfaces, 1, {floor});
        expect_same(found, every_vertex_below(surfaces, {floor}));
        EXPECT_EQ(found.size(), offset > y ? 1U : 0U) << offset - y;
    }
}
