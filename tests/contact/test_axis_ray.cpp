#include "contact_scenes.hpp"

#include <corocontact/contact/axis_ray.hpp>
#include <corocontact/contact/winding_number.hpp>
#include <corocontact/core/primitives.hpp>

#include "detail/inside_tests.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>

using namespace coro;
using namespace coro::test;

namespace {

const AxisRayTolerances TOL;
const std::vector<Index> NO_FACES;

InsideTest exact(const ContactSurface& s, const Vec3& p) { return inside_test(s, p, DetectionMode::EXACT, NO_FACES, TOL); }

std::vector<Index> all_faces(const ContactSurface& s)
{
    std::vector<Index> faces(static_cast<std::size_t>(s.faces.rows()));
    for (std::size_t f = 0; f < faces.size(); ++f)
        faces[f] = static_cast<Index>(f);
    return faces;
}

bool strictly_inside(const Vec3& p, const Vec3& min, const Vec3& max)
{
    return (p.array() > min.array()).all() && (p.array() < max.array()).all();
}
bool in_closed(const Vec3& p, const Vec3& min, const Vec3& max)
{
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
}

/// A sphere mesh's surface with the band in which its discrete surface may lie: every point
/// closer to the centre than `inner` is inside the mesh, every point farther than `outer` outside.
struct MeshBall {
    ContactSurface surface;
    Vec3 center;
    double inner = 0.0, outer = 0.0;
};

MeshBall mesh_ball(const Vec3& center, double radius, Index resolution, double degrees, const std::string& name)
{
    TetMesh mesh = make_sphere(Vec3::Zero(), radius, resolution);
    BodyTransform transform;
    transform.rotate_axis = Vec3(1, 2, 3);
    transform.rotate_degrees = degrees;
    transform.translate = center;
    transform.apply(mesh.rest_positions);
    MeshBall ball{surface_of(mesh, name), center};
    const ContactSurface& s = ball.surface;
    // Every face sees the centre on its inner side (n·(a − c) > 0), so each ray from the centre
    // crosses the closed surface exactly once: the mesh is star-shaped about c. A ray's crossing is
    // then no nearer than the nearest face plane (inner) and no farther than the farthest vertex.
    ball.inner = radius;
    for (Index f = 0; f < s.faces.rows(); ++f) {
        const Vec3 a = s.vertices.row(s.faces(f, 0)).transpose();
        const Vec3 n = (s.vertices.row(s.faces(f, 1)).transpose() - a).cross(s.vertices.row(s.faces(f, 2)).transpose() - a);
        const double h = n.normalized().dot(a - center);
        EXPECT_GT(h, 0.0) << name << " face " << f << " does not face away from the centre";
        ball.inner = std::min(ball.inner, h);
    }
    for (Index v = 0; v < s.vertices.rows(); ++v)
        ball.outer = std::max(ball.outer, (s.vertices.row(v).transpose() - center).norm());
    return ball;
}

/// Every vertex of `a` outside the band of `b` against |p − c| < r; returns how many were checked.
std::array<int, 2> expect_vertices_match_ball(const MeshBall& a, const MeshBall& b)
{
    std::array<int, 2> checked{0, 0}; // outside, inside
    for (Index v = 0; v < a.surface.vertices.rows(); ++v) {
        const Vec3 p = a.surface.vertices.row(v).transpose();
        const double r = (p - b.center).norm();
        if (r >= b.inner - 1e-12 && r <= b.outer + 1e-12)
            continue; // within the chord band: the analytic sphere does not decide
        const bool expected = r < b.inner;
        EXPECT_EQ(exact(b.surface, p).inside, expected)
            << a.surface.name << " vertex " << v << " at distance " << r << " from " << b.surface.name
            << "'s centre (band " << b.inner << ".." << b.outer << ")";
        ++checked[expected ? 1 : 0];
    }
    return checked;
}

/// Exact mode on every vertex of `a` against box surface `b` spanning [min, max]: inside iff
/// strictly inside; on the closed box's boundary ⇒ on the surface, not inside.
int expect_vertices_match_box(const ContactSurface& a, const ContactSurface& b, const Vec3& min, const Vec3& max,
                              DetectionMode mode = DetectionMode::EXACT)
{
    int fallbacks = 0;
    for (Index v = 0; v < a.vertices.rows(); ++v) {
        const Vec3 p = a.vertices.row(v).transpose();
        const InsideTest r = inside_test(b, p, mode, NO_FACES, TOL);
        const bool inside = strictly_inside(p, min, max);
        const bool on = !inside && in_closed(p, min, max);
        EXPECT_EQ(r.inside, inside) << a.name << " vertex " << v << " (" << p.transpose() << ") in " << b.name;
        EXPECT_EQ(r.on_surface, on) << a.name << " vertex " << v << " (" << p.transpose() << ") on " << b.name;
        fallbacks += r.decided_by == DecidedBy::EXACT_PARITY ? 1 : 0;
    }
    return fallbacks;
}

struct BoxSpec {
    Vec3 min, max;
    std::array<Index, 3> cells;
};

ContactSurface box_surface(const BoxSpec& spec, const std::string& name)
{
    return surface_of(make_box(spec.min, spec.max, spec.cells), name);
}

/// The octahedron |x| + |y| + |z| ≤ 1, faces wound outward: its faces are tilted to every axis.
ContactSurface unit_octahedron()
{
    Positions v(6, 3);
    v << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
    Tris f(8, 3);
    f << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
    return ContactSurface::from_body("octahedron", v, f);
}

} // namespace

TEST(InsideTest, SphereVerticesAgainstAnalyticSphere)
{
    struct Case {
        Vec3 ca;
        Index res_a;
        Vec3 cb;
        double rb;
        Index res_b;
    };
    const Case cases[] = {{Vec3(0, 0, 0), 8, Vec3(0.8, 0.3, -0.2), 0.9, 10},  // deep overlap
                          {Vec3(0, 0, 0), 9, Vec3(1.7, 0.2, 0.1), 0.8, 7},    // shallow
                          {Vec3(0, 0, 0), 12, Vec3(0.1, -0.05, 0.02), 0.4, 6}}; // B inside A
    int total_inside = 0, total_outside = 0;
    for (const Case& c : cases) {
        const MeshBall a = mesh_ball(c.ca, 1.0, c.res_a, 17.0, "A");
        const MeshBall b = mesh_ball(c.cb, c.rb, c.res_b, -31.0, "B");
        ASSERT_LT(b.outer - b.inner, 0.05); // the band is thin: few vertices skipped
        const auto ab = expect_vertices_match_ball(a, b);
        const auto ba = expect_vertices_match_ball(b, a);
        total_outside += ab[0] + ba[0];
        total_inside += ab[1] + ba[1];
    }
    EXPECT_GT(total_inside, 200);
    EXPECT_GT(total_outside, 200);
}

TEST(InsideTest, DecidingCrossingBoundsTheDepth)
{
    // The closest clean crossing of the deciding axis is a surface point: the nearest one is no
    // farther (the nearest-point search starts from this bound).
    const MeshBall a = mesh_ball(Vec3(0, 0, 0), 1.0, 10, 17.0, "A");
    const MeshBall b = mesh_ball(Vec3(0.8, 0.3, -0.2), 0.9, 10, -31.0, "B");
    int decided = 0;
    for (Index v = 0; v < a.surface.vertices.rows(); ++v) {
        const Vec3 p = a.surface.vertices.row(v).transpose();
        const InsideTest r = exact(b.surface, p);
        if (!r.inside || axis_of(r.decided_by) < 0)
            continue;
        ++decided;
        ASSERT_GE(r.crossing_face, 0);
        ASSERT_LT(r.crossing_face, b.surface.faces.rows());
        const double nearest = b.surface.tree.nearest(b.surface.vertices, p).distance;
        ASSERT_GE(r.surface_distance_bound, nearest) << "vertex " << v;
    }
    EXPECT_GT(decided, 100);
}

TEST(InsideTest, StructuredBoxesTouchingAndOverlapping)
{
    const BoxSpec b_spec{Vec3(0, 0, 0), Vec3(1, 1, 1), {2, 2, 2}};
    const ContactSurface b = box_surface(b_spec, "B");
    const BoxSpec cases[] = {
        {Vec3(1, 0, 0), Vec3(2, 1, 1), {2, 2, 2}},                // face to face, vertices on vertices
        {Vec3(1, 1, 1), Vec3(2, 2, 2), {1, 1, 1}},                // corner on corner
        {Vec3(1, 1, 0.25), Vec3(2, 2, 1.25), {2, 2, 2}},          // vertices on an edge
        {Vec3(1, 0.1, 0.2), Vec3(2, 1.3, 1.4), {2, 2, 2}},        // vertices strictly inside faces
        {Vec3(0.75, 0.25, 0.25), Vec3(1.75, 1.25, 1.25), {4, 4, 4}}, // overlap by exact amounts
        {Vec3(0.5, 0.5, 0.5), Vec3(1.5, 1.5, 1.5), {2, 2, 2}},    // projections on B's grid vertices
        {Vec3(0.25, 0.25, 0.25), Vec3(0.75, 0.75, 0.75), {2, 2, 2}}, // contained
        {Vec3(-0.5, -0.5, -0.5), Vec3(1.5, 1.5, 1.5), {4, 4, 4}}, // containing, sharing B's grid lines
        {Vec3(0, 0, 1), Vec3(1, 1, 2), {3, 3, 1}},                // stacked, offset grid on the face
    };
    int fallbacks = 0;
    for (const BoxSpec& spec : cases) {
        const ContactSurface a = box_surface(spec, "A");
        fallbacks += expect_vertices_match_box(a, b, b_spec.min, b_spec.max);
        fallbacks += expect_vertices_match_box(b, a, spec.min, spec.max);
        expect_vertices_match_box(a, b, b_spec.min, b_spec.max, DetectionMode::BRUTE_FORCE);
    }
    EXPECT_GT(fallbacks, 0); // some vertices project onto edges on all three axes
}

TEST(InsideTest, RandomBoxesOnACoarseGrid)
{
    // Corners on a 1/8 grid around B: vertices on B's faces, edges and grid lines all the time.
    std::mt19937 rng(21);
    std::uniform_int_distribution<int> coord(-4, 12);
    std::uniform_int_distribution<int> cells(1, 3);
    const BoxSpec b_spec{Vec3(0, 0, 0), Vec3(1, 1, 1), {2, 3, 2}};
    const ContactSurface b = box_surface(b_spec, "B");
    for (int trial = 0; trial < 60; ++trial) {
        BoxSpec spec;
        for (int k = 0; k < 3; ++k) {
            int lo = coord(rng), hi = coord(rng);
            if (lo == hi)
                ++hi;
            spec.min[k] = std::min(lo, hi) / 8.0;
            spec.max[k] = std::max(lo, hi) / 8.0;
            spec.cells[static_cast<std::size_t>(k)] = cells(rng);
        }
        const ContactSurface a = box_surface(spec, "A");
        SCOPED_TRACE("trial " + std::to_string(trial));
        expect_vertices_match_box(a, b, b_spec.min, b_spec.max);
        expect_vertices_match_box(b, a, spec.min, spec.max);
    }
}

TEST(InsideTest, RotatedBoxWithFacesParallelToOneAxis)
{
    // B = [−0.5, 0.5]² × [0, 1] turned 30° about z: its sides are parallel to z only; top and
    // bottom stay exactly in the planes z = 0 and z = 1.
    TetMesh mesh = make_box(Vec3(-0.5, -0.5, 0), Vec3(0.5, 0.5, 1), {2, 2, 2});
    const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
        const double x = mesh.rest_positions(v, 0), y = mesh.rest_positions(v, 1);
        mesh.rest_positions(v, 0) = c * x - s * y;
        mesh.rest_positions(v, 1) = s * x + c * y;
    }
    const ContactSurface b = surface_of(mesh, "B");
    std::mt19937 rng(4);
    int inside = 0, on = 0, checked = 0;
    for (int q = 0; q < 3000; ++q) {
        Vec3 p = random_point(Vec3(-0.9, -0.9, -0.3), Vec3(0.9, 0.9, 1.3), rng);
        const double zs[] = {0.0, 1.0, 0.5, 0.25};
        if (q % 2 == 0)
            p.z() = zs[q / 2 % 4]; // in the top or bottom plane, or on the grid's levels
        const double lx = c * p.x() + s * p.y(), ly = -s * p.x() + c * p.y();
        const double side = std::max(std::abs(lx), std::abs(ly));
        if (std::abs(side - 0.5) < 1e-9)
            continue; // within rounding of a side: no exact expectation
        const bool expected_inside = side < 0.5 && p.z() > 0.0 && p.z() < 1.0;
        const bool expected_on = side < 0.5 && (p.z() == 0.0 || p.z() == 1.0);
        const InsideTest r = exact(b, p);
        ASSERT_EQ(r.inside, expected_inside) << "point " << p.transpose();
        ASSERT_EQ(r.on_surface, expected_on) << "point " << p.transpose();
        inside += expected_inside;
        on += expected_on;
        ++checked;
    }
    EXPECT_GT(inside, 300);
    EXPECT_GT(on, 100);
    EXPECT_GT(checked, 2900);
}

namespace {

/// Exact (and brute-force) mode against the generalized winding number and ray parity along a
/// random direction, on random points in the surface's box.
void expect_matches_references(const ContactSurface& b, int queries, unsigned seed)
{
    ASSERT_TRUE(b.closed);
    std::mt19937 rng(seed);
    const Aabb box = b.tree.bounds().inflated(0.05);
    int inside = 0;
    for (int q = 0; q < queries; ++q) {
        const Vec3 p = random_point(box.min, box.max, rng);
        const double w = winding_number(b.vertices, b.faces, p);
        ASSERT_LT(std::abs(w - std::round(w)), 1e-6) << "point " << p.transpose() << " is near the surface";
        const bool parity = ray_parity_inside(b.vertices, b.faces, p, rng);
        ASSERT_EQ(parity, w > 0.5) << "the references disagree at " << p.transpose();
        ASSERT_EQ(exact(b, p).inside, parity) << "point " << q << " " << p.transpose() << ", w = " << w;
        ASSERT_EQ(inside_test(b, p, DetectionMode::BRUTE_FORCE, NO_FACES, TOL).inside, parity);
        inside += parity;
    }
    EXPECT_GT(inside, queries / 10);
    EXPECT_LT(inside, queries - queries / 10);
}

} // namespace

TEST(InsideTest, TwistedBentBarAgainstWindingNumberAndRayParity)
{
    TetMesh bar = make_box(Vec3(0, -0.5, -0.5), Vec3(4, 0.5, 0.5), {16, 4, 4});
    bar.rest_positions = twist_and_bend(bar.rest_positions, 0.6, 2.0);
    const ContactSurface b = surface_of(bar, "bar");
    expect_matches_references(b, 800, 31);
    // Vertices of a ball cutting through the bend, too.
    const TetMesh ball = make_sphere(Vec3(1.2, 0.6, 0.1), 0.7, 8);
    const ContactSurface a = surface_of(ball, "ball");
    std::mt19937 rng(2);
    for (Index v = 0; v < a.vertices.rows(); ++v) {
        const Vec3 p = a.vertices.row(v).transpose();
        ASSERT_EQ(exact(b, p).inside, ray_parity_inside(b.vertices, b.faces, p, rng)) << "ball vertex " << v;
    }
}

TEST(InsideTest, TorusAgainstWindingNumberAndRayParity)
{
    const SurfaceMesh torus = make_torus(Vec3(0.1, -0.2, 0.3), 1.0, 0.35, 48, 24);
    ASSERT_TRUE(check_surface(torus.faces).closed_and_oriented());
    ASSERT_GT(enclosed_volume(torus.vertices, torus.faces), 0.0);
    const ContactSurface b = surface_of(torus, "torus");
    expect_matches_references(b, 1000, 41);
}

TEST(InsideTest, OpenSurfaceUsesTheWindingNumber)
{
    const TetMesh box = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1), {1, 1, 1});
    Tris faces = boundary_faces(box);
    const Tris open = faces.topRows(faces.rows() - 1); // one triangle missing
    const ContactSurface b = ContactSurface::from_body("open", box.rest_positions, open);
    ASSERT_FALSE(b.closed);
    const InsideTest r = exact(b, Vec3(0.3, 0.4, 0.5));
    EXPECT_TRUE(r.inside);
    EXPECT_EQ(r.decided_by, DecidedBy::WINDING_NUMBER);
    EXPECT_FALSE(exact(b, Vec3(1.3, 0.4, 0.5)).inside);
}

TEST(AxisTest, PointOnFaceEdgeOrVertexIsOnTheSurface)
{
    const ContactSurface b = box_surface({Vec3(0, 0, 0), Vec3(1, 1, 1), {1, 1, 1}}, "B");
    for (const Vec3& p : {Vec3(1, 0.3, 0.6), Vec3(0.3, 0.6, 0), Vec3(1, 1, 0.4), Vec3(0, 1, 1), Vec3(0.5, 0.5, 1)}) {
        const InsideTest r = exact(b, p);
        EXPECT_FALSE(r.inside) << p.transpose();
        EXPECT_TRUE(r.on_surface) << p.transpose();
    }
    // Along x the point (1, 0.3, 0.6) is crossed at distance 0.
    EXPECT_EQ(axis_test(b, Vec3(1, 0.3, 0.6), 0, DetectionMode::EXACT, NO_FACES, TOL), AxisOutcome::ON_SURFACE);
    // Along y its line lies in the plane x = 1 of two faces parallel to y: degenerate, not decided.
    EXPECT_EQ(axis_test(b, Vec3(1, 0.3, 0.6), 1, DetectionMode::EXACT, NO_FACES, TOL), AxisOutcome::DEGENERATE);
}

TEST(AxisTest, APointARoundingOffATiltedFaceIsOnTheSideItIsOn)
{
    // The octahedron |x| + |y| + |z| ≤ 1, and points (1/4, 1/4, 1/2 ± k ulp) next to its face
    // x + y + z = 1: within the rounding bound of that face's plane, which once made all of them
    // "on the surface". Their exact side (x + y + z against 1, exact in long double here) is
    // what counts; only k = 0 lies on the surface.
    const ContactSurface octahedron = unit_octahedron();
    for (const double direction : {-1.0, 1.0})
        for (const int k : {0, 1, 2, 8, 32, 64}) {
            Vec3 p(0.25, 0.25, 0.5);
            for (int i = 0; i < k; ++i)
                p.z() = std::nextafter(p.z(), direction);
            const long double sum = static_cast<long double>(p.x()) + p.y() + p.z();
            for (const DetectionMode mode : {DetectionMode::EXACT, DetectionMode::BRUTE_FORCE}) {
                const InsideTest r = inside_test(octahedron, p, mode, NO_FACES, TOL);
                EXPECT_EQ(r.inside, sum < 1.0L) << "k = " << k << " direction " << direction;
                EXPECT_EQ(r.on_surface, sum == 1.0L) << "k = " << k << " direction " << direction;
            }
        }
}

TEST(InsideTest, APointARoundingOffAnEdgeIsDecidedExactly)
{
    // Next to the octahedron's edge x + y = 1, z = 0, every axis line meets an edge: the three
    // axes leave (1/2, 1/2 ± k ulp, 0) undecided, and the exact parity decides (it was the float
    // winding number, which rounding can fool there).
    const ContactSurface octahedron = unit_octahedron();
    int by_parity = 0;
    for (const double direction : {-1.0, 1.0})
        for (const int k : {0, 1, 2, 8, 64}) {
            Vec3 p(0.5, 0.5, 0.0);
            for (int i = 0; i < k; ++i)
                p.y() = std::nextafter(p.y(), direction);
            const long double sum = static_cast<long double>(p.x()) + p.y() + std::abs(p.z());
            for (const DetectionMode mode : {DetectionMode::EXACT, DetectionMode::BRUTE_FORCE}) {
                const InsideTest r = inside_test(octahedron, p, mode, NO_FACES, TOL);
                EXPECT_EQ(r.inside, sum < 1.0L) << "k = " << k << " direction " << direction;
                EXPECT_EQ(r.on_surface, sum == 1.0L) << "k = " << k << " direction " << direction;
                by_parity += r.decided_by == DecidedBy::EXACT_PARITY ? 1 : 0;
            }
        }
    EXPECT_GT(by_parity, 0); // the case this test is for
}

TEST(AxisTest, EdgeAndParallelContactsDoNotDecide)
{
    const ContactSurface b = box_surface({Vec3(0, 0, 0), Vec3(1, 1, 1), {1, 1, 1}}, "B");
    // The midpoint of the diagonal edge that splits the face x = 0, moved into the box: along x
    // the projection lands on that edge.
    Vec3 mid = Vec3::Zero();
    int found = 0;
    for (Index f = 0; f < b.faces.rows() && found == 0; ++f)
        for (int c = 0; c < 3; ++c) {
            const Vec3 p0 = b.vertices.row(b.faces(f, c)).transpose();
            const Vec3 p1 = b.vertices.row(b.faces(f, (c + 1) % 3)).transpose();
            if (p0.x() == 0 && p1.x() == 0 && p0.y() != p1.y() && p0.z() != p1.z()) {
                mid = 0.5 * (p0 + p1);
                found = 1;
                break;
            }
        }
    ASSERT_EQ(found, 1);
    const Vec3 p(0.3, mid.y(), mid.z());
    EXPECT_EQ(axis_test(b, p, 0, DetectionMode::EXACT, NO_FACES, TOL), AxisOutcome::DEGENERATE);
    EXPECT_TRUE(exact(b, p).inside);
    // A line in the plane of the top face, outside the box: parallel faces and edges only.
    EXPECT_EQ(axis_test(b, Vec3(2, 0.5, 1), 0, DetectionMode::EXACT, NO_FACES, TOL), AxisOutcome::DEGENERATE);
    EXPECT_EQ(axis_test(b, Vec3(2, 0.5, 1), 2, DetectionMode::EXACT, NO_FACES, TOL), AxisOutcome::NO_HIT);
    EXPECT_FALSE(exact(b, Vec3(2, 0.5, 1)).inside);
    // Paper mode takes the first of the equally close crossings and decides anyway.
    EXPECT_EQ(axis_test(b, p, 0, DetectionMode::PAPER, all_faces(b), TOL), AxisOutcome::INSIDE);
}

TEST(AxisTest, ClosestCrossingDecidesInBothDirections)
{
    // Two boxes' worth of surface in one: a hollow is modelled by a box inside a box, the inner one
    // reversed. A point in the wall between them is inside; one in the hollow is outside.
    const TetMesh outer = make_box(Vec3(0, 0, 0), Vec3(3, 3, 3), {1, 1, 1});
    const TetMesh inner = make_box(Vec3(1, 1, 1), Vec3(2, 2, 2), {1, 1, 1});
    Positions v(outer.num_vertices() + inner.num_vertices(), 3);
    v << outer.rest_positions, inner.rest_positions;
    const Tris fo = boundary_faces(outer);
    Tris fi = boundary_faces(inner).rowwise().reverse();
    fi.array() += outer.num_vertices();
    Tris faces(fo.rows() + fi.rows(), 3);
    faces << fo, fi;
    const ContactSurface b = ContactSurface::from_body("hollow", v, faces);
    ASSERT_TRUE(b.closed);
    EXPECT_TRUE(exact(b, Vec3(0.5, 1.37, 1.61)).inside);   // wall, nearest crossing toward −x
    EXPECT_TRUE(exact(b, Vec3(2.6, 1.37, 1.61)).inside);   // wall, nearest crossing toward +x
    EXPECT_FALSE(exact(b, Vec3(1.4, 1.37, 1.61)).inside);  // hollow
    EXPECT_FALSE(exact(b, Vec3(1.6, 1.37, 1.61)).inside);  // hollow, nearer the other side
    EXPECT_EQ(axis_test(b, Vec3(1.4, 1.37, 1.61), 0, DetectionMode::EXACT, NO_FACES, TOL), AxisOutcome::OUTSIDE);
}

TEST(AxisTest, CompetingCrossingsThatDisagreeDoNotDecide)
{
    // Two closed boxes in one surface, touching face to face at x = 1 (vertices not shared):
    // along x the point (0.5, ·, ·) meets x = 0 and x = 1 at the same distance 0.5, and at x = 1
    // two coincident faces with opposite normals vote in and out. That axis must not decide.
    const TetMesh left = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1), {1, 1, 1});
    const TetMesh right = make_box(Vec3(1, 0, 0), Vec3(2, 1, 1), {1, 1, 1});
    Positions v(left.num_vertices() + right.num_vertices(), 3);
    v << left.rest_positions, right.rest_positions;
    Tris fr = boundary_faces(right);
    fr.array() += left.num_vertices();
    const Tris fl = boundary_faces(left);
    Tris faces(fl.rows() + fr.rows(), 3);
    faces << fl, fr;
    const ContactSurface b = ContactSurface::from_body("pair", v, faces);
    ASSERT_TRUE(b.closed);
    const Vec3 p(0.5, 0.3, 0.6);
    EXPECT_EQ(axis_test(b, p, 0, DetectionMode::EXACT, NO_FACES, TOL), AxisOutcome::DEGENERATE);
    const InsideTest r = exact(b, p);
    EXPECT_TRUE(r.inside);
    EXPECT_EQ(r.decided_by, DecidedBy::Y_AXIS);
}

namespace {

/// inside_tests() (packets of up to AXIS_PACKET x-axis lines walked together) gives
/// every point the same result as inside_test(), field for field, for every packet size: the
/// points are cut into runs of 1, 2, …, 9 so that packets of all widths (and a run longer than
/// one packet) occur. Returns how many points x did not decide.
int expect_packets_match_single(const ContactSurface& b, const std::vector<Vec3>& points)
{
    std::vector<InsideTest> packed(points.size());
    std::size_t begin = 0;
    for (Index run = 1; begin < points.size(); run = run % 9 + 1) {
        const Index n = std::min<Index>(run, static_cast<Index>(points.size() - begin));
        detail::inside_tests(b, points.data() + begin, n, DetectionMode::EXACT, NO_FACES, TOL, packed.data() + begin);
        begin += static_cast<std::size_t>(n);
    }
    int not_x = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const InsideTest single = exact(b, points[i]);
        const InsideTest& p = packed[i];
        EXPECT_EQ(p.inside, single.inside) << "point " << i << " (" << points[i].transpose() << ")";
        EXPECT_EQ(p.on_surface, single.on_surface) << "point " << i;
        EXPECT_EQ(p.decided_by, single.decided_by) << "point " << i;
        EXPECT_EQ(p.surface_distance_bound, single.surface_distance_bound) << "point " << i; // bitwise
        EXPECT_EQ(p.crossing_face, single.crossing_face) << "point " << i;
        not_x += single.decided_by != DecidedBy::X_AXIS ? 1 : 0;
    }
    return not_x;
}

} // namespace

TEST(InsideTests, PacketsEqualSingleQueriesOnDeformedSpheres)
{
    const MeshBall a = mesh_ball(Vec3(0, 0, 0), 1.0, 10, 17.0, "A");
    const MeshBall b = mesh_ball(Vec3(0.8, 0.3, -0.2), 0.9, 10, -31.0, "B");
    for (const auto& [x, y] : {std::pair{&a, &b}, std::pair{&b, &a}}) {
        std::vector<Vec3> points = candidate_points(x->surface, y->surface);
        ASSERT_GT(points.size(), 100u);
        expect_packets_match_single(y->surface, points);
        std::mt19937 rng(5); // scattered packets too: lines far apart share little of the walk
        std::shuffle(points.begin(), points.end(), rng);
        expect_packets_match_single(y->surface, points);
    }
}

TEST(InsideTests, PacketsEqualSingleQueriesOnRandomPointsAndNonConvexBodies)
{
    TetMesh bar = make_box(Vec3(0, -0.5, -0.5), Vec3(4, 0.5, 0.5), {16, 4, 4});
    bar.rest_positions = twist_and_bend(bar.rest_positions, 0.6, 2.0);
    const SurfaceMesh torus_mesh = make_torus(Vec3(0.1, -0.2, 0.3), 1.0, 0.35, 48, 24);
    const ContactSurface bodies[] = {surface_of(bar, "bar"), surface_of(torus_mesh, "torus")};
    std::mt19937 rng(8);
    for (const ContactSurface& b : bodies) {
        const Aabb box = b.tree.bounds();
        std::vector<Vec3> points;
        for (int q = 0; q < 1500; ++q)
            points.push_back(random_point(box.min, box.max, rng));
        // Runs of close points, as detection sends them, mixed inside and outside.
        for (int q = 0; q < 200; ++q) {
            const Vec3 c = random_point(box.min, box.max, rng);
            for (int k = 0; k < 8; ++k)
                points.push_back(c + random_point(Vec3::Constant(-0.05), Vec3::Constant(0.05), rng));
        }
        expect_packets_match_single(b, points);
    }
}

TEST(InsideTests, PacketsEqualSingleQueriesOnDegenerateBoxes)
{
    // Vertices on faces, edges and vertices of B, and on planes parallel to the axes: packets
    // mix decided, on-surface and degenerate (x does not decide) points.
    const ContactSurface b = box_surface({Vec3(0, 0, 0), Vec3(1, 1, 1), {2, 2, 2}}, "B");
    const BoxSpec cases[] = {
        {Vec3(1, 0, 0), Vec3(2, 1, 1), {2, 2, 2}},       {Vec3(1, 1, 1), Vec3(2, 2, 2), {1, 1, 1}},
        {Vec3(1, 1, 0.25), Vec3(2, 2, 1.25), {2, 2, 2}}, {Vec3(0.5, 0.5, 0.5), Vec3(1.5, 1.5, 1.5), {2, 2, 2}},
        {Vec3(-0.5, -0.5, -0.5), Vec3(1.5, 1.5, 1.5), {4, 4, 4}}, {Vec3(0, 0, 1), Vec3(1, 1, 2), {3, 3, 1}},
    };
    int not_x = 0;
    for (const BoxSpec& spec : cases) {
        const ContactSurface a = box_surface(spec, "A");
        not_x += expect_packets_match_single(b, candidate_points(a, b));
        not_x += expect_packets_match_single(a, candidate_points(b, a));
    }
    EXPECT_GT(not_x, 20);
}
