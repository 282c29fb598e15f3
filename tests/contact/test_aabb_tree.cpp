#include "brute_force_nearest.hpp"
#include "contact_scenes.hpp"
#include "near.hpp"

#include <corocontact/contact/aabb_tree.hpp>
#include <corocontact/core/primitives.hpp>

#include "detail/axis_walk.hpp"
#include "detail/tree_access.hpp"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

using namespace coro;
using namespace coro::test;

namespace {

Vec3 vertex(const SurfaceMesh& m, Index f, int c) { return m.vertices.row(m.faces(f, c)).transpose(); }

Aabb face_box(const SurfaceMesh& m, Index f)
{
    Aabb box;
    for (int c = 0; c < 3; ++c)
        box.extend(vertex(m, f, c));
    return box;
}

// Independent closest point: the plane projection if it falls inside the triangle, else the
// nearest of the three edges (clamped segment parameter).
double reference_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c)
{
    const Vec3 n = (b - a).cross(c - a);
    const Vec3 q = p - n * (n.dot(p - a) / n.squaredNorm());
    Eigen::Matrix<double, 3, 2> e;
    e << b - a, c - a;
    const Eigen::Vector2d uv = e.colPivHouseholderQr().solve(q - a);
    if (uv[0] >= 0 && uv[1] >= 0 && uv[0] + uv[1] <= 1)
        return (p - q).norm();
    const auto segment = [&](const Vec3& x, const Vec3& y) {
        const double s = std::clamp((p - x).dot(y - x) / (y - x).squaredNorm(), 0.0, 1.0);
        return (p - (x + s * (y - x))).norm();
    };
    return std::min({segment(a, b), segment(b, c), segment(c, a)});
}

// Smooth deformation plus jitter, for refit tests.
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

void expect_queries_equal_brute_force(const AabbTree& tree, const SurfaceMesh& m, std::mt19937& rng, int queries)
{
    const Aabb bounds = tree.bounds();
    Aabb expected_bounds;
    for (Index f = 0; f < m.faces.rows(); ++f)
        expected_bounds.extend(face_box(m, f));
    ASSERT_EQ(bounds.min, expected_bounds.min);
    ASSERT_EQ(bounds.max, expected_bounds.max);
    const Vec3 lo = bounds.min.array() - 0.1, hi = bounds.max.array() + 0.1;
    std::uniform_real_distribution<double> extent(0.0, 0.4);
    std::vector<Index> got, want;
    for (int q = 0; q < queries; ++q) {
        // Boxes.
        const Vec3 corner = random_point(lo, hi, rng);
        const Aabb box{corner, corner + Vec3(extent(rng), extent(rng), extent(rng))};
        tree.faces_overlapping(m.vertices, box, got);
        want.clear();
        for (Index f = 0; f < m.faces.rows(); ++f)
            if (face_box(m, f).overlaps(box))
                want.push_back(f);
        ASSERT_EQ(got, want) << "box query " << q;

        // Vertices in the box.
        tree.vertices_in_box(m.vertices, box, got);
        std::sort(got.begin(), got.end());
        want.clear();
        for (const Index v : surface_vertices(m.faces)) // only vertices the faces use
            if (box.contains(m.vertices.row(v).transpose()))
                want.push_back(v);
        ASSERT_EQ(got, want) << "vertex query " << q;

        // Axis lines, with and without tolerance, and with a pruning visitor.
        const Vec3 p = random_point(lo, hi, rng);
        const int axis = q % 3;
        const double tolerance = q % 2 == 0 ? 0.0 : 0.01;
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        got.clear();
        detail::faces_on_axis_line(tree, m.vertices, p, axis, tolerance, [&](Index f, const Index* corners) {
            got.push_back(f);
            for (int c = 0; c < 3; ++c) // the face's vertices, in its order (orientation)
                ASSERT_EQ(corners[c], m.faces(f, c)) << "face " << f << " corner " << c;
        });
        std::sort(got.begin(), got.end());
        ASSERT_TRUE(std::adjacent_find(got.begin(), got.end()) == got.end()) << "a face visited twice";
        want.clear();
        std::vector<Index> want_near;
        const double cutoff = 0.15;
        for (Index f = 0; f < m.faces.rows(); ++f) {
            const Aabb b = face_box(m, f);
            if (p[u] >= b.min[u] - tolerance && p[u] <= b.max[u] + tolerance && p[v] >= b.min[v] - tolerance &&
                p[v] <= b.max[v] + tolerance) {
                want.push_back(f);
                if (std::max({b.min[axis] - p[axis], p[axis] - b.max[axis], 0.0}) <= cutoff)
                    want_near.push_back(f);
            }
        }
        ASSERT_EQ(got, want) << "axis query " << q;
        got.clear();
        detail::faces_on_axis_line(tree, m.vertices, p, axis, tolerance, [&](Index f, const Index*) {
            got.push_back(f);
            return cutoff;
        });
        std::sort(got.begin(), got.end());
        // Every face within the cutoff is visited; others only until the first value is returned.
        ASSERT_TRUE(std::includes(got.begin(), got.end(), want_near.begin(), want_near.end()))
            << "pruned axis query " << q;
        ASSERT_TRUE(std::includes(want.begin(), want.end(), got.begin(), got.end())) << "pruned axis query " << q;

        // Nearest point.
        const NearestPoint nearest = tree.nearest(m.vertices, p);
        double best = std::numeric_limits<double>::infinity();
        for (Index f = 0; f < m.faces.rows(); ++f)
            best = std::min(best, reference_distance(p, vertex(m, f, 0), vertex(m, f, 1), vertex(m, f, 2)));
        ASSERT_NEAR_REL(nearest.distance, best, 1e-12, 1e-9) << "nearest query " << q;
        ASSERT_GE(nearest.face, 0);
        const Vec3 rebuilt = nearest.barycentric[0] * vertex(m, nearest.face, 0) +
                             nearest.barycentric[1] * vertex(m, nearest.face, 1) +
                             nearest.barycentric[2] * vertex(m, nearest.face, 2);
        ASSERT_NEAR_REL(rebuilt, nearest.point, 1e-12, 0.0);
        ASSERT_NEAR_REL((nearest.point - p).norm(), nearest.distance, 1e-12, 1e-12);
    }
}

} // namespace

TEST(ClosestPointOnTriangle, MatchesPlaneOrEdgeReference)
{
    std::mt19937 rng(11);
    for (int trial = 0; trial < 2000; ++trial) {
        const Vec3 a = random_point(Vec3::Zero(), Vec3::Ones(), rng);
        const Vec3 b = random_point(Vec3::Zero(), Vec3::Ones(), rng);
        const Vec3 c = random_point(Vec3::Zero(), Vec3::Ones(), rng);
        const Vec3 p = random_point(Vec3::Constant(-1), Vec3::Constant(2), rng);
        const TrianglePoint q = closest_point_on_triangle(p, a, b, c);
        ASSERT_NEAR_REL((q.point - p).norm(), reference_distance(p, a, b, c), 1e-12, 1e-9) << "trial " << trial;
        ASSERT_GE(q.barycentric.minCoeff(), -1e-15);
        ASSERT_NEAR(q.barycentric.sum(), 1.0, 1e-12);
        ASSERT_NEAR_REL(Vec3(q.barycentric[0] * a + q.barycentric[1] * b + q.barycentric[2] * c), q.point, 1e-12, 0.0);
    }
    // A degenerate (collinear) triangle: the nearest point of the segment it spans.
    const TrianglePoint q = closest_point_on_triangle(Vec3(0.5, 1, 0), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0));
    EXPECT_NEAR_REL(q.point, Vec3(0.5, 0, 0), 1e-15, 0.0);
}

TEST(AabbTree, QueriesEqualBruteForceOnRandomTriangles)
{
    std::mt19937 rng(5);
    const SurfaceMesh m = random_triangles(700, rng);
    AabbTree tree;
    tree.build(m.vertices, m.faces);
    EXPECT_EQ(tree.num_faces(), 700);
    expect_queries_equal_brute_force(tree, m, rng, 300);
}

TEST(AabbTree, FacesBeyondTheFloatRangeHideNoOtherFace)
{
    // Random triangles near the origin and a few lying wholly beyond the float range (x from
    // 10³⁹ on, or below −10³⁹): their float boxes are clamped to the largest float, and no NaN
    // may reach a node's box and hide the faces beside them.
    std::mt19937 rng(17);
    SurfaceMesh m = random_triangles(60, rng);
    for (Index f = 0; f < 6; ++f)
        for (int c = 0; c < 3; ++c)
            m.vertices(m.faces(f, c), 0) = (f % 2 == 0 ? 1.0 : -1.0) * (1e39 + 1e38 * c + 1e37 * f);
    AabbTree tree;
    tree.build(m.vertices, m.faces);
    const auto brute_force = [&](const Aabb& box) {
        std::vector<Index> want;
        for (Index f = 0; f < m.faces.rows(); ++f)
            if (face_box(m, f).overlaps(box))
                want.push_back(f);
        return want;
    };
    std::vector<Index> got;
    const Aabb near{Vec3(-1, -1, -1), Vec3(2, 2, 2)};
    const Aabb far{Vec3(5e38, -1e300, -1e300), Vec3(1e300, 1e300, 1e300)};
    const Aabb far_below{Vec3(-1e300, -1e300, -1e300), Vec3(-5e38, 1e300, 1e300)};
    for (const Aabb& box : {near, far, far_below}) {
        tree.faces_overlapping(m.vertices, box, got);
        const std::vector<Index> want = brute_force(box);
        ASSERT_FALSE(want.empty());
        EXPECT_EQ(got, want);
    }
    // Axis lines along x through each face's centroid meet at least that face.
    for (Index f = 0; f < m.faces.rows(); ++f) {
        const Vec3 c = (vertex(m, f, 0) + vertex(m, f, 1) + vertex(m, f, 2)) / 3.0;
        bool met = false;
        detail::faces_on_axis_line(tree, m.vertices, c, 0, 0.0, [&](Index g, const Index*) { met = met || g == f; });
        EXPECT_TRUE(met) << "face " << f;
    }
    Aabb bounds;
    for (Index f = 0; f < m.faces.rows(); ++f)
        bounds.extend(face_box(m, f));
    EXPECT_EQ(tree.bounds().min, bounds.min);
    EXPECT_EQ(tree.bounds().max, bounds.max);
}

TEST(AabbTree, NodesHoldFourChildrenButOnePerLevel)
{
    // A node with four children adds three to the count of things to hold, so F faces need at
    // least ⌈(F − 1)/3⌉ nodes; the build may leave one node per level short. Splits at the plain
    // median made 853 nodes over the 1,728 faces of the 10k-tet sphere, where 577 do.
    std::mt19937 rng(9);
    for (const Index faces : {2, 3, 4, 5, 7, 17, 27, 100, 700, 1728, 8112}) {
        const SurfaceMesh m = random_triangles(faces, rng);
        AabbTree tree;
        tree.build(m.vertices, m.faces);
        Index levels = 0;
        for (Index capacity = 1; capacity < faces; capacity *= 4)
            ++levels;
        const auto nodes = static_cast<Index>(detail::TreeAccess::nodes(tree).size());
        EXPECT_GE(nodes, (faces - 1 + 2) / 3) << faces << " faces";
        EXPECT_LE(nodes, (faces - 1 + 2) / 3 + levels) << faces << " faces";
    }
}

TEST(AabbTree, QueriesEqualBruteForceAfterRefit)
{
    std::mt19937 rng(6);
    const TetMesh ball = make_sphere(Vec3(0.1, 0.2, 0.3), 0.8, 8);
    SurfaceMesh m{ball.rest_positions, boundary_faces(ball)};
    AabbTree tree;
    tree.build(m.vertices, m.faces);
    expect_queries_equal_brute_force(tree, m, rng, 150);
    m.vertices = deform(m.vertices, rng);
    tree.refit(m.vertices);
    expect_queries_equal_brute_force(tree, m, rng, 150);
}

TEST(AabbTree, LargeTreeRefitsInParallelAsSerially)
{
    // Enough faces for the level-by-level parallel refit; refit under 1 and 2 threads must give
    // the same queries as brute force on the deformed positions.
    std::mt19937 rng(8);
    SurfaceMesh m = random_triangles(40000, rng);
    AabbTree one, two;
    one.build(m.vertices, m.faces);
    two = one;
    m.vertices = deform(m.vertices, rng);
    tbb::task_arena(1).execute([&] { one.refit(m.vertices); });
    tbb::task_arena(2).execute([&] { two.refit(m.vertices); });
    for (AabbTree* tree : {&one, &two}) {
        const Vec3 p(0.5, 0.4, 0.6);
        std::vector<Index> got, want;
        const Aabb box{Vec3(0.3, 0.3, 0.3), Vec3(0.45, 0.5, 0.4)};
        tree->faces_overlapping(m.vertices, box, got);
        for (Index f = 0; f < m.faces.rows(); ++f)
            if (face_box(m, f).overlaps(box))
                want.push_back(f);
        ASSERT_EQ(got, want);
        ASSERT_FALSE(want.empty());
        double best = std::numeric_limits<double>::infinity();
        for (Index f = 0; f < m.faces.rows(); ++f)
            best = std::min(best, reference_distance(p, vertex(m, f, 0), vertex(m, f, 1), vertex(m, f, 2)));
        ASSERT_NEAR_REL(tree->nearest(m.vertices, p).distance, best, 1e-12, 1e-9);
    }
}

TEST(AabbTree, EmptyTreeAnswersNothing)
{
    AabbTree tree;
    tree.build(Positions(0, 3), Tris(0, 3));
    EXPECT_TRUE(tree.bounds().empty());
    std::vector<Index> out{1, 2};
    tree.faces_overlapping(Positions(0, 3), Aabb{Vec3::Zero(), Vec3::Ones()}, out);
    EXPECT_TRUE(out.empty());
    int visits = 0;
    detail::faces_on_axis_line(tree, Positions(0, 3), Vec3::Zero(), 0, 1.0, [&](Index, const Index*) { ++visits; });
    EXPECT_EQ(visits, 0);
    EXPECT_EQ(tree.nearest(Positions(0, 3), Vec3::Zero()).face, -1);
}

TEST(AabbTree, NearestAndAxisLineFromAFarPoint)
{
    // Squared distances beyond the float range: nothing may be pruned before a face is found.
    const ContactSurface s = surface_of(make_sphere(Vec3(0.0, 0.0, 0.0), 1.0, 6), "sphere");
    const Vec3 p(3e19, 1e19, -2e19);
    const NearestPoint got = s.tree.nearest(s.vertices, p);
    ASSERT_GE(got.face, 0);
    const double best = test::brute_force_nearest(s, p).squared_distance;
    EXPECT_EQ(got.distance, std::sqrt(best));
    // The x line through (−3e19, 0.1, 0.2) crosses the sphere: faces are visited.
    int visits = 0;
    detail::faces_on_axis_line(s.tree, s.vertices, Vec3(-3e19, 0.1, 0.2), 0, 0.0, [&](Index, const Index*) {
        ++visits;
        return std::numeric_limits<double>::infinity();
    });
    EXPECT_GT(visits, 0);
}

TEST(FloatRounding, StepsOutwardAndStaysFinite)
{
    // The outward rounding of the walks' boxes: a float below (above) x beyond the nearest one,
    // and for values beyond the float range the largest finite float of that sign, as the
    // library's fmin/fmax would clamp them.
    const float largest = std::numeric_limits<float>::max();
    const auto reference_down = [&](double x) {
        const float f = static_cast<float>(x);
        return std::fmin(f - (std::abs(f) * 0x1p-23f + 0x1p-126f), largest);
    };
    const auto reference_up = [&](double x) {
        const float f = static_cast<float>(x);
        return std::fmax(f + (std::abs(f) * 0x1p-23f + 0x1p-126f), -largest);
    };
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
    std::uniform_int_distribution<int> exponent(-150, 120);
    for (int i = 0; i < 20000; ++i) {
        const double x = std::ldexp(mantissa(rng), exponent(rng));
        const float down = detail::float_down(x), up = detail::float_up(x);
        EXPECT_LT(static_cast<double>(down), x) << x;
        EXPECT_GT(static_cast<double>(up), x) << x;
        EXPECT_LT(down, static_cast<float>(x)) << x;
        EXPECT_GT(up, static_cast<float>(x)) << x;
        EXPECT_EQ(down, reference_down(x)) << x;
        EXPECT_EQ(up, reference_up(x)) << x;
    }
    const double inf = std::numeric_limits<double>::infinity();
    for (const double x : {inf, 1e300, 3.5e38, -inf, -1e300, -3.5e38, std::nan(""), 0.0, -0.0}) {
        EXPECT_EQ(detail::float_down(x), reference_down(x)) << x;
        EXPECT_EQ(detail::float_up(x), reference_up(x)) << x;
    }
    EXPECT_EQ(detail::float_down(inf), largest);
    EXPECT_EQ(detail::float_up(-inf), -largest);
}
