#include "brute_force_nearest.hpp"
#include "contact_scenes.hpp"

#include <corocontact/core/primitives.hpp>

#include "detail/nearest_search.hpp"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <limits>
#include <random>

using namespace coro;
using namespace coro::test;

namespace {

Positions deform(CRef<Positions> p, std::mt19937& rng)
{
    std::uniform_real_distribution<double> jitter(-0.02, 0.02);
    Positions out(p.rows(), 3);
    for (Eigen::Index i = 0; i < p.rows(); ++i) {
        const double x = p(i, 0), y = p(i, 1), z = p(i, 2);
        out.row(i) << x + 0.3 * std::sin(2 * y) + jitter(rng), y + 0.2 * z * z + jitter(rng),
            z - 0.25 * x * y + jitter(rng);
    }
    return out;
}

/// Query points around a surface: deep inside (many faces nearly equally far, where box and
/// plane bounds prune hardest), near it, outside, and on the grid planes of a structured box
/// (faces exactly tied).
Vec3 query_point(const ContactSurface& s, int q, std::mt19937& rng)
{
    const Aabb box = s.tree.bounds();
    Vec3 p = random_point(box.min.array() - 0.2, box.max.array() + 0.2, rng);
    if (q % 3 == 0)
        p = 0.5 * (box.min + box.max) + 0.1 * (p - 0.5 * (box.min + box.max));
    if (q % 5 == 0)
        p = (p * 6.0).array().round() / 6.0;
    return p;
}

void expect_brute_force(const ContactSurface& s, const NearestPoint& got, const Vec3& p, const std::string& what)
{
    const BruteForceNearest brute = brute_force_nearest(s, p);
    ASSERT_EQ(got.face, brute.face) << what;
    ASSERT_EQ(got.distance, std::sqrt(brute.squared_distance)) << what;
    const TrianglePoint t = closest_point_on_triangle(p, s.vertices.row(s.faces(got.face, 0)).transpose(),
                                                      s.vertices.row(s.faces(got.face, 1)).transpose(),
                                                      s.vertices.row(s.faces(got.face, 2)).transpose());
    ASSERT_EQ(got.point, t.point) << what;
    ASSERT_EQ(got.barycentric, t.barycentric) << what;
}

} // namespace

TEST(NearestSearch, IsTheBruteForceMinimumWithSmallestFaceOnTies)
{
    // The answer must be, bit for bit, the minimum over all faces of (computed squared
    // distance, face index): with the boxes only (AabbTree::nearest), with face planes, and
    // after a refit to deformed positions with the planes forgotten (reset) and computed anew.
    std::mt19937 rng(12);
    for (ContactSurface s : {surface_of(make_sphere(Vec3(0.1, -0.2, 0.05), 1.0, 10), "sphere"),
                             surface_of(make_box(Vec3(0, 0, 0), Vec3(1, 2, 1), {3, 6, 3}), "box")}) {
        detail::FacePlaneCache planes;
        for (int round = 0; round < 2; ++round) {
            planes.reset(s.tree);
            const detail::NearestSearch with_planes(s.tree, s.vertices, &planes);
            for (int q = 0; q < 300; ++q) {
                const Vec3 p = query_point(s, q, rng);
                const std::string what = s.name + " round " + std::to_string(round) + " query " + std::to_string(q);
                expect_brute_force(s, s.tree.nearest(s.vertices, p), p, what + " (boxes)");
                expect_brute_force(s, with_planes.find(p), p, what + " (planes)");
            }
            s.vertices = deform(s.vertices, rng);
            s.tree.refit(s.vertices);
        }
    }
}

TEST(NearestSearch, StartsFromHintsAndBoundsGiveTheSameAnswerBitForBit)
{
    std::mt19937 rng(7);
    for (const ContactSurface& s : {surface_of(make_sphere(Vec3(0.1, -0.2, 0.05), 1.0, 8), "sphere"),
                                    surface_of(make_box(Vec3(0, 0, 0), Vec3(1, 2, 1), {3, 6, 3}), "box")}) {
        detail::FacePlaneCache planes;
        planes.reset(s.tree);
        const detail::NearestSearch search(s.tree, s.vertices, &planes);
        Index previous = -1;
        for (int q = 0; q < 400; ++q) {
            const Vec3 p = query_point(s, q, rng);
            const NearestPoint plain = search.find(p);
            const Index random_face = std::uniform_int_distribution<Index>(0, s.tree.num_faces() - 1)(rng);
            const double bounds[] = {std::numeric_limits<double>::infinity(), plain.distance,
                                     plain.distance * 1.5 + 1e-3};
            for (const double bound : bounds)
                for (const Index hint : {Index{-1}, plain.face, random_face, previous}) {
                    const NearestPoint started = search.find(p, bound, hint, &s.faces);
                    ASSERT_EQ(started.face, plain.face) << s.name << " query " << q;
                    ASSERT_EQ(started.distance, plain.distance) << s.name << " query " << q;
                    ASSERT_EQ(started.point, plain.point) << s.name << " query " << q;
                    ASSERT_EQ(started.barycentric, plain.barycentric) << s.name << " query " << q;
                }
            // A bound below the true distance (a wrong start) still gives the right answer.
            EXPECT_EQ(search.find(p, 0.5 * plain.distance).face, plain.face);
            EXPECT_EQ(search.find(p, 0.5 * plain.distance, random_face, &s.faces).face, plain.face);
            previous = plain.face;
        }
    }
}

TEST(NearestSearch, ThreadsSharingOnePlaneCacheGetTheBruteForceAnswers)
{
    // Two threads search the same large tree at once: they claim, compute and read the planes
    // of the nodes concurrently (a node another thread computes is searched without its planes).
    std::mt19937 rng(13);
    ContactSurface s = surface_of(make_sphere(Vec3(0.0, 0.0, 0.0), 1.0, 24), "large sphere");
    s.vertices = deform(s.vertices, rng);
    s.tree.refit(s.vertices);
    ASSERT_GT(s.faces.rows(), 6000);
    std::vector<Vec3> points;
    for (int q = 0; q < 80; ++q)
        points.push_back(random_point(Vec3::Constant(q % 2 == 0 ? -0.3 : -1.2), Vec3::Constant(q % 2 == 0 ? 0.3 : 1.2), rng));
    detail::FacePlaneCache planes;
    for (int round = 0; round < 2; ++round) {
        planes.reset(s.tree);
        const detail::NearestSearch search(s.tree, s.vertices, &planes);
        std::vector<NearestPoint> got(points.size());
        tbb::task_arena(2).execute([&] {
            tbb::parallel_for(std::size_t{0}, points.size(), [&](std::size_t i) { got[i] = search.find(points[i]); });
        });
        for (std::size_t i = 0; i < points.size(); ++i)
            expect_brute_force(s, got[i], points[i], "round " + std::to_string(round) + " query " + std::to_string(i));
    }
}

TEST(NearestSearch, PlanesOfDegenerateFacesPruneNothing)
{
    // A surface with collinear and repeated-vertex faces among good ones: their planes are
    // "none" (infinite slack) and their points are still found.
    Positions v(6, 3);
    v << 0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 1, 1, 0.5, 0, 0, 1;
    Tris f(5, 3);
    f << 0, 1, 2, // collinear
        0, 1, 3, 1, 4, 3, 0, 0, 5, // a repeated vertex
        3, 4, 5;
    const ContactSurface s = surface_of(SurfaceMesh{v, f}, "degenerate");
    detail::FacePlaneCache planes;
    planes.reset(s.tree);
    const detail::NearestSearch search(s.tree, s.vertices, &planes);
    std::mt19937 rng(3);
    for (int q = 0; q < 200; ++q) {
        const Vec3 p = random_point(Vec3::Constant(-1), Vec3::Constant(3), rng);
        expect_brute_force(s, search.find(p), p, "query " + std::to_string(q));
    }
    expect_brute_force(s, search.find(Vec3(1.5, -0.5, 0.0)), Vec3(1.5, -0.5, 0.0), "beside the collinear face");
}
