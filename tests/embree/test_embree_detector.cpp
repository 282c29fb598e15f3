// Embree backend of contact detection: the axis queries against analytic answers, Embree's
// normal convention, degenerate rays, refits, and agreement with the axis-ray detector.
#include <corocontact/contact/detector.hpp>
#include <corocontact/core/error.hpp>
#include <corocontact/core/primitives.hpp>
#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/embree/embree_detector.hpp>

#include "brute_force_nearest.hpp"
#include "detail/embree_scene_set.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

using namespace coro;
using ::testing::HasSubstr;

namespace {

/// A body's nodes and its boundary faces (indices into the nodes).
struct BodyMesh {
    Positions positions;
    Tris faces;
};

BodyMesh sphere_body(const Vec3& center, double radius, Index resolution)
{
    const TetMesh mesh = make_sphere(center, radius, resolution);
    return {mesh.rest_positions, boundary_faces(mesh)};
}

BodyMesh box_body(const Vec3& min, const Vec3& max, Index cells)
{
    const TetMesh mesh = make_box(min, max, {cells, cells, cells});
    return {mesh.rest_positions, boundary_faces(mesh)};
}

ContactSurface surface_of(const std::string& name, const BodyMesh& body)
{
    return ContactSurface::from_body(name, body.positions, body.faces);
}

/// The octahedron |x| + |y| + |z| ≤ 1, faces wound outward.
ContactSurface octahedron()
{
    Positions v(6, 3);
    v << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
    Tris f(8, 3);
    Index row = 0;
    for (int sx : {1, -1})
        for (int sy : {1, -1})
            for (int sz : {1, -1}) {
                const Index x = sx > 0 ? 0 : 1, y = sy > 0 ? 2 : 3, z = sz > 0 ? 4 : 5;
                if (sx * sy * sz > 0)
                    f.row(row++) << x, y, z;
                else
                    f.row(row++) << x, z, y;
            }
    return ContactSurface::from_body("octahedron", v, f);
}

Vec3 winding_normal(const ContactSurface& s, Index f)
{
    const Vec3 x0 = s.vertices.row(s.faces(f, 0)).transpose();
    const Vec3 x1 = s.vertices.row(s.faces(f, 1)).transpose();
    const Vec3 x2 = s.vertices.row(s.faces(f, 2)).transpose();
    return (x1 - x0).cross(x2 - x0);
}

/// How far the flat faces of a sphere mesh dip inside the sphere (the chord error).
double chord_error(const ContactSurface& s, const Vec3& center, double radius)
{
    double sag = 0.0;
    for (Index f = 0; f < s.faces.rows(); ++f) {
        const Vec3 n = winding_normal(s, f).normalized();
        const Vec3 x0 = s.vertices.row(s.faces(f, 0)).transpose();
        sag = std::max(sag, radius - std::abs(n.dot(x0 - center)));
    }
    return sag;
}

/// A rotation drawn from a seeded generator (unit quaternion from a Gaussian 4-vector).
Mat3 random_rotation(std::mt19937& rng)
{
    std::normal_distribution<double> g;
    Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
    q.normalize();
    return q.toRotationMatrix();
}

/// Rotates the body about `center` and bends it with a smooth displacement field.
void deform(BodyMesh& body, const Vec3& center, const Mat3& rotation, double amplitude)
{
    for (Index v = 0; v < static_cast<Index>(body.positions.rows()); ++v) {
        const Vec3 p = center + rotation * (body.positions.row(v).transpose() - center);
        const Vec3 bend(std::sin(2.1 * p.y() + 0.3), std::sin(1.7 * p.z() - 0.2), std::sin(2.3 * p.x() + 1.1));
        body.positions.row(v) = (p + amplitude * bend).transpose();
    }
}

std::string describe(const std::vector<Disagreement>& d, std::size_t max_items = 10)
{
    std::ostringstream out;
    for (std::size_t i = 0; i < d.size() && i < max_items; ++i)
        out << "  body " << d[i].body << " vertex " << d[i].vertex << " other " << d[i].other
            << ": axis-ray " << d[i].axis_ray_inside << ", embree " << d[i].embree_inside << "\n";
    return out.str();
}

// ---------------------------------------------------------------------------------------------
// The unit cube [0,1]³ (one cell: 12 triangles, each square face split along a diagonal).

class EmbreeUnitCube : public ::testing::Test {
protected:
    void SetUp() override
    {
        m_surfaces.push_back(surface_of("cube", box_body(Vec3::Zero(), Vec3::Ones(), 1)));
        m_scenes = std::make_unique<EmbreeScenes>(m_surfaces);
    }
    std::vector<ContactSurface> m_surfaces;
    std::unique_ptr<EmbreeScenes> m_scenes;
};

TEST_F(EmbreeUnitCube, InsidePointIsInsideOnEveryAxis)
{
    // (y, z), (x, z), (x, y) avoid the face diagonals y = z, x = z, x = y and their mirrors.
    const Vec3 p(0.3, 0.4, 0.45);
    for (int axis = 0; axis < 3; ++axis)
        EXPECT_EQ(m_scenes->axis_test(0, p, axis), AxisOutcome::INSIDE) << "axis " << axis;
    const InsideTest t = m_scenes->inside_test(0, p);
    EXPECT_TRUE(t.inside);
    EXPECT_EQ(t.decided_by, DecidedBy::X_AXIS);
}

class EmbreeUnitCubeAxis : public EmbreeUnitCube, public ::testing::WithParamInterface<int> {};

TEST_P(EmbreeUnitCubeAxis, OutsideAlongOneAxisHitsOnlyThatAxis)
{
    const int axis = GetParam();
    for (double beyond : {-0.7, 1.6}) {
        Vec3 p(0.3, 0.4, 0.45);
        p[axis] = beyond;
        for (int a = 0; a < 3; ++a)
            EXPECT_EQ(m_scenes->axis_test(0, p, a), a == axis ? AxisOutcome::OUTSIDE : AxisOutcome::NO_HIT)
                << "point " << p.transpose() << ", axis " << a;
        const InsideTest t = m_scenes->inside_test(0, p);
        EXPECT_FALSE(t.inside);
        EXPECT_FALSE(t.on_surface);
        EXPECT_EQ(t.decided_by, DecidedBy::X_AXIS); // x: OUTSIDE, or NO_HIT, which decides outside too
    }
}

TEST_P(EmbreeUnitCubeAxis, GeometricNormalFollowsWinding)
{
    // From inside toward the face at coordinate 1 and from outside toward the face at 0: Embree's
    // Ng must be parallel to the face's winding normal (x1−x0)×(x2−x0) with the sign the
    // backend assumes, and that winding normal must point out of the cube.
    const int axis = GetParam();
    detail::EmbreeSceneSet scenes(m_surfaces, detail::EmbreeBuild::REFIT);
    for (double start : {0.5, -1.0}) {
        Vec3 p(0.3, 0.4, 0.45);
        p[axis] = start;
        const detail::EmbreeFirstHit hit = scenes.first_hit(0, p, axis);
        ASSERT_GE(hit.face, 0) << "no hit from " << p.transpose();
        const Vec3 n = winding_normal(m_surfaces[0], hit.face);
        Vec3 outward = Vec3::Zero();
        outward[axis] = start > 0.0 ? 1.0 : -1.0;
        EXPECT_GT(n.normalized().dot(outward), 1.0 - 1e-12) << "face " << hit.face;
        const double cosine = hit.ng.normalized().dot(n.normalized());
        EXPECT_NEAR(cosine, detail::embree_ng_along_winding(), 1e-6) << "Ng " << hit.ng.transpose();
        EXPECT_NEAR(hit.t, start > 0.0 ? 0.5 : 1.0, 1e-6);
    }
}

INSTANTIATE_TEST_SUITE_P(Axes, EmbreeUnitCubeAxis, ::testing::Values(0, 1, 2),
                         [](const ::testing::TestParamInfo<int>& param_info) { return std::string(1, "XYZ"[param_info.param]); });

TEST_F(EmbreeUnitCube, FarPointHasNoHitOnAnyAxis)
{
    const Vec3 p(2.0, -3.0, 4.0);
    for (int axis = 0; axis < 3; ++axis)
        EXPECT_EQ(m_scenes->axis_test(0, p, axis), AxisOutcome::NO_HIT);
    const InsideTest t = m_scenes->inside_test(0, p);
    EXPECT_FALSE(t.inside);
    EXPECT_EQ(t.decided_by, DecidedBy::X_AXIS);
}

TEST_F(EmbreeUnitCube, RayThroughSharedEdgeIsDegenerate)
{
    // The two triangles of the face x = 1 share a diagonal; a point whose +x ray meets that
    // diagonal (and is closer to it than to the face x = 0) must not count as two crossings.
    const ContactSurface& cube = m_surfaces[0];
    std::vector<Index> on_face;
    for (Index f = 0; f < cube.faces.rows(); ++f) {
        bool all = true;
        for (int k = 0; k < 3; ++k)
            all = all && cube.vertices(cube.faces(f, k), 0) == 1.0;
        if (all)
            on_face.push_back(f);
    }
    ASSERT_EQ(on_face.size(), 2u);
    std::vector<Index> shared;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (cube.faces(on_face[0], i) == cube.faces(on_face[1], j))
                shared.push_back(cube.faces(on_face[0], i));
    ASSERT_EQ(shared.size(), 2u);
    const Vec3 a = cube.vertices.row(shared[0]).transpose(), b = cube.vertices.row(shared[1]).transpose();
    Vec3 p = a + 0.3 * (b - a);
    p.x() = 0.8;

    EXPECT_EQ(m_scenes->axis_test(0, p, 0), AxisOutcome::DEGENERATE);
    // The y and z lines of that point are clear of edges: they decide.
    const InsideTest t = m_scenes->inside_test(0, p);
    EXPECT_TRUE(t.inside);
    EXPECT_EQ(t.decided_by, DecidedBy::Y_AXIS);

    // The same edge seen from outside the cube.
    Vec3 q = p;
    q.x() = 1.5;
    EXPECT_EQ(m_scenes->axis_test(0, q, 0), AxisOutcome::DEGENERATE);
    const InsideTest u = m_scenes->inside_test(0, q);
    EXPECT_FALSE(u.inside);
    EXPECT_EQ(u.decided_by, DecidedBy::Y_AXIS);
}

TEST_F(EmbreeUnitCube, PointOnTheSurfaceIsOnSurfaceNotInside)
{
    for (const Vec3& p : {Vec3(1.0, 0.4, 0.45), Vec3(0.0, 0.4, 0.45), Vec3(0.3, 0.4, 1.0)}) {
        const int axis = p.z() == 1.0 ? 2 : 0;
        EXPECT_EQ(m_scenes->axis_test(0, p, axis), AxisOutcome::ON_SURFACE) << p.transpose();
    }
    const InsideTest t = m_scenes->inside_test(0, Vec3(1.0, 0.4, 0.45));
    EXPECT_FALSE(t.inside);
    EXPECT_TRUE(t.on_surface);
    EXPECT_EQ(t.decided_by, DecidedBy::X_AXIS);
}

TEST(EmbreeScenes, CoincidentOppositeFacesAreDegenerate)
{
    // Two unit cubes touching face to face at x = 1, as one surface: on that plane two faces
    // with opposite normals cross the x line at the same distance, away from every edge.
    const BodyMesh left = box_body(Vec3::Zero(), Vec3::Ones(), 1);
    const BodyMesh right = box_body(Vec3(1, 0, 0), Vec3(2, 1, 1), 1);
    BodyMesh both;
    both.positions.resize(left.positions.rows() + right.positions.rows(), 3);
    both.positions << left.positions, right.positions;
    both.faces.resize(left.faces.rows() + right.faces.rows(), 3);
    both.faces << left.faces, (right.faces.array() + static_cast<Index>(left.positions.rows())).matrix();
    std::vector<ContactSurface> surfaces{surface_of("two cubes", both)};
    EmbreeScenes scenes(surfaces);
    const Vec3 p(0.7, 0.4, 0.45);
    EXPECT_EQ(scenes.axis_test(0, p, 0), AxisOutcome::DEGENERATE);
    EXPECT_EQ(scenes.axis_test(0, p, 1), AxisOutcome::INSIDE);
    const InsideTest t = scenes.inside_test(0, p);
    EXPECT_TRUE(t.inside);
    EXPECT_EQ(t.decided_by, DecidedBy::Y_AXIS);
}

TEST(EmbreeScenes, ManyLayersAlongTheAxis)
{
    // Twelve disjoint unit cubes along x as one surface: the x line meets 24 faces, more than
    // the hit list keeps inline.
    BodyMesh row;
    constexpr int CUBES = 12;
    for (int k = 0; k < CUBES; ++k) {
        const BodyMesh cube = box_body(Vec3(2.0 * k, 0, 0), Vec3(2.0 * k + 1.0, 1, 1), 1);
        const auto offset = static_cast<Index>(row.positions.rows());
        row.positions.conservativeResize(offset + cube.positions.rows(), 3);
        row.positions.bottomRows(cube.positions.rows()) = cube.positions;
        const auto f0 = row.faces.rows();
        row.faces.conservativeResize(f0 + cube.faces.rows(), 3);
        row.faces.bottomRows(cube.faces.rows()) = (cube.faces.array() + offset).matrix();
    }
    std::vector<ContactSurface> surfaces{surface_of("row", row)};
    detail::EmbreeSceneSet scenes(surfaces, detail::EmbreeBuild::REFIT);
    for (int k = 0; k < CUBES; ++k) {
        detail::EmbreeQueryCounts counts;
        EXPECT_EQ(scenes.axis_test(0, Vec3(2.0 * k + 0.3, 0.4, 0.45), 0, &counts), AxisOutcome::INSIDE) << k;
        EXPECT_EQ(counts.hits, 2 * CUBES);
        EXPECT_EQ(scenes.axis_test(0, Vec3(2.0 * k + 1.6, 0.4, 0.45), 0), AxisOutcome::OUTSIDE) << k;
    }
}

TEST(EmbreeScenes, RayThroughVertexFallsBackToWindingNumber)
{
    // Every axis line of (0.2, 0, 0) runs through a vertex or an edge of the octahedron.
    std::vector<ContactSurface> surfaces{octahedron()};
    EmbreeScenes scenes(surfaces);
    const Vec3 p(0.2, 0.0, 0.0);
    for (int axis = 0; axis < 3; ++axis)
        EXPECT_EQ(scenes.axis_test(0, p, axis), AxisOutcome::DEGENERATE) << "axis " << axis;
    const InsideTest t = scenes.inside_test(0, p);
    EXPECT_TRUE(t.inside);
    EXPECT_EQ(t.decided_by, DecidedBy::WINDING_NUMBER);
    const InsideTest out = scenes.inside_test(0, Vec3(1.2, 0.0, 0.0));
    EXPECT_FALSE(out.inside);
}

// ---------------------------------------------------------------------------------------------
// Spheres against |p − c| < r.

/// Checks every vertex of `points` against the sphere mesh surface `s` of `scenes`, for the
/// vertices outside the chord-error band; returns the numbers checked inside and outside.
std::pair<int, int> expect_matches_sphere(const EmbreeScenes& scenes, Index s, const ContactSurface& sphere,
                                          const Vec3& center, double radius, const Positions& points)
{
    const double sag = chord_error(sphere, center, radius);
    constexpr double FLOAT_BAND = 1e-5;
    int inside = 0, outside = 0;
    for (Index v = 0; v < static_cast<Index>(points.rows()); ++v) {
        const Vec3 p = points.row(v).transpose();
        const double d = (p - center).norm();
        if (d < radius - sag - FLOAT_BAND) {
            ++inside;
            EXPECT_TRUE(scenes.inside_test(s, p).inside) << "vertex " << v << " at |p−c| = " << d;
        } else if (d > radius + FLOAT_BAND) {
            ++outside;
            EXPECT_FALSE(scenes.inside_test(s, p).inside) << "vertex " << v << " at |p−c| = " << d;
        }
    }
    return {inside, outside};
}

TEST(EmbreeScenes, SphereVerticesInsideOtherSphereMatchDistance)
{
    const Vec3 ca(0.0, 0.0, 0.0), cb(1.1, 0.23, -0.17);
    const double ra = 1.0, rb = 0.8;
    std::vector<ContactSurface> surfaces{surface_of("a", sphere_body(ca, ra, 12)),
                                         surface_of("b", sphere_body(cb, rb, 10))};
    const EmbreeScenes scenes(surfaces);
    const auto [in_b, out_b] = expect_matches_sphere(scenes, 1, surfaces[1], cb, rb, surfaces[0].vertices);
    const auto [in_a, out_a] = expect_matches_sphere(scenes, 0, surfaces[0], ca, ra, surfaces[1].vertices);
    EXPECT_GT(in_b, 50);
    EXPECT_GT(out_b, 50);
    EXPECT_GT(in_a, 50);
    EXPECT_GT(out_a, 50);
}

TEST(EmbreeScenes, UpdateRefitsToMovedVertices)
{
    const Vec3 ca(0.0, 0.0, 0.0), cb(1.4, 0.1, 0.0);
    BodyMesh a = sphere_body(ca, 1.0, 8), b = sphere_body(cb, 1.0, 8);
    std::vector<ContactSurface> surfaces{surface_of("a", a), surface_of("b", b)};
    EmbreeScenes scenes(surfaces);
    const Vec3 p(0.8, 0.12, 0.03);
    ASSERT_TRUE(scenes.inside_test(1, p).inside);

    // Move b far away: p is no longer inside it, the moved point is.
    const Vec3 shift(3.0, -0.5, 0.25);
    b.positions.rowwise() += shift.transpose();
    surfaces[1].update(b.positions);
    scenes.update(surfaces);
    EXPECT_FALSE(scenes.inside_test(1, p).inside);
    EXPECT_TRUE(scenes.inside_test(1, p + shift).inside);
    EXPECT_EQ(scenes.axis_test(1, p + shift, 0), AxisOutcome::INSIDE);

    // Grow b about its new centre, refitting each step; compare with the analytic sphere and
    // with scenes built from scratch at the final shape.
    const Vec3 centre = cb + shift;
    double radius = 1.0;
    for (int step = 0; step < 4; ++step) {
        radius *= 1.25;
        b.positions = ((b.positions.rowwise() - centre.transpose()) * 1.25).rowwise() + centre.transpose();
        surfaces[1].update(b.positions);
        scenes.update(surfaces);
        const auto [inside, outside] = expect_matches_sphere(scenes, 1, surfaces[1], centre, radius,
                                                             surfaces[0].vertices.rowwise() + shift.transpose());
        EXPECT_GT(inside, 10) << "step " << step;
    }
    const EmbreeScenes fresh(surfaces);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-4.0, 4.0);
    for (int i = 0; i < 2000; ++i) {
        const Vec3 q = centre + Vec3(u(rng), u(rng), u(rng));
        EXPECT_EQ(scenes.inside_test(1, q).inside, fresh.inside_test(1, q).inside) << q.transpose();
    }
}

// ---------------------------------------------------------------------------------------------
// Detection: against the axis-ray detector.

std::vector<ContactSurface> deformed_sphere_pair(unsigned seed, Index res_a, Index res_b)
{
    std::mt19937 rng(seed);
    const Vec3 ca(0.0, 0.0, 0.0), cb(0.9, 0.15, -0.1);
    BodyMesh a = sphere_body(ca, 1.0, res_a), b = sphere_body(cb, 0.8, res_b);
    deform(a, ca, random_rotation(rng), 0.03);
    deform(b, cb, random_rotation(rng), 0.04);
    return {surface_of("a", a), surface_of("b", b)};
}

TEST(DetectContactsEmbree, AgreesWithAxisRayDetectorOnDeformedSpheres)
{
    for (unsigned seed : {1u, 2u, 3u, 4u}) {
        const std::vector<ContactSurface> surfaces = deformed_sphere_pair(seed, 12, 10);
        DetectionStats axis_stats, embree_stats;
        const std::vector<ContactPoint> axis_ray = detect_contacts(surfaces, DetectionSettings{}, &axis_stats);
        const EmbreeScenes scenes(surfaces);
        const std::vector<ContactPoint> embree =
            detect_contacts_embree(surfaces, scenes, DetectionSettings{}, &embree_stats);

        const std::vector<Disagreement> disagreements = cross_check(axis_ray, embree);
        EXPECT_TRUE(disagreements.empty()) << "seed " << seed << ": " << disagreements.size()
                                           << " disagreements\n" << describe(disagreements);
        EXPECT_EQ(embree_stats.pairs, axis_stats.pairs);
        EXPECT_EQ(embree_stats.candidate_vertices, axis_stats.candidate_vertices);
        EXPECT_EQ(embree_stats.inside, static_cast<Index>(embree.size()));
        EXPECT_EQ(embree_stats.on_surface, 0);
        EXPECT_GT(embree.size(), 100u) << "seed " << seed << ": the overlap is not deep";
        // The depths come from Embree's point queries, the axis-ray detector's from our tree:
        // the same nearest face and point, bit for bit.
        ASSERT_EQ(embree.size(), axis_ray.size());
        EXPECT_EQ(depth_disagreements(axis_ray, embree), 0) << "seed " << seed;
        for (std::size_t i = 0; i < embree.size(); ++i) {
            EXPECT_EQ(embree[i].face, axis_ray[i].face) << "seed " << seed << " point " << i;
            EXPECT_EQ(embree[i].depth, axis_ray[i].depth) << "seed " << seed << " point " << i;
            EXPECT_EQ(embree[i].barycentric, axis_ray[i].barycentric) << "seed " << seed << " point " << i;
            EXPECT_EQ(embree[i].normal, axis_ray[i].normal) << "seed " << seed << " point " << i;
        }
    }
}

TEST(DetectContactsEmbree, ReportsSortedDepthsAndNormalsOfTheOtherSphere)
{
    const Vec3 ca(0.0, 0.0, 0.0), cb(1.2, -0.1, 0.2);
    const double rb = 0.9;
    std::vector<ContactSurface> surfaces{surface_of("a", sphere_body(ca, 1.0, 12)),
                                         surface_of("b", sphere_body(cb, rb, 12))};
    const EmbreeScenes scenes(surfaces);
    DetectionStats stats;
    const std::vector<ContactPoint> points = detect_contacts_embree(surfaces, scenes, DetectionSettings{}, &stats);
    ASSERT_GT(points.size(), 50u);
    EXPECT_EQ(stats.pairs, 1);
    const double sag = chord_error(surfaces[1], cb, rb);
    for (std::size_t i = 0; i < points.size(); ++i) {
        const ContactPoint& c = points[i];
        if (i > 0) {
            const ContactPoint& prev = points[i - 1];
            EXPECT_TRUE(std::tie(prev.body, prev.vertex, prev.other) < std::tie(c.body, c.vertex, c.other));
        }
        if (c.body != 0)
            continue;
        const Vec3 p = surfaces[0].vertices.row(c.vertex).transpose();
        EXPECT_EQ(c.other, ContactTarget::surface(1));
        EXPECT_NEAR(c.depth, rb - (p - cb).norm(), sag + 1e-9) << "vertex " << c.vertex;
        EXPECT_GT(c.normal.dot((p - cb).normalized()), 0.9) << "vertex " << c.vertex;
        EXPECT_NEAR(c.normal.norm(), 1.0, 1e-12);
        EXPECT_GE(c.face, 0);
    }
}

TEST(DetectContactsEmbree, OneAndTwoThreadsGiveTheSameResult)
{
    const std::vector<ContactSurface> surfaces = deformed_sphere_pair(11, 12, 12);
    const EmbreeScenes scenes(surfaces);
    std::vector<ContactPoint> one;
    tbb::task_arena single(1);
    single.execute([&] { one = detect_contacts_embree(surfaces, scenes, DetectionSettings{}); });
    tbb::task_arena two(2);
    std::vector<ContactPoint> many;
    two.execute([&] { many = detect_contacts_embree(surfaces, scenes, DetectionSettings{}); });
    ASSERT_EQ(one.size(), many.size());
    for (std::size_t i = 0; i < one.size(); ++i) {
        EXPECT_EQ(one[i].body, many[i].body);
        EXPECT_EQ(one[i].vertex, many[i].vertex);
        EXPECT_EQ(one[i].other, many[i].other);
        EXPECT_EQ(one[i].depth, many[i].depth); // bitwise: the same query in any order
    }
}

TEST(DetectContactsEmbree, SeparatedBodiesHaveNoContacts)
{
    std::vector<ContactSurface> surfaces{surface_of("a", sphere_body(Vec3::Zero(), 1.0, 6)),
                                         surface_of("b", sphere_body(Vec3(2.5, 0, 0), 1.0, 6))};
    const EmbreeScenes scenes(surfaces);
    DetectionStats stats;
    EXPECT_TRUE(detect_contacts_embree(surfaces, scenes, DetectionSettings{}, &stats).empty());
    EXPECT_EQ(stats.pairs, 0);
    EXPECT_EQ(stats.candidate_vertices, 0);
}

// ---------------------------------------------------------------------------------------------
// cross_check and errors.

ContactPoint point(Index body, Index vertex, Index other)
{
    ContactPoint c;
    c.body = body;
    c.vertex = vertex;
    c.other = ContactTarget::surface(other);
    return c;
}

TEST(CrossCheck, ListsVerticesFoundByOnlyOneSide)
{
    const std::vector<ContactPoint> axis_ray{point(0, 1, 1), point(0, 2, 1), point(1, 5, 0), point(2, 0, 0)};
    const std::vector<ContactPoint> embree{point(0, 2, 1), point(0, 3, 1), point(1, 5, 0), point(2, 0, 1)};
    const std::vector<Disagreement> d = cross_check(axis_ray, embree);
    ASSERT_EQ(d.size(), 4u);
    EXPECT_EQ(std::tie(d[0].body, d[0].vertex, d[0].other), std::make_tuple(0, 1, 1));
    EXPECT_TRUE(d[0].axis_ray_inside);
    EXPECT_FALSE(d[0].embree_inside);
    EXPECT_EQ(std::tie(d[1].body, d[1].vertex, d[1].other), std::make_tuple(0, 3, 1));
    EXPECT_FALSE(d[1].axis_ray_inside);
    EXPECT_TRUE(d[1].embree_inside);
    EXPECT_EQ(std::tie(d[2].body, d[2].vertex, d[2].other), std::make_tuple(2, 0, 0));
    EXPECT_TRUE(d[2].axis_ray_inside);
    EXPECT_EQ(std::tie(d[3].body, d[3].vertex, d[3].other), std::make_tuple(2, 0, 1));
    EXPECT_TRUE(d[3].embree_inside);
    EXPECT_TRUE(cross_check(axis_ray, axis_ray).empty());
}

TEST(CrossCheck, LeavesPlaneContactsOut)
{
    // A run's contacts hold plane contacts too (plane 1 here, not surface 1); Embree never finds them.
    ContactPoint on_plane = point(0, 2, 0);
    on_plane.other = ContactTarget::plane(1);
    const std::vector<ContactPoint> axis_ray{point(0, 1, 1), on_plane};
    const std::vector<ContactPoint> embree{point(0, 1, 1)};
    EXPECT_TRUE(cross_check(axis_ray, embree).empty());
}

TEST(CrossCheck, CountsDepthDisagreementsOfVerticesBothFoundInside)
{
    const auto point = [](Index body, Index vertex, Index face, double depth) {
        ContactPoint c;
        c.body = body;
        c.vertex = vertex;
        c.other = ContactTarget::surface(1 - body);
        c.face = face;
        c.depth = depth;
        return c;
    };
    const std::vector<ContactPoint> axis_ray{point(0, 1, 4, 0.1), point(0, 2, 5, 0.2), point(0, 7, 6, 0.3),
                                             point(1, 3, 2, 0.4)};
    const std::vector<ContactPoint> embree{point(0, 2, 5, 0.2), point(0, 5, 1, 0.5),
                                           point(0, 7, 6, std::nextafter(0.3, 1.0)), point(1, 3, 9, 0.4)};
    // Vertex 0:1 and 0:5 are found by one side only (cross_check's business); 0:7 differs in
    // depth by one ulp, 1:3 in its face.
    EXPECT_EQ(depth_disagreements(axis_ray, embree), 2);
    EXPECT_EQ(depth_disagreements(axis_ray, axis_ray), 0);
}

TEST(EmbreeScenes, RejectsNonFiniteVertices)
{
    std::vector<ContactSurface> surfaces{surface_of("cube", box_body(Vec3::Zero(), Vec3::Ones(), 2))};
    surfaces[0].vertices(3, 1) = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THAT([&] { EmbreeScenes scenes(surfaces); },
                ::testing::ThrowsMessage<NumericalError>(HasSubstr("'cube'")));
}

TEST(EmbreeScenes, UpdateRejectsOtherSurfaces)
{
    std::vector<ContactSurface> surfaces{surface_of("cube", box_body(Vec3::Zero(), Vec3::Ones(), 2))};
    EmbreeScenes scenes(surfaces);
    std::vector<ContactSurface> more{surfaces[0], surfaces[0]};
    EXPECT_THAT([&] { scenes.update(more); }, ::testing::ThrowsMessage<InputError>(HasSubstr("2 surfaces")));
    std::vector<ContactSurface> other{surface_of("cube", box_body(Vec3::Zero(), Vec3::Ones(), 3))};
    EXPECT_THAT([&] { scenes.update(other); }, ::testing::ThrowsMessage<InputError>(HasSubstr("'cube'")));
}

TEST(EmbreeScenes, UpdateThrowsTheFirstFailingSurfacesError)
{
    // The scenes commit as parallel tasks: of two bad surfaces, the first is reported, every time.
    std::vector<ContactSurface> surfaces;
    for (int k = 0; k < 4; ++k)
        surfaces.push_back(surface_of("cube" + std::to_string(k), box_body(Vec3(2.0 * k, 0, 0), Vec3(2.0 * k + 1, 1, 1), 2)));
    for (int attempt = 0; attempt < 10; ++attempt) {
        std::vector<ContactSurface> moved = surfaces;
        EmbreeScenes scenes(moved); // built again each time: a failed update leaves it unusable
        moved[1].vertices(3, 1) = std::numeric_limits<double>::quiet_NaN();
        moved[3].vertices(0, 2) = std::numeric_limits<double>::infinity();
        EXPECT_THAT([&] { scenes.update(moved); }, ::testing::ThrowsMessage<NumericalError>(HasSubstr("'cube1'")));
    }
}

TEST(EmbreeSceneSet, NearestIsTheBruteForceMinimumWithSmallestFaceOnTies)
{
    // Embree's point query with our callback must give the minimum over all faces of (computed
    // squared distance, face index), as AabbTree::nearest does: deep points inside a deformed
    // sphere (many faces nearly equally far), points near and outside the surface, points of a
    // structured box on its grid planes (exact ties between faces), after an update to moved
    // vertices, with and without a distance bound (also one that is too small).
    std::mt19937 rng(21);
    std::vector<ContactSurface> surfaces = deformed_sphere_pair(6, 12, 10);
    surfaces.push_back(surface_of("box", box_body(Vec3(0.0, 0.0, 0.0), Vec3(1.0, 1.0, 1.0), 4)));
    detail::EmbreeSceneSet scenes(surfaces, detail::EmbreeBuild::REFIT);
    BodyMesh moved = sphere_body(Vec3(0.0, 0.0, 0.0), 1.0, 12);
    deform(moved, Vec3(0.0, 0.0, 0.0), random_rotation(rng), 0.08);
    surfaces[0].vertices = surface_of("a", moved).vertices;
    surfaces[0].tree.refit(surfaces[0].vertices);
    scenes.update(surfaces);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (Index s = 0; s < static_cast<Index>(surfaces.size()); ++s) {
        const ContactSurface& surface = surfaces[static_cast<std::size_t>(s)];
        const Aabb box = surface.tree.bounds();
        const Vec3 centre = 0.5 * (box.min + box.max), size = box.max - box.min;
        for (int q = 0; q < 300; ++q) {
            Vec3 p = centre + (1.4 * Vec3(unit(rng), unit(rng), unit(rng)) - Vec3::Constant(0.7)).cwiseProduct(size);
            if (q % 3 == 0)
                p = centre + 0.1 * (p - centre); // deep inside
            if (q % 5 == 0)
                p = (p * 4.0).array().round() / 4.0; // grid planes of the box: ties
            const test::BruteForceNearest brute = test::brute_force_nearest(surface, p);
            const double best = brute.squared_distance;
            const Index best_face = brute.face;
            const double bound = q % 4 == 0   ? std::numeric_limits<double>::infinity()
                                 : q % 4 == 1 ? 0.5 * std::sqrt(best) // too small: searched again
                                              : std::sqrt(best) * 1.5;
            const NearestPoint got = scenes.nearest(surface, s, p, bound);
            ASSERT_EQ(got.face, best_face) << surface.name << " query " << q;
            ASSERT_EQ(got.distance, std::sqrt(best)) << surface.name << " query " << q;
            const NearestPoint tree = surface.tree.nearest(surface.vertices, p);
            EXPECT_EQ(got.point, tree.point) << surface.name << " query " << q;
            EXPECT_EQ(got.barycentric, tree.barycentric) << surface.name << " query " << q;
        }
    }
}

TEST(EmbreeSceneSet, RebuildSettingsGiveTheSameAnswers)
{
    const std::vector<ContactSurface> surfaces = deformed_sphere_pair(5, 10, 10);
    detail::EmbreeSceneSet refit(surfaces, detail::EmbreeBuild::REFIT);
    detail::EmbreeSceneSet low(surfaces, detail::EmbreeBuild::LOW_REBUILD);
    detail::EmbreeSceneSet medium(surfaces, detail::EmbreeBuild::MEDIUM_REBUILD);
    detail::EmbreeQueryCounts counts;
    const auto r = detail::detect_contacts_embree(surfaces, refit, DetectionSettings{}, nullptr, &counts);
    const auto l = detail::detect_contacts_embree(surfaces, low, DetectionSettings{}, nullptr, nullptr);
    const auto m = detail::detect_contacts_embree(surfaces, medium, DetectionSettings{}, nullptr, nullptr);
    EXPECT_TRUE(cross_check(r, l).empty());
    EXPECT_TRUE(cross_check(r, m).empty());
    EXPECT_GT(counts.axis_tests, 0);
    EXPECT_EQ(counts.rays, counts.axis_tests); // one ray per axis line
    EXPECT_GE(counts.hits, counts.rays);
}

} // namespace
