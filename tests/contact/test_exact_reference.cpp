// Detection against an exact rational reference on small seeded scenes built to be hard:
// bodies on a coarse grid (vertices exactly on faces, edges and vertices of other bodies), then
// nudged by a few ulps, rotated in floating point, shifted far from the origin or given noise at
// the level of the coordinates' rounding. The reference knows nothing of the axis rays: a vertex
// on a face (exact orientation and closed triangle) is on the surface, else it is inside when a
// segment from it to outside the surface's box crosses an odd number of faces; every sign is exact
// (floating point beyond Shewchuk's error bound, GMP rationals within it), and a segment lying in
// a face's plane, or crossing one on an edge's line, is redrawn.

#include "contact_scenes.hpp"
#include "detail/segment_triangle.hpp"

#include <corocontact/contact/axis_ray.hpp>
#include <corocontact/contact/detector.hpp>
#include <corocontact/core/primitives.hpp>
#include <corocontact/core/surface_mesh.hpp>

#include <gmpxx.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <set>
#include <tuple>
#include <vector>

using namespace coro;
using namespace coro::test;

namespace {

using Q = mpq_class;
constexpr double INF = std::numeric_limits<double>::infinity();
using QVec = std::array<Q, 3>;

QVec rational(const Vec3& p) { return {Q(p.x()), Q(p.y()), Q(p.z())}; } // exact: a double is a rational

/// The sign of det[b − a, c − a, d − a]: positive when d lies on the side of plane (a, b, c) its
/// counter-clockwise normal points to. From the float determinant where it clears Shewchuk's
/// error bound (orient3d's errboundA, which covers every rounding of its evaluation, plus
/// 2⁻¹⁰⁰⁰·(1 + the factors of the minors) for products that underflow), else in rationals.
int orientation(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d)
{
    const Vec3 ad = a - d, bd = b - d, cd = c - d; // det[a − d, b − d, c − d] = −det[b − a, c − a, d − a]
    const double det = ad.x() * (bd.y() * cd.z() - bd.z() * cd.y()) + bd.x() * (cd.y() * ad.z() - cd.z() * ad.y()) +
                       cd.x() * (ad.y() * bd.z() - ad.z() * bd.y());
    const double permanent = std::abs(ad.x()) * (std::abs(bd.y() * cd.z()) + std::abs(bd.z() * cd.y())) +
                             std::abs(bd.x()) * (std::abs(cd.y() * ad.z()) + std::abs(cd.z() * ad.y())) +
                             std::abs(cd.x()) * (std::abs(ad.y() * bd.z()) + std::abs(ad.z() * bd.y()));
    const double epsilon = 0x1p-53;
    const double underflow = 0x1p-1000 * (1.0 + std::abs(ad.x()) + std::abs(bd.x()) + std::abs(cd.x()));
    if (std::abs(det) > (7.0 + 56.0 * epsilon) * epsilon * permanent + underflow)
        return det > 0.0 ? -1 : 1;
    const QVec qa = rational(a), qb = rational(b), qc = rational(c), qd = rational(d);
    const Q u0 = qb[0] - qa[0], u1 = qb[1] - qa[1], u2 = qb[2] - qa[2];
    const Q v0 = qc[0] - qa[0], v1 = qc[1] - qa[1], v2 = qc[2] - qa[2];
    const Q w0 = qd[0] - qa[0], w1 = qd[1] - qa[1], w2 = qd[2] - qa[2];
    return sgn(u0 * (v1 * w2 - v2 * w1) - u1 * (v0 * w2 - v2 * w0) + u2 * (v0 * w1 - v1 * w0));
}

/// The sign of the 2-D orientation of (a, b, p) in the plane of coordinates i, j.
int orientation_2d(const QVec& a, const QVec& b, const QVec& p, int i, int j)
{
    const Q det = (b[i] - a[i]) * (p[j] - a[j]) - (b[j] - a[j]) * (p[i] - a[i]);
    return sgn(det);
}

/// Whether p, known to lie in the plane of (a, b, c), lies in the closed triangle: the signs of
/// its 2-D orientations against the edges in a projection that keeps the triangle's area.
bool in_closed_triangle(const QVec& a, const QVec& b, const QVec& c, const QVec& p)
{
    for (int drop = 0; drop < 3; ++drop) {
        const int i = (drop + 1) % 3, j = (drop + 2) % 3;
        const int area = orientation_2d(a, b, c, i, j);
        if (area == 0)
            continue; // the triangle is edge-on in this projection
        const int s0 = orientation_2d(a, b, p, i, j), s1 = orientation_2d(b, c, p, i, j),
                  s2 = orientation_2d(c, a, p, i, j);
        return s0 * area >= 0 && s1 * area >= 0 && s2 * area >= 0;
    }
    return false; // a degenerate face holds no surface
}

enum class Side { OUTSIDE, INSIDE, ON_SURFACE };

/// Directions of the reference's segments: small integers aligned with no axis, plane or edge of
/// the scenes' grid.
const std::array<Vec3, 8> DIRECTIONS{Vec3(3, 5, 7),   Vec3(-7, 2, 5), Vec3(5, -11, 3), Vec3(2, 3, -13),
                                     Vec3(-5, -7, 2), Vec3(11, 3, -2), Vec3(-3, 13, -5), Vec3(7, -2, -11)};

/// A closed surface's faces: corners and boxes (a triangle lies in the box of its corners, so
/// comparisons with the box are exact filters).
struct ExactSurface {
    explicit ExactSurface(const ContactSurface& s)
    {
        for (Eigen::Index f = 0; f < s.faces.rows(); ++f) {
            const Vec3 a = s.vertices.row(s.faces(f, 0)), b = s.vertices.row(s.faces(f, 1)),
                       c = s.vertices.row(s.faces(f, 2));
            corners.push_back({a, b, c});
            lo.push_back(a.cwiseMin(b).cwiseMin(c));
            hi.push_back(a.cwiseMax(b).cwiseMax(c));
        }
        box_lo = s.vertices.colwise().minCoeff().transpose();
        box_hi = s.vertices.colwise().maxCoeff().transpose();
    }

    std::vector<std::array<Vec3, 3>> corners;
    std::vector<Vec3> lo, hi; // per face
    Vec3 box_lo, box_hi;
};

/// The exact side of `point` with respect to the closed surface `s`.
Side exact_side(const ExactSurface& s, const Vec3& point)
{
    const std::size_t faces = s.corners.size();
    for (std::size_t f = 0; f < faces; ++f) {
        if ((point.array() < s.lo[f].array()).any() || (point.array() > s.hi[f].array()).any())
            continue;
        const auto& t = s.corners[f];
        if (orientation(t[0], t[1], t[2], point) == 0 &&
            in_closed_triangle(rational(t[0]), rational(t[1]), rational(t[2]), rational(point)))
            return Side::ON_SURFACE;
    }
    // The segment's far end q: every coordinate beyond the box (whatever q's rounding, the
    // segment from the point to q is what is tested, exactly).
    const double reach = 2.0 * ((s.box_hi - s.box_lo).maxCoeff() + (point - s.box_lo).cwiseAbs().maxCoeff() + 1.0);
    for (const Vec3& d : DIRECTIONS) {
        const Vec3 q = point + reach * d;
        const Vec3& p = point;
        bool degenerate = false;
        int crossings = 0;
        for (std::size_t f = 0; f < faces && !degenerate; ++f) {
            bool behind = false; // the face lies wholly on the side of the point the segment leaves
            for (int i = 0; i < 3; ++i)
                behind = behind || (d[i] > 0 ? s.hi[f][i] < point[i] : s.lo[f][i] > point[i]);
            if (behind)
                continue;
            const auto& t = s.corners[f];
            const int sp = orientation(t[0], t[1], t[2], p), sq = orientation(t[0], t[1], t[2], q);
            if (sp == 0 && sq == 0) {
                degenerate = true; // the segment lies in the face's plane
            } else if (sp != 0 && sq != 0 && sp != sq) {
                const int e0 = orientation(p, q, t[0], t[1]), e1 = orientation(p, q, t[1], t[2]),
                          e2 = orientation(p, q, t[2], t[0]);
                if (e0 == 0 || e1 == 0 || e2 == 0)
                    degenerate = true; // through an edge's line, maybe the edge or a vertex: redraw
                else if ((e0 > 0) == (e1 > 0) && (e1 > 0) == (e2 > 0))
                    ++crossings;
            }
            // One end in the plane and the other not: the segment meets the plane at that end
            // only; the point is not on the face, and the far end lies outside the box.
        }
        if (!degenerate)
            return crossings % 2 == 1 ? Side::INSIDE : Side::OUTSIDE;
    }
    ADD_FAILURE() << "every reference direction is degenerate at " << point.transpose();
    return Side::OUTSIDE;
}

/// A body of a scene: node positions and outward boundary faces.
struct Body {
    Positions nodes;
    Tris faces;
};

/// k/8 for a random k in [lo, hi].
double eighths(std::mt19937& rng, int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng) / 8.0; }

Body random_box(std::mt19937& rng)
{
    const Vec3 min(eighths(rng, 0, 8), eighths(rng, 0, 8), eighths(rng, 0, 8));
    const Vec3 size(eighths(rng, 2, 8), eighths(rng, 2, 8), eighths(rng, 2, 8));
    std::uniform_int_distribution<Index> cells(1, 5);
    const TetMesh mesh = make_box(min, min + size, {cells(rng), cells(rng), cells(rng)});
    return {mesh.rest_positions, boundary_faces(mesh)};
}

Body random_octahedron(std::mt19937& rng)
{
    const Vec3 centre(eighths(rng, 4, 12), eighths(rng, 4, 12), eighths(rng, 4, 12));
    const double radius = eighths(rng, 2, 6);
    Body b{Positions(6, 3), Tris(8, 3)};
    for (int axis = 0; axis < 3; ++axis)
        for (int sign = 0; sign < 2; ++sign) {
            b.nodes.row(2 * axis + sign) = centre.transpose();
            b.nodes(2 * axis + sign, axis) += sign == 0 ? radius : -radius;
        }
    b.faces << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
    return b;
}

/// One of four perturbations of the whole scene (or of one body), or none.
void perturb(std::vector<Body>& bodies, std::mt19937& rng)
{
    std::uniform_int_distribution<int> pick(0, 4);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    switch (pick(rng)) {
    case 0: { // a few coordinates of one body, 1–4 ulps either way
        Positions& x = bodies[std::uniform_int_distribution<std::size_t>(0, bodies.size() - 1)(rng)].nodes;
        for (int n = 0; n < 4; ++n) {
            double& c = x(std::uniform_int_distribution<Eigen::Index>(0, x.rows() - 1)(rng),
                          std::uniform_int_distribution<Eigen::Index>(0, 2)(rng));
            const double toward = unit(rng) < 0.0 ? -INF : INF;
            for (int k = std::uniform_int_distribution<int>(1, 4)(rng); k > 0; --k)
                c = std::nextafter(c, toward);
        }
        break;
    }
    case 1: { // the scene rotated in floating point: exact coincidences become near ones
        const Eigen::Quaterniond q = Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng)).normalized();
        const Eigen::Matrix3d r = q.toRotationMatrix();
        for (Body& b : bodies)
            b.nodes = (b.nodes * r.transpose()).eval();
        break;
    }
    case 2: { // the scene far from the origin (exactly, where the coordinates' bits allow)
        const double scale = std::exp2(std::uniform_int_distribution<int>(1, 3)(rng) * 10);
        const Eigen::RowVector3d shift(scale * 3, -scale * 5, scale);
        for (Body& b : bodies)
            b.nodes.rowwise() += shift;
        break;
    }
    case 3: { // noise at the level of the coordinates' rounding on one body
        Positions& x = bodies[std::uniform_int_distribution<std::size_t>(0, bodies.size() - 1)(rng)].nodes;
        const double size = std::exp2(-std::uniform_int_distribution<int>(40, 53)(rng));
        for (Eigen::Index i = 0; i < x.size(); ++i)
            x.data()[i] += unit(rng) * size * std::abs(x.data()[i]);
        break;
    }
    default: break; // the grid as it is: vertices exactly on faces, edges and vertices
    }
}

/// Points within rounding of `s`'s surface, where float signs of the inside test cannot decide:
/// for some of its faces, the centroid, an edge midpoint (the edge of two faces) and another
/// point of the face, each as computed in floating point and nudged 1 or 2 ulps either way along
/// one coordinate.
std::vector<Vec3> points_near_faces(const ContactSurface& s, int faces, std::mt19937& rng)
{
    std::vector<Vec3> points;
    std::uniform_int_distribution<Eigen::Index> face(0, s.faces.rows() - 1);
    std::uniform_int_distribution<int> coordinate(0, 2);
    for (int n = 0; n < faces; ++n) {
        const Eigen::Index f = face(rng);
        const Vec3 a = s.vertices.row(s.faces(f, 0)), b = s.vertices.row(s.faces(f, 1)),
                   c = s.vertices.row(s.faces(f, 2));
        for (const Vec3& on : {Vec3((a + b + c) / 3.0), Vec3(0.5 * (a + b)), Vec3(0.25 * a + 0.25 * b + 0.5 * c)}) {
            const int i = coordinate(rng);
            for (const int ulps : {-2, -1, 0, 1, 2}) {
                Vec3 p = on;
                for (int k = 0; k < std::abs(ulps); ++k)
                    p[i] = std::nextafter(p[i], ulps > 0 ? INF : -INF);
                points.push_back(p);
            }
        }
    }
    return points;
}

using Contact = std::tuple<Index, Index, Index>; // (body, vertex, other body)

std::set<Contact> contacts_found(const std::vector<ContactSurface>& surfaces, DetectionMode mode, Index& shared)
{
    DetectionSettings settings;
    settings.mode = mode;
    DetectionScratch scratch;
    DetectionStats stats;
    std::set<Contact> found;
    for (const ContactPoint& c : detect_contacts(surfaces, settings, scratch, &stats)) {
        EXPECT_TRUE(c.other.is_surface());
        EXPECT_TRUE(std::isfinite(c.depth) && c.depth >= 0.0) << c.depth;
        found.emplace(c.body, c.vertex, c.other.index);
    }
    shared += stats.by_neighbour + stats.by_hull;
    return found;
}

} // namespace

TEST(ExactReference, DetectionAgreesWithExactRationalsOnGridAndPerturbedScenes)
{
    std::mt19937 rng(20261127);
    const AxisRayTolerances tolerances;
    const std::vector<Index> no_faces;
    long inside = 0, on_surface = 0, outside = 0;
    std::array<long, 3> near_face{}; // points near faces: outside, inside, on the surface
    Index shared = 0;                 // answers detection shared (clear-edge groups, hull slabs)
    for (int scene = 0; scene < 80; ++scene) {
        std::vector<Body> bodies;
        const int count = std::uniform_int_distribution<int>(2, 3)(rng);
        for (int b = 0; b < count; ++b)
            bodies.push_back(std::uniform_int_distribution<int>(0, 2)(rng) == 0 ? random_octahedron(rng)
                                                                                 : random_box(rng));
        perturb(bodies, rng);
        std::vector<ContactSurface> surfaces;
        for (std::size_t b = 0; b < bodies.size(); ++b)
            surfaces.push_back(ContactSurface::from_body("body" + std::to_string(b), bodies[b].nodes, bodies[b].faces));

        std::vector<ExactSurface> exact;
        for (const ContactSurface& s : surfaces)
            exact.emplace_back(s);
        std::set<Contact> expected;
        for (std::size_t a = 0; a < surfaces.size(); ++a)
            for (std::size_t b = 0; b < surfaces.size(); ++b) {
                if (a == b)
                    continue;
                for (Eigen::Index v = 0; v < surfaces[a].vertices.rows(); ++v) {
                    const Vec3 p = surfaces[a].vertices.row(v).transpose();
                    const Side side = exact_side(exact[b], p);
                    inside += side == Side::INSIDE;
                    on_surface += side == Side::ON_SURFACE;
                    outside += side == Side::OUTSIDE;
                    if (side == Side::INSIDE)
                        expected.emplace(static_cast<Index>(a), static_cast<Index>(v), static_cast<Index>(b));
                    const InsideTest r = inside_test(surfaces[b], p, DetectionMode::EXACT, no_faces, tolerances);
                    EXPECT_EQ(r.inside, side == Side::INSIDE) << "scene " << scene << ", body " << a << " vertex " << v
                                                              << " against body " << b;
                    EXPECT_EQ(r.on_surface, side == Side::ON_SURFACE) << "scene " << scene << ", body " << a
                                                                      << " vertex " << v << " against body " << b;
                }
            }
        for (std::size_t i = 0; i < surfaces.size(); ++i) {
            const ContactSurface& b = surfaces[i];
            for (const Vec3& p : points_near_faces(b, 8, rng)) {
                const Side side = exact_side(exact[i], p);
                near_face[static_cast<std::size_t>(side)] += 1;
                for (const DetectionMode mode : {DetectionMode::EXACT, DetectionMode::BRUTE_FORCE}) {
                    const InsideTest r = inside_test(b, p, mode, no_faces, tolerances);
                    EXPECT_EQ(r.inside, side == Side::INSIDE) << "scene " << scene << ", " << b.name << ", point "
                                                              << p.transpose();
                    EXPECT_EQ(r.on_surface, side == Side::ON_SURFACE) << "scene " << scene << ", " << b.name
                                                                      << ", point " << p.transpose();
                }
            }
        }
        EXPECT_EQ(contacts_found(surfaces, DetectionMode::EXACT, shared), expected) << "scene " << scene;
        EXPECT_EQ(contacts_found(surfaces, DetectionMode::BRUTE_FORCE, shared), expected) << "scene " << scene;
    }
    // The corpus must exercise all three answers, touching included.
    EXPECT_GT(inside, 100);
    EXPECT_GT(on_surface, 100);
    EXPECT_GT(outside, 100);
    for (const long n : near_face)
        EXPECT_GT(n, 100);
    EXPECT_GT(shared, 100);
    std::printf("exact reference: vertices %ld inside, %ld on a surface, %ld outside; points near faces %ld inside, "
                "%ld on a surface, %ld outside; %ld answers shared\n",
                inside, on_surface, outside, near_face[1], near_face[2], near_face[0], static_cast<long>(shared));
}

namespace {

/// What segment_misses_triangle claims when it answers "misses", in exact signs: both ends
/// strictly on one side of the triangle's plane, or the segment's line strictly on the left of
/// one edge and strictly on the right of another.
bool exactly_disjoint(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c)
{
    const int sp = orientation(a, b, c, p), sq = orientation(a, b, c, q);
    if (sp != 0 && sp == sq)
        return true;
    const int e0 = orientation(p, q, a, b), e1 = orientation(p, q, b, c), e2 = orientation(p, q, c, a);
    return (e0 > 0 || e1 > 0 || e2 > 0) && (e0 < 0 || e1 < 0 || e2 < 0);
}

} // namespace


TEST(ExactReference, SubnormalCoordinatesAreDecidedExactly)
{
    // A box whose face y = 0 is tilted by a subnormal amount: its corner (1/2, 0, 5/4) moved to
    // y = k times the smallest subnormal. The point (9/16, k/2 of it, 33/32) lies on the tilted
    // face; points a few ulps and subnormal steps away lie on either side. The float products of
    // the orientation signs underflow there, which relative rounding bounds alone do not cover
    // (found by the scenes above with another seed: a point on the surface was inside). The same
    // points start segments for the grouping's edge test.
    const TetMesh mesh = make_box(Vec3(0.25, 0.0, 0.375), Vec3(1.0, 0.375, 1.25), {3, 4, 1});
    const Tris faces = boundary_faces(mesh);
    const double tiny = std::numeric_limits<double>::denorm_min();
    const AxisRayTolerances tolerances;
    const std::vector<Index> no_faces;
    std::array<long, 3> sides{};
    for (const int k : {-4, -2, 2, 4}) {
        Positions nodes = mesh.rest_positions;
        for (Eigen::Index v = 0; v < nodes.rows(); ++v)
            if (nodes.row(v) == Eigen::RowVector3d(0.5, 0.0, 1.25))
                nodes(v, 1) = k * tiny;
        const ContactSurface surface = ContactSurface::from_body("box", nodes, faces);
        const ExactSurface exact(surface);
        for (int ulps = -2; ulps <= 2; ++ulps)
            for (int steps = -2; steps <= 2; ++steps) {
                Vec3 p(0.5625, (k / 2 + steps) * tiny, 1.03125);
                for (int i = 0; i < std::abs(ulps); ++i)
                    p.x() = std::nextafter(p.x(), ulps > 0 ? 1.0 : 0.0);
                const Side side = exact_side(exact, p);
                sides[static_cast<std::size_t>(side)] += 1;
                for (const DetectionMode mode : {DetectionMode::EXACT, DetectionMode::BRUTE_FORCE}) {
                    const InsideTest r = inside_test(surface, p, mode, no_faces, tolerances);
                    EXPECT_EQ(r.inside, side == Side::INSIDE) << "k " << k << ", point " << p.transpose();
                    EXPECT_EQ(r.on_surface, side == Side::ON_SURFACE) << "k " << k << ", point " << p.transpose();
                }
                // The grouping's edge test from p, a face at a time and TRIANGLE_LANES at once:
                // "misses" must hold exactly.
                for (const Vec3& q : {Vec3(p + Vec3(0.0, 1.0, 0.0)), Vec3(p + Vec3(0.125, -1.0, 0.25))})
                    for (Eigen::Index first = 0; first < surface.faces.rows(); first += detail::TRIANGLE_LANES) {
                        const double *a[detail::TRIANGLE_LANES], *b[detail::TRIANGLE_LANES], *c[detail::TRIANGLE_LANES];
                        const int count = static_cast<int>(
                            std::min<Eigen::Index>(detail::TRIANGLE_LANES, surface.faces.rows() - first));
                        int singles = 0;
                        for (int lane = 0; lane < count; ++lane) {
                            const Eigen::Index face = first + lane;
                            const Vec3 fa = surface.vertices.row(surface.faces(face, 0)),
                                       fb = surface.vertices.row(surface.faces(face, 1)),
                                       fc = surface.vertices.row(surface.faces(face, 2));
                            a[lane] = &surface.vertices(surface.faces(face, 0), 0);
                            b[lane] = &surface.vertices(surface.faces(face, 1), 0);
                            c[lane] = &surface.vertices(surface.faces(face, 2), 0);
                            if (detail::segment_misses_triangle(p.data(), q.data(), a[lane], b[lane], c[lane])) {
                                singles |= 1 << lane;
                                EXPECT_TRUE(exactly_disjoint(p, q, fa, fb, fc))
                                    << "k " << k << ", segment from " << p.transpose() << ", face " << face;
                            }
                        }
                        EXPECT_EQ(detail::segment_misses_triangles(p.data(), q.data(), a, b, c, count), singles);
                    }
            }
    }
    for (const long n : sides)
        EXPECT_GT(n, 0);
}

TEST(ExactReference, PointsOnATinyFaceAreOnTheSurface)
{
    // A tetrahedron of edge 2⁻⁵⁴⁰: every float component of its faces' normals underflows to 0,
    // so a projection chosen by them can be one where a face is edge-on.
    const double s = std::ldexp(1.0, -540);
    Positions v(4, 3);
    v << 0, 0, 0, s, 0, 0, 0, s, 0, 0, 0, s;
    Tris f(4, 3);
    f << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
    const ContactSurface tetrahedron = ContactSurface::from_body("tiny", v, f);
    const ExactSurface exact(tetrahedron);
    const AxisRayTolerances tolerances;
    const std::vector<Index> no_faces;
    const double q = s / 4;
    for (const Vec3& p : {Vec3(q, 0, q), Vec3(q, q, 0), Vec3(0, q, q), Vec3(q, q, q), Vec3(q, q, 2 * q),
                          Vec3(q, q, 3 * q), Vec3(-q, q, q)}) {
        const Side side = exact_side(exact, p);
        for (const DetectionMode mode : {DetectionMode::EXACT, DetectionMode::BRUTE_FORCE}) {
            const InsideTest r = inside_test(tetrahedron, p, mode, no_faces, tolerances);
            EXPECT_EQ(r.inside, side == Side::INSIDE) << "point " << p.transpose() / q << " × s/4";
            EXPECT_EQ(r.on_surface, side == Side::ON_SURFACE) << "point " << p.transpose() / q << " × s/4";
        }
    }
    // The points chosen cover all three answers.
    EXPECT_EQ(exact_side(exact, Vec3(q, 0, q)), Side::ON_SURFACE);
    EXPECT_EQ(exact_side(exact, Vec3(q, q, q)), Side::INSIDE);
    EXPECT_EQ(exact_side(exact, Vec3(q, q, 3 * q)), Side::OUTSIDE);
}

