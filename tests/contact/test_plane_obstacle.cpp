#include "contact_scenes.hpp"

#include <corocontact/contact/plane_obstacle.hpp>
#include <corocontact/core/primitives.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace coro;
using test::deformed_ball;
using test::random_point;
using test::surface_of;

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
    // Both paths ran: bodies wholly above one of the first 32 planes (skipped), and contacts
    // with the planes after them (always tested).
    Index above = 0;
    for (const ContactSurface& surface : surfaces)
        for (std::size_t k = 0; k < 32; ++k) {
            const Eigen::VectorXd heights = (surface.vertices.rowwise() - planes[k].point.transpose()) * planes[k].normal;
            above += heights.minCoeff() > 0.01 ? 1 : 0;
        }
    EXPECT_GT(above, 20);
    EXPECT_TRUE(std::any_of(expected.begin(), expected.end(), [](const ContactPoint& p) { return p.other.index >= 32; }));

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

// Oblique planes through a box's corner vertex, moved by a few ulps either way: the lowest
// corner of the box is that vertex, so whether the box lies above the plane is decided within
// rounding, and the vertex's own height may round either way.
TEST(PlaneContacts, ObliquePlanesThroughACornerWithinRounding)
{
    const Vec3 corner(0.3, -0.7, 1.1);
    std::vector<ContactSurface> surfaces{surface_of(make_box(corner, corner + Vec3(0.4, 0.5, 0.6), {2, 2, 2}), "box")};
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0.1, 1.0);
    Index touching = 0;
    for (int trial = 0; trial < 200; ++trial) {
        PlaneObstacle plane;
        plane.normal = Vec3(u(rng), u(rng), u(rng)).normalized(); // the corner is the lowest point
        plane.point = corner;
        const int steps = trial % 7 - 3;
        for (int i = 0; i < 3; ++i)
            for (int s = 0; s < std::abs(steps); ++s)
                plane.point[i] = std::nextafter(plane.point[i], steps > 0 ? 10.0 : -10.0);
        const std::vector<ContactPoint> found = detect_plane_contacts(surfaces, 1, {plane});
        const std::vector<ContactPoint> expected = every_vertex_below(surfaces, {plane});
        expect_same(found, expected);
        touching += expected.empty() ? 0 : 1;
    }
    EXPECT_GT(touching, 10); // the corner's height rounds below zero in some trials
    EXPECT_LT(touching, 190);
}

// A vertex that no face uses (an embedded surface may keep such rows) is tested like the rest,
// though the tree's box does not hold it.
TEST(PlaneContacts, AVertexNoFaceUsesIsTested)
{
    ContactSurface surface = surface_of(make_box(Vec3(0, 1, 0), Vec3(1, 2, 1), {1, 1, 1}), "box");
    const Index rows = surface.vertices.rows();
    surface.vertices.conservativeResize(rows + 1, 3);
    surface.vertices.row(rows) << 0.5, 0.5, 0.5; // below the faces' box, and below the floor
    PlaneObstacle floor;
    floor.point = Vec3(0.0, 0.75, 0.0);
    floor.normal = Vec3::UnitY();
    const std::vector<ContactSurface> surfaces{surface};
    const std::vector<ContactPoint> found = detect_plane_contacts(surfaces, 1, {floor});
    ASSERT_EQ(found.size(), 1U);
    EXPECT_EQ(found[0].vertex, rows);
    EXPECT_DOUBLE_EQ(found[0].depth, 0.25);
}
