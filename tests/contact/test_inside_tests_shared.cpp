#include "brute_force_nearest.hpp"
#include "contact_scenes.hpp"

#include <corocontact/contact/axis_ray.hpp>
#include <corocontact/core/primitives.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

using namespace coro;
using namespace coro::test;

namespace {

const AxisRayTolerances TOL;
const std::vector<Index> NO_FACES;

/// Distance from p to the surface, scanning every face.
double brute_force_distance(const ContactSurface& s, const Vec3& p)
{
    return std::sqrt(test::brute_force_nearest(s, p).squared_distance);
}

/// inside_tests_shared() against inside_test() on every point: the same `inside` everywhere,
/// every field for the points it tested, and for the others a point off the surface whose
/// distance bound holds. Points are passed in runs of `run` (one call each). Returns how many
/// took a neighbour's answer.
Index expect_shared_matches_single(const ContactSurface& b, const std::vector<Vec3>& points, Index run)
{
    std::vector<InsideTest> shared(points.size());
    Index reported = 0;
    for (std::size_t begin = 0; begin < points.size(); begin += static_cast<std::size_t>(run)) {
        const Index n = std::min<Index>(run, static_cast<Index>(points.size() - begin));
        reported += inside_tests_shared(b, points.data() + begin, n, DetectionMode::EXACT, NO_FACES, TOL,
                                        shared.data() + begin);
    }
    Index by_neighbour = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const InsideTest single = inside_test(b, points[i], DetectionMode::EXACT, NO_FACES, TOL);
        const InsideTest& s = shared[i];
        EXPECT_EQ(s.inside, single.inside) << "point " << i << " (" << points[i].transpose() << ")";
        if (s.deciding_axis != DECIDED_BY_NEIGHBOUR) {
            EXPECT_EQ(s.on_surface, single.on_surface) << "point " << i;
            EXPECT_EQ(s.deciding_axis, single.deciding_axis) << "point " << i;
            EXPECT_EQ(s.surface_distance_bound, single.surface_distance_bound) << "point " << i; // bitwise
            EXPECT_EQ(s.crossing_face, single.crossing_face) << "point " << i;
            continue;
        }
        ++by_neighbour;
        EXPECT_FALSE(single.on_surface) << "point " << i << " on the surface took a neighbour's answer";
        EXPECT_FALSE(s.on_surface);
        if (s.surface_distance_bound < std::numeric_limits<double>::infinity()) {
            EXPECT_GE(s.surface_distance_bound, brute_force_distance(b, points[i])) << "point " << i;
        }
    }
    EXPECT_EQ(reported, by_neighbour);
    return by_neighbour;
}

} // namespace

TEST(InsideTestsShared, DeepOverlapOfDeformedSpheresSharesMostAnswers)
{
    const ContactSurface a = deformed_ball(Vec3(0, 0, 0), 1.0, 14, 0.06, "A");
    const ContactSurface b = deformed_ball(Vec3(0.8, 0.1, -0.05), 0.9, 12, 0.05, "B");
    for (const auto& [x, y] : {std::pair{&a, &b}, std::pair{&b, &a}}) {
        const std::vector<Vec3> points = candidate_points(*x, *y);
        ASSERT_GT(points.size(), 400u);
        for (const Index run : {128, 37, 1000}) {
            const Index shared = expect_shared_matches_single(*y, points, run);
            EXPECT_GT(shared, static_cast<Index>(points.size()) / 3) << "run " << run;
        }
    }
}

TEST(InsideTestsShared, NonConvexBodiesAndClustersOfRandomPoints)
{
    TetMesh bar = make_box(Vec3(0, -0.5, -0.5), Vec3(4, 0.5, 0.5), {16, 4, 4});
    bar.rest_positions = twist_and_bend(bar.rest_positions, 0.6, 2.0);
    const SurfaceMesh torus_mesh = make_torus(Vec3(0.1, -0.2, 0.3), 1.0, 0.35, 48, 24);
    const ContactSurface bodies[] = {surface_of(bar, "bar"), surface_of(torus_mesh, "torus")};
    std::mt19937 rng(9);
    for (const ContactSurface& b : bodies) {
        const Aabb box = b.tree.bounds();
        std::vector<Vec3> points;
        // Clusters of close points, as detection sends them, inside, outside and straddling.
        for (int q = 0; q < 150; ++q) {
            const Vec3 c = random_point(box.min, box.max, rng);
            const double spread = q % 2 == 0 ? 0.03 : 0.3;
            for (int k = 0; k < 16; ++k)
                points.push_back(c + random_point(Vec3::Constant(-spread), Vec3::Constant(spread), rng));
        }
        EXPECT_GT(expect_shared_matches_single(b, points, 128), 200) << b.name;
    }
}

TEST(InsideTestsShared, PointsOnTouchingBoxesAreTestedThemselves)
{
    // Vertices on B's faces, edges and corners must never take a neighbour's answer: their
    // on_surface comes from their own test.
    const ContactSurface b = surface_of(make_box(Vec3(0, 0, 0), Vec3(1, 1, 1), {2, 2, 2}), "B");
    const ContactSurface touching[] = {
        surface_of(make_box(Vec3(1, 0, 0), Vec3(2, 1, 1), {4, 4, 4}), "face"),
        surface_of(make_box(Vec3(0.5, 0.5, 0.5), Vec3(1.5, 1.5, 1.5), {6, 6, 6}), "corner"),
        surface_of(make_box(Vec3(-0.5, -0.5, -0.5), Vec3(1.5, 1.5, 1.5), {8, 8, 8}), "around"),
    };
    Index on_surface = 0;
    for (const ContactSurface& a : touching) {
        const std::vector<Vec3> points = candidate_points(a, b);
        expect_shared_matches_single(b, points, 128);
        for (const Vec3& p : points)
            on_surface += inside_test(b, p, DetectionMode::EXACT, NO_FACES, TOL).on_surface ? 1 : 0;
    }
    EXPECT_GT(on_surface, 30);
}

TEST(InsideTestsShared, OpenSurfaceOrPaperModeTestsEveryPoint)
{
    SurfaceMesh open = make_torus(Vec3::Zero(), 1.0, 0.35, 24, 12);
    open.faces.conservativeResize(open.faces.rows() - 40, 3);
    ContactSurface s = surface_of(open, "open");
    s.closed = false;
    const ContactSurface closed = surface_of(make_torus(Vec3::Zero(), 1.0, 0.35, 24, 12), "closed");
    std::mt19937 rng(10);
    std::vector<Vec3> points;
    const Vec3 c(1.0, 0.0, 0.0);
    for (int k = 0; k < 64; ++k)
        points.push_back(c + random_point(Vec3::Constant(-0.1), Vec3::Constant(0.1), rng));
    std::vector<InsideTest> results(points.size());
    EXPECT_EQ(inside_tests_shared(s, points.data(), 64, DetectionMode::EXACT, NO_FACES, TOL, results.data()), 0);
    for (std::size_t i = 0; i < points.size(); ++i)
        EXPECT_EQ(results[i].deciding_axis, 3);
    std::vector<Index> faces(static_cast<std::size_t>(closed.faces.rows()));
    for (std::size_t f = 0; f < faces.size(); ++f)
        faces[f] = static_cast<Index>(f);
    EXPECT_EQ(inside_tests_shared(closed, points.data(), 64, DetectionMode::PAPER, faces, TOL, results.data()), 0);
    for (std::size_t i = 0; i < points.size(); ++i)
        EXPECT_NE(results[i].deciding_axis, DECIDED_BY_NEIGHBOUR);
}
