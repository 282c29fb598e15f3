#include <corocontact/contact/contact_surface.hpp>
#include <corocontact/contact/detector.hpp>
#include <corocontact/core/error.hpp>
#include <corocontact/core/primitives.hpp>
#include <corocontact/core/surface_mesh.hpp>

#include "detail/tree_access.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <string>
#include <vector>

namespace coro {
namespace {

/// Node positions of `mesh` moved by a smooth field that differs per body.
Positions moved(const TetMesh& mesh, double phase)
{
    Positions x = mesh.rest_positions;
    for (Index i = 0; i < x.rows(); ++i) {
        x(i, 0) += 0.08 * std::sin(3.0 * x(i, 1) + phase);
        x(i, 1) += 0.05 * std::cos(2.0 * x(i, 2) - phase);
        x(i, 2) -= 0.1 * x(i, 0) * x(i, 0);
    }
    return x;
}

void expect_same_surfaces(const std::vector<ContactSurface>& a, const std::vector<ContactSurface>& b)
{
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t s = 0; s < a.size(); ++s) {
        EXPECT_EQ(a[s].vertices, b[s].vertices) << "surface " << s; // bitwise
        EXPECT_EQ(a[s].tree.bounds().min, b[s].tree.bounds().min) << "surface " << s;
        EXPECT_EQ(a[s].tree.bounds().max, b[s].tree.bounds().max) << "surface " << s;
    }
}

TEST(UpdateSurfaces, EqualsUpdatingEachInTurnAndLeavesTheRestAlone)
{
    // Three bodies (one large enough that its vertex copy and its refit are split into tasks of
    // their own) and a fourth surface, an obstacle, that is not given positions.
    std::vector<TetMesh> meshes{make_sphere(Vec3(0, 0, 0), 1.0, 20), make_sphere(Vec3(1.2, 0.1, 0), 0.8, 6),
                                make_sphere(Vec3(0.2, 1.1, 0.3), 0.7, 4), make_sphere(Vec3(0, 0, -1.5), 0.9, 5)};
    std::vector<ContactSurface> start;
    for (std::size_t b = 0; b < meshes.size(); ++b)
        start.push_back(ContactSurface::from_body("body" + std::to_string(b), meshes[b].rest_positions,
                                                  boundary_faces(meshes[b])));
    ASSERT_GT(start[0].vertices.rows(), 2048); // ContactSurface::update copies in tasks from 2,048
    std::vector<Positions> positions;
    for (std::size_t b = 0; b < 3; ++b)
        positions.push_back(moved(meshes[b], static_cast<double>(b)));

    std::vector<ContactSurface> in_turn = start, together = start, through_maps = start;
    for (std::size_t b = 0; b < positions.size(); ++b)
        in_turn[b].update(positions[b]);
    update_surfaces(together, positions);
    std::vector<Eigen::Map<const Positions>> maps;
    for (const Positions& p : positions)
        maps.emplace_back(p.data(), p.rows(), 3);
    update_surfaces(through_maps, maps);

    expect_same_surfaces(together, in_turn);
    expect_same_surfaces(through_maps, in_turn);
    EXPECT_EQ(together[3].vertices, start[3].vertices);
    EXPECT_EQ(through_maps[3].vertices, start[3].vertices);
    EXPECT_NE(together[0].vertices, start[0].vertices);
    // The trees answer as the trees refit one by one.
    const std::vector<ContactPoint> expected = detect_contacts(in_turn, DetectionSettings{});
    const std::vector<ContactPoint> got = detect_contacts(together, DetectionSettings{});
    // More position sets than surfaces is an input error, not a write past the end.
    std::vector<ContactSurface> two(start.begin(), start.begin() + 2);
    EXPECT_THROW(update_surfaces(two, positions), InputError);
    ASSERT_FALSE(expected.empty());
    ASSERT_EQ(got.size(), expected.size());
    for (std::size_t i = 0; i < got.size(); ++i) {
        EXPECT_EQ(got[i].body, expected[i].body);
        EXPECT_EQ(got[i].vertex, expected[i].vertex);
        EXPECT_EQ(got[i].other, expected[i].other);
        EXPECT_EQ(got[i].depth, expected[i].depth);
    }
}

TEST(SurfaceEdges, ListEveryEdgeFromBothEndsWithItsFacesAndTheirTreeSlots)
{
    const TetMesh ball = make_sphere(Vec3(0.1, 0.2, 0.3), 0.7, 6);
    const ContactSurface s = ContactSurface::from_body("ball", ball.rest_positions, boundary_faces(ball));
    // Brute force: each unordered vertex pair that is a side of some face, with those faces.
    std::set<std::array<Index, 2>> sides;
    for (Index f = 0; f < s.faces.rows(); ++f)
        for (int c = 0; c < 3; ++c)
            sides.insert({std::min(s.faces(f, c), s.faces(f, (c + 1) % 3)), std::max(s.faces(f, c), s.faces(f, (c + 1) % 3))});
    const SurfaceEdges& e = s.edges;
    ASSERT_EQ(e.start.size(), static_cast<std::size_t>(s.vertices.rows()) + 1);
    ASSERT_EQ(e.vertex.size(), 2 * sides.size());
    ASSERT_EQ(e.faces.size(), e.vertex.size());
    ASSERT_EQ(e.tree_slots.size(), e.vertex.size());
    const auto& face_of_slot = detail::TreeAccess::face_of_slot(s.tree);
    for (Index v = 0; v < s.vertices.rows(); ++v) {
        for (Index k = e.start[static_cast<std::size_t>(v)]; k < e.start[static_cast<std::size_t>(v) + 1]; ++k) {
            const auto kk = static_cast<std::size_t>(k);
            const Index w = e.vertex[kk];
            EXPECT_EQ(sides.count({std::min(v, w), std::max(v, w)}), 1u) << v << "-" << w;
            if (k > e.start[static_cast<std::size_t>(v)]) {
                EXPECT_LT(e.vertex[kk - 1], w) << "edges of " << v << " ordered by their other end";
            }
            for (int j = 0; j < 2; ++j) {
                const Index f = e.faces[kk][static_cast<std::size_t>(j)];
                const auto row = s.faces.row(f);
                EXPECT_TRUE((row.array() == v).any() && (row.array() == w).any()) << "face " << f;
                EXPECT_EQ(face_of_slot[static_cast<std::size_t>(e.tree_slots[kk][static_cast<std::size_t>(j)])], f);
            }
            EXPECT_NE(e.faces[kk][0], e.faces[kk][1]); // a closed surface: two faces per edge
        }
    }
}

TEST(SurfaceEdges, DetectionRefusesASurfaceWhoseEdgesWereNotBuiltWithIt)
{
    const TetMesh box = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1), {2, 2, 2});
    const TetMesh other = make_box(Vec3(0.5, 0.5, 0.5), Vec3(1.5, 1.5, 1.5), {2, 2, 2});
    std::vector<ContactSurface> surfaces{ContactSurface::from_body("a", box.rest_positions, boundary_faces(box)),
                                         ContactSurface::from_body("b", other.rest_positions, boundary_faces(other))};
    surfaces[0].edges = surface_edges(surfaces[0].faces, static_cast<Index>(surfaces[0].vertices.rows()));
    EXPECT_THAT([&] { detect_contacts(surfaces, DetectionSettings{}); },
                testing::ThrowsMessage<InputError>(testing::HasSubstr("surface 'a'")));
}

} // namespace
} // namespace coro
