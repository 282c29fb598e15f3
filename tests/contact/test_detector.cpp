#include "brute_force_nearest.hpp"
#include "contact_scenes.hpp"
#include "near.hpp"

#include <corocontact/contact/detector.hpp>
#include <corocontact/core/primitives.hpp>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <tuple>

using namespace coro;
using namespace coro::test;

namespace {

ContactSurface box_surface(const Vec3& min, const Vec3& max, const std::array<Index, 3>& cells, const std::string& name)
{
    return surface_of(make_box(min, max, cells), name);
}

using Key = std::tuple<Index, Index, Index>;
Key key(const ContactPoint& c)
{
    EXPECT_TRUE(c.other.is_surface());
    return {c.body, c.vertex, c.other.index};
}

std::vector<Key> keys(const std::vector<ContactPoint>& points)
{
    std::vector<Key> out;
    for (const ContactPoint& c : points)
        out.push_back(key(c));
    return out;
}

/// Every vertex of every body against every other body with the brute-force inside test.
std::vector<Key> brute_force_contacts(const std::vector<ContactSurface>& surfaces)
{
    std::vector<Key> out;
    for (std::size_t a = 0; a < surfaces.size(); ++a)
        for (Index v = 0; v < surfaces[a].vertices.rows(); ++v)
            for (std::size_t b = 0; b < surfaces.size(); ++b)
                if (a != b && inside_test(surfaces[b], surfaces[a].vertices.row(v).transpose(),
                                          DetectionMode::BRUTE_FORCE, {}, AxisRayTolerances())
                                  .inside)
                    out.emplace_back(static_cast<Index>(a), v, static_cast<Index>(b));
    return out;
}

std::vector<ContactSurface> pile_scene()
{
    std::vector<ContactSurface> s;
    s.push_back(deformed_ball(Vec3(0, 0, 0), 1.0, 10, 0.08, "ball0"));
    s.push_back(deformed_ball(Vec3(1.3, 0.2, -0.1), 0.8, 9, 0.05, "ball1"));
    s.push_back(box_surface(Vec3(-0.4, 0.6, -0.5), Vec3(0.9, 1.4, 0.4), {5, 3, 4}, "box2"));
    s.push_back(box_surface(Vec3(5, 5, 5), Vec3(6, 6, 6), {1, 1, 1}, "far3"));
    s.push_back(deformed_ball(Vec3(0.6, -0.9, 0.3), 0.5, 8, 0.1, "ball4"));
    return s;
}

} // namespace

TEST(DetectContacts, ExactEqualsBruteForceOnEveryVertexOfAPile)
{
    const std::vector<ContactSurface> surfaces = pile_scene();
    DetectionStats stats;
    const auto points = detect_contacts(surfaces, DetectionSettings{}, &stats);
    const auto expected = brute_force_contacts(surfaces);
    EXPECT_EQ(keys(points), expected);
    EXPECT_GT(expected.size(), 100u);
    // Some vertices are inside two bodies: the output orders their points by the other body.
    Index in_two = 0;
    for (std::size_t i = 1; i < expected.size(); ++i)
        in_two += std::get<0>(expected[i]) == std::get<0>(expected[i - 1]) &&
                          std::get<1>(expected[i]) == std::get<1>(expected[i - 1])
                      ? 1
                      : 0;
    EXPECT_GT(in_two, 0);
    EXPECT_EQ(stats.inside, static_cast<Index>(points.size()));
    // Without depth and normal the points are made from the candidates, not from slots.
    DetectionSettings inside_only;
    inside_only.contact_data = false;
    EXPECT_EQ(keys(detect_contacts(surfaces, inside_only)), expected);
    Index pairs = 0;
    for (std::size_t a = 0; a < surfaces.size(); ++a)
        for (std::size_t b = a + 1; b < surfaces.size(); ++b)
            pairs += bounding_box(surfaces[a].vertices).overlaps(bounding_box(surfaces[b].vertices)) ? 1 : 0;
    EXPECT_EQ(stats.pairs, pairs);
    EXPECT_GE(pairs, 4);
    EXPECT_GT(stats.candidate_vertices, stats.inside);
}

TEST(DetectContacts, OneAndTwoThreadsGiveIdenticalContacts)
{
    const std::vector<ContactSurface> surfaces = pile_scene();
    for (const DetectionMode mode : {DetectionMode::EXACT, DetectionMode::PAPER}) {
        DetectionSettings settings;
        settings.mode = mode;
        std::vector<ContactPoint> one, two;
        DetectionStats s1, s2;
        tbb::task_arena(1).execute([&] { one = detect_contacts(surfaces, settings, &s1); });
        tbb::task_arena(2).execute([&] { two = detect_contacts(surfaces, settings, &s2); });
        ASSERT_EQ(one.size(), two.size());
        ASSERT_GT(one.size(), 100u);
        for (std::size_t i = 0; i < one.size(); ++i) {
            ASSERT_EQ(key(one[i]), key(two[i])) << "contact " << i;
            ASSERT_EQ(one[i].depth, two[i].depth) << "contact " << i; // bitwise
            ASSERT_EQ(one[i].normal, two[i].normal) << "contact " << i;
            ASSERT_EQ(one[i].face, two[i].face) << "contact " << i;
            ASSERT_EQ(one[i].barycentric, two[i].barycentric) << "contact " << i;
        }
        EXPECT_EQ(s1.candidate_vertices, s2.candidate_vertices);
        EXPECT_EQ(s1.inside, s2.inside);
        EXPECT_TRUE(std::is_sorted(one.begin(), one.end(),
                                   [](const ContactPoint& a, const ContactPoint& b) { return key(a) < key(b); }));
    }
}

TEST(DetectContacts, SharedAnswersChangeNothingButTheWork)
{
    // Deep overlap: most candidate vertices take the answer of their clear-edge group's first.
    std::vector<ContactSurface> surfaces = pile_scene();
    surfaces.push_back(deformed_ball(Vec3(0.3, 0.1, 0.0), 0.9, 12, 0.06, "deep5"));
    DetectionSettings shared, each;
    each.share_answers = false;
    DetectionStats s1, s2;
    const auto a = detect_contacts(surfaces, shared, &s1);
    const auto b = detect_contacts(surfaces, each, &s2);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(key(a[i]), key(b[i])) << "contact " << i;
        ASSERT_EQ(a[i].depth, b[i].depth) << "contact " << i; // bitwise
        ASSERT_EQ(a[i].normal, b[i].normal) << "contact " << i;
        ASSERT_EQ(a[i].face, b[i].face) << "contact " << i;
        ASSERT_EQ(a[i].barycentric, b[i].barycentric) << "contact " << i;
    }
    EXPECT_EQ(keys(a), brute_force_contacts(surfaces));
    EXPECT_EQ(s1.candidate_vertices, s2.candidate_vertices);
    EXPECT_EQ(s1.inside, s2.inside);
    EXPECT_GT(s1.by_neighbour, s1.candidate_vertices / 4);
    EXPECT_EQ(s2.by_neighbour, 0);
}

TEST(DetectContacts, PairsWithFewCandidatesTestEveryCandidate)
{
    // Two balls that barely touch have a handful of candidates: each is tested (grouping them
    // would cost more than the tests it saves). Pushed deep into each other they have hundreds,
    // and most take a neighbour's answer. Both give the brute-force answers.
    for (const double gap : {1.97, 1.2}) {
        std::vector<ContactSurface> surfaces;
        surfaces.push_back(deformed_ball(Vec3(0, 0, 0), 1.0, 12, 0.06, "a"));
        surfaces.push_back(deformed_ball(Vec3(gap, 0.05, -0.03), 1.0, 12, 0.06, "b"));
        DetectionStats stats;
        const auto points = detect_contacts(surfaces, DetectionSettings{}, &stats);
        EXPECT_EQ(keys(points), brute_force_contacts(surfaces)) << "gap " << gap;
        EXPECT_EQ(stats.pairs, 1);
        if (gap > 1.5) {
            ASSERT_GT(stats.inside, 0);
            ASSERT_LT(stats.candidate_vertices, 64);
            EXPECT_EQ(stats.by_neighbour, 0);
        } else {
            ASSERT_GE(stats.candidate_vertices, 64);
            EXPECT_GT(stats.by_neighbour, stats.candidate_vertices / 4);
        }
    }
}

TEST(DetectContacts, DepthNormalAndFaceAreTheBruteForceNearestPointOfEveryContact)
{
    // Every inside vertex's nearest point, against a scan of every face of the other surface
    // (closest_point_on_triangle, the smallest face index of equally near ones): the same face
    // and depth bit for bit, that face's unit normal, the point's barycentric weights. A pile and
    // a deep overlap, where many vertices lie far inside (nearly equally far from much of the
    // other surface).
    std::vector<ContactSurface> deep;
    deep.push_back(deformed_ball(Vec3(0, 0, 0), 1.0, 12, 0.06, "a"));
    deep.push_back(deformed_ball(Vec3(0.6, 0.05, -0.03), 1.0, 11, 0.05, "b"));
    for (const std::vector<ContactSurface>& surfaces : {pile_scene(), deep}) {
        const auto points = detect_contacts(surfaces, DetectionSettings{});
        ASSERT_GT(points.size(), 200u);
        double deepest = 0.0;
        for (const ContactPoint& c : points) {
            const ContactSurface& b = surfaces[static_cast<std::size_t>(c.other.index)];
            const Vec3 p = surfaces[static_cast<std::size_t>(c.body)].vertices.row(c.vertex).transpose();
            const test::BruteForceNearest brute = test::brute_force_nearest(b, p);
            ASSERT_EQ(c.face, brute.face) << c.body << " vertex " << c.vertex;
            ASSERT_EQ(c.depth, std::sqrt(brute.squared_distance)) << c.body << " vertex " << c.vertex;
            const Vec3 x0 = b.vertices.row(b.faces(c.face, 0)).transpose();
            const Vec3 x1 = b.vertices.row(b.faces(c.face, 1)).transpose();
            const Vec3 x2 = b.vertices.row(b.faces(c.face, 2)).transpose();
            ASSERT_EQ(c.normal, (x1 - x0).cross(x2 - x0).normalized());
            const TrianglePoint t = closest_point_on_triangle(p, x0, x1, x2);
            ASSERT_EQ(c.barycentric, t.barycentric);
            deepest = std::max(deepest, c.depth);
        }
        EXPECT_GT(deepest, 0.2);
    }
}

TEST(DetectContacts, AScratchKeptFromCallToCallChangesNoAnswer)
{
    // One scratch through scenes of different sizes and back, with and without contact data:
    // every answer bit for bit that of a scratch of its own.
    std::vector<ContactSurface> deep = pile_scene();
    deep.push_back(deformed_ball(Vec3(0.3, 0.1, 0.0), 0.9, 12, 0.06, "deep5"));
    const std::vector<ContactSurface> two{deformed_ball(Vec3(0, 0, 0), 1.0, 9, 0.06, "a"),
                                          deformed_ball(Vec3(0.8, 0.1, 0.0), 0.8, 8, 0.05, "b")};
    DetectionSettings inside_only;
    inside_only.contact_data = false;
    DetectionScratch scratch;
    for (int round = 0; round < 2; ++round)
        for (const std::vector<ContactSurface>* surfaces : std::array<const std::vector<ContactSurface>*, 3>{&deep, &two, &deep})
            for (const DetectionSettings& settings : {DetectionSettings{}, inside_only}) {
                const auto kept = detect_contacts(*surfaces, settings, scratch);
                const auto own = detect_contacts(*surfaces, settings);
                ASSERT_EQ(kept.size(), own.size());
                ASSERT_FALSE(own.empty());
                for (std::size_t i = 0; i < own.size(); ++i) {
                    ASSERT_EQ(key(kept[i]), key(own[i])) << "contact " << i;
                    ASSERT_EQ(kept[i].depth, own[i].depth) << "contact " << i;
                    ASSERT_EQ(kept[i].face, own[i].face) << "contact " << i;
                    ASSERT_EQ(kept[i].normal, own[i].normal) << "contact " << i;
                }
            }
}

TEST(DetectContacts, DepthAndNormalOfSmallBoxesPushedIntoALargeBox)
{
    // B = [0, 10]³. A small box enters B's +x face by 0.2, another its −y face by 0.3, a third
    // its +z face by 0.05: their inner vertices are inside with exactly these depths.
    std::vector<ContactSurface> s;
    s.push_back(box_surface(Vec3(0, 0, 0), Vec3(10, 10, 10), {2, 2, 2}, "B"));
    s.push_back(box_surface(Vec3(9.8, 4.1, 3.2), Vec3(10.6, 4.9, 4.4), {1, 1, 1}, "px"));
    s.push_back(box_surface(Vec3(6.1, -0.7, 2.2), Vec3(7.3, 0.3, 3.1), {1, 1, 1}, "my"));
    s.push_back(box_surface(Vec3(3.3, 7.1, 9.95), Vec3(3.9, 7.6, 11), {1, 1, 1}, "pz"));
    const auto points = detect_contacts(s, DetectionSettings{});
    ASSERT_EQ(points.size(), 12u); // 4 vertices of each small box; none of B's are inside them
    const std::map<Index, std::pair<double, Vec3>> expected{
        {1, {0.2, Vec3(1, 0, 0)}}, {2, {0.3, Vec3(0, -1, 0)}}, {3, {0.05, Vec3(0, 0, 1)}}};
    for (const ContactPoint& c : points) {
        ASSERT_EQ(c.other, ContactTarget::surface(0));
        const auto& [depth, normal] = expected.at(c.body);
        const Vec3 p = s[static_cast<std::size_t>(c.body)].vertices.row(c.vertex).transpose();
        EXPECT_NEAR_REL(c.depth, depth, 1e-12, 1e-9) << s[static_cast<std::size_t>(c.body)].name;
        EXPECT_NEAR_REL(c.normal, normal, 1e-12, 0.0);
        // The nearest point, rebuilt from face and barycentric weights, is p moved along n by depth.
        const ContactSurface& b = s[0];
        Vec3 q = Vec3::Zero();
        for (int k = 0; k < 3; ++k)
            q += c.barycentric[k] * b.vertices.row(b.faces(c.face, k)).transpose();
        EXPECT_NEAR_REL(q, Vec3(p + depth * normal), 1e-12, 1e-12);
    }
    // Without contact data: the same vertices, depth and face left at their defaults.
    DetectionSettings inside_only;
    inside_only.contact_data = false;
    const auto bare = detect_contacts(s, inside_only);
    EXPECT_EQ(keys(bare), keys(points));
    for (const ContactPoint& c : bare) {
        EXPECT_EQ(c.depth, 0.0);
        EXPECT_EQ(c.face, -1);
    }
}

TEST(DetectContacts, PaperModeMissesALargeFaceCrossingTheOverlap)
{
    // B is a slab of two cells whose faces are large; A pokes into its top face. I = AABB(A) ∩
    // AABB(B) holds no vertex of B, so the paper's candidate faces (a vertex in I) are none and
    // A's inside vertices are missed; exact mode searches B's whole surface along the axis lines.
    std::vector<ContactSurface> s;
    s.push_back(box_surface(Vec3(0, 0, 0), Vec3(10, 10, 1), {1, 1, 1}, "slab"));
    s.push_back(box_surface(Vec3(4.2, 4.6, 0.5), Vec3(5.1, 5.3, 1.5), {1, 1, 1}, "peg"));
    const auto candidates = contact_candidates(s, DetectionMode::PAPER);
    ASSERT_EQ(candidates.size(), 2u);
    EXPECT_TRUE(candidates[1].faces.empty()); // peg → slab: no candidate face
    EXPECT_EQ(candidates[1].vertices.size(), 4u); // the peg's vertices in I: the lower four

    DetectionSettings paper;
    paper.mode = DetectionMode::PAPER;
    EXPECT_TRUE(detect_contacts(s, paper).empty());
    const auto exact = detect_contacts(s, DetectionSettings{});
    ASSERT_EQ(exact.size(), 4u); // the peg's four lower vertices (z = 0.5)
    for (const ContactPoint& c : exact) {
        EXPECT_EQ(c.body, 1);
        EXPECT_NEAR(c.depth, 0.5, 1e-12);
    }
}

TEST(DetectContacts, PaperModeDecidesWronglyOnAFartherCandidateFace)
{
    // B is one surface of two boxes: a slab of large faces, z ∈ [0, 1], and above it a block,
    // z ∈ [2, 3], whose bottom face has a vertex at its centre (4.5, 4.5, 2). A post from inside
    // the slab into the block: its lower corners are inside the slab, but the slab's top face,
    // their nearest crossing along z, has no vertex in I and is no paper candidate; the next
    // crossing is the block's bottom face (a candidate, its centre vertex is in I), whose outward
    // normal points toward the corner: paper mode says outside. Exact mode finds the slab's face.
    const TetMesh slab = make_box(Vec3(0, 0, 0), Vec3(10, 10, 1), {1, 1, 1});
    const TetMesh block = make_box(Vec3(4, 4, 2), Vec3(5, 5, 3), {2, 2, 1});
    Positions v(slab.num_vertices() + block.num_vertices(), 3);
    v << slab.rest_positions, block.rest_positions;
    Tris fb = boundary_faces(block);
    fb.array() += slab.num_vertices();
    const Tris fs = boundary_faces(slab);
    Tris faces(fs.rows() + fb.rows(), 3);
    faces << fs, fb;
    std::vector<ContactSurface> s;
    s.push_back(ContactSurface::from_body("slab+block", v, faces));
    s.push_back(box_surface(Vec3(4.42, 4.38, 0.5), Vec3(4.61, 4.57, 2.3), {1, 1, 1}, "post"));
    ASSERT_TRUE(s[0].closed);

    const auto exact = detect_contacts(s, DetectionSettings{});
    std::vector<Key> expected;
    for (Index i = 0; i < s[0].vertices.rows(); ++i)
        if (s[0].vertices.row(i) == Eigen::RowVector3d(4.5, 4.5, 2))
            expected.emplace_back(0, i, 1); // the block's bottom centre is inside the post
    ASSERT_EQ(expected.size(), 1u);
    for (Index i = 0; i < 8; ++i)
        expected.emplace_back(1, i, 0); // all eight corners of the post are inside B
    EXPECT_EQ(keys(exact), expected);

    DetectionSettings paper;
    paper.mode = DetectionMode::PAPER;
    const auto by_paper = detect_contacts(s, paper);
    std::vector<Key> expected_paper{expected[0]};
    for (Index i = 0; i < 8; ++i)
        if (s[1].vertices(i, 2) > 2.0)
            expected_paper.emplace_back(1, i, 0); // only the upper corners
    EXPECT_EQ(keys(by_paper), expected_paper);
    const std::vector<Index> none;
    for (Index i = 0; i < 8; ++i)
        if (s[1].vertices(i, 2) < 1.0) {
            const auto candidates = contact_candidates(s, DetectionMode::PAPER);
            EXPECT_EQ(axis_test(s[0], s[1].vertices.row(i).transpose(), 2, DetectionMode::PAPER, candidates[1].faces,
                                AxisRayTolerances()),
                      AxisOutcome::OUTSIDE);
        }
}

TEST(DetectContacts, CallerSuppliedInsideTestRunsTheSamePipeline)
{
    const std::vector<ContactSurface> surfaces = pile_scene();
    DetectionStats stats, stats_fn;
    const auto points = detect_contacts(surfaces, DetectionSettings{}, &stats);
    CustomNarrowPhase brute;
    brute.inside = [&](Index other, const Vec3& p) {
        return inside_test(surfaces[static_cast<std::size_t>(other)], p, DetectionMode::BRUTE_FORCE, {},
                           AxisRayTolerances());
    };
    const auto via_function = detect_contacts(surfaces, brute, true, &stats_fn);
    EXPECT_EQ(keys(points), keys(via_function));
    EXPECT_EQ(stats.candidate_vertices, stats_fn.candidate_vertices);
    for (std::size_t i = 0; i < points.size(); ++i) { // the trees' depth searches: the same answers
        ASSERT_EQ(points[i].depth, via_function[i].depth) << "contact " << i;
        ASSERT_EQ(points[i].face, via_function[i].face) << "contact " << i;
    }
    // A caller's depth search too: its answers are taken as they come.
    brute.nearest = [&](Index other, const Vec3& p, double) {
        const ContactSurface& b = surfaces[static_cast<std::size_t>(other)];
        NearestPoint n;
        const test::BruteForceNearest f = test::brute_force_nearest(b, p);
        n.face = f.face;
        n.distance = std::sqrt(f.squared_distance);
        const TrianglePoint t = closest_point_on_triangle(p, b.vertices.row(b.faces(f.face, 0)).transpose(),
                                                          b.vertices.row(b.faces(f.face, 1)).transpose(),
                                                          b.vertices.row(b.faces(f.face, 2)).transpose());
        n.point = t.point;
        n.barycentric = t.barycentric;
        return n;
    };
    const auto with_nearest = detect_contacts(surfaces, brute, true);
    ASSERT_EQ(with_nearest.size(), points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
        ASSERT_EQ(points[i].depth, with_nearest[i].depth) << "contact " << i;
        ASSERT_EQ(points[i].normal, with_nearest[i].normal) << "contact " << i;
    }
}

TEST(ContactCandidates, VerticesInsideTheOverlapAndThePapersFaces)
{
    const std::vector<ContactSurface> surfaces = pile_scene();
    const auto candidates = contact_candidates(surfaces, DetectionMode::PAPER);
    ASSERT_GE(candidates.size(), 8u);
    for (const PairCandidates& c : candidates) {
        const ContactSurface& a = surfaces[static_cast<std::size_t>(c.body)];
        const ContactSurface& b = surfaces[static_cast<std::size_t>(c.other)];
        const Aabb I = bounding_box(a.vertices).intersection(bounding_box(b.vertices));
        std::vector<Index> want;
        for (Index v = 0; v < a.vertices.rows(); ++v)
            if (I.contains(a.vertices.row(v).transpose()))
                want.push_back(v);
        std::vector<Index> got = c.vertices;
        std::sort(got.begin(), got.end());
        EXPECT_EQ(got, want) << c.body << " in " << c.other;
        want.clear();
        for (Index f = 0; f < b.faces.rows(); ++f)
            for (int k = 0; k < 3; ++k)
                if (I.contains(b.vertices.row(b.faces(f, k)).transpose())) {
                    want.push_back(f);
                    break;
                }
        EXPECT_EQ(c.faces, want) << c.body << " in " << c.other;
    }
    EXPECT_TRUE(std::is_sorted(candidates.begin(), candidates.end(), [](const auto& x, const auto& y) {
        return std::tie(x.body, x.other) < std::tie(y.body, y.other);
    }));
}
