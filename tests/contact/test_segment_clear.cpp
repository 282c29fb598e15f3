#include "contact_scenes.hpp"

#include <corocontact/contact/aabb_tree.hpp>
#include <corocontact/core/primitives.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace coro;
using namespace coro::test;

namespace {

using Quad = __float128;

struct Vec3q {
    Quad x, y, z;
};
Vec3q quad(const Vec3& a) { return {a.x(), a.y(), a.z()}; }
Vec3q operator-(const Vec3q& a, const Vec3q& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Quad dot(const Vec3q& a, const Vec3q& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3q cross(const Vec3q& a, const Vec3q& b)
{
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

/// Whether the closed segment [p, q] meets the closed triangle (a, b, c): Möller–Trumbore
/// (p + t(q − p) = a + u(b − a) + v(c − a)) in quadruple precision, a formulation independent
/// of AabbTree::segment_clear's signs and near-exact for double input. A segment parallel to
/// the triangle's plane counts as missing it (random segments are never coplanar with a face).
bool segment_meets_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c)
{
    const Vec3q r = quad(q) - quad(p), e1 = quad(b) - quad(a), e2 = quad(c) - quad(a);
    const Vec3q h = cross(r, e2);
    const Quad det = dot(e1, h);
    if (det == 0)
        return false;
    const Vec3q s = quad(p) - quad(a);
    const Quad u = dot(s, h) / det;
    const Vec3q k = cross(s, e1);
    const Quad v = dot(r, k) / det;
    const Quad t = dot(e2, k) / det;
    return u >= 0 && v >= 0 && u + v <= 1 && t >= 0 && t <= 1;
}

bool segment_meets_surface(const ContactSurface& s, const Vec3& p, const Vec3& q)
{
    const Vec3 lo = p.cwiseMin(q), hi = p.cwiseMax(q);
    for (Index f = 0; f < s.faces.rows(); ++f) {
        Aabb box; // a face whose box misses the segment's cannot meet it
        for (int c = 0; c < 3; ++c)
            box.extend(s.vertices.row(s.faces(f, c)).transpose());
        if ((box.min.array() > hi.array()).any() || (box.max.array() < lo.array()).any())
            continue;
        if (segment_meets_triangle(p, q, s.vertices.row(s.faces(f, 0)).transpose(),
                                   s.vertices.row(s.faces(f, 1)).transpose(),
                                   s.vertices.row(s.faces(f, 2)).transpose()))
            return true;
    }
    return false;
}

/// Random segments from `starts`, random directions, lengths log-uniform in [1e-4, 0.5]:
/// segment_clear is true exactly when no face meets the segment (sign ties are never drawn).
void expect_segments_match_brute_force(const ContactSurface& s, const std::vector<Vec3>& starts, std::mt19937& rng)
{
    std::normal_distribution<double> normal;
    std::uniform_real_distribution<double> exponent(-4.0, std::log10(0.5));
    const int count = static_cast<int>(starts.size());
    int clear = 0, blocked = 0;
    for (const Vec3& p : starts) {
        const Vec3 d = Vec3(normal(rng), normal(rng), normal(rng)).normalized();
        const Vec3 q = p + std::pow(10.0, exponent(rng)) * d;
        const bool meets = segment_meets_surface(s, p, q);
        EXPECT_EQ(s.tree.segment_clear(s.vertices, p, q), !meets)
            << "segment " << p.transpose() << " → " << q.transpose();
        (meets ? blocked : clear) += 1;
    }
    // Both answers are exercised.
    EXPECT_GT(clear, count / 10);
    EXPECT_GT(blocked, count / 20);
}

} // namespace

TEST(SegmentClear, MatchesBruteForceOnADeformedBall)
{
    std::mt19937 rng(11);
    const ContactSurface ball = deformed_ball(Vec3(0.1, -0.2, 0.3), 1.0, 8, 0.1, "ball");
    // Starts within 0.1 of a surface vertex: many segments cross or pass close to the surface.
    std::uniform_int_distribution<Index> vertex(0, ball.vertices.rows() - 1);
    std::vector<Vec3> starts;
    for (int i = 0; i < 2000; ++i)
        starts.push_back(ball.vertices.row(vertex(rng)).transpose() +
                         random_point(Vec3::Constant(-0.1), Vec3::Constant(0.1), rng));
    expect_segments_match_brute_force(ball, starts, rng);
}

TEST(SegmentClear, MatchesBruteForceOnATriangleSoup)
{
    std::mt19937 rng(12);
    const ContactSurface soup = surface_of(random_triangles(300, rng), "soup");
    std::vector<Vec3> starts;
    for (int i = 0; i < 2000; ++i)
        starts.push_back(random_point(Vec3::Zero(), Vec3::Ones(), rng));
    expect_segments_match_brute_force(soup, starts, rng);
}

TEST(SegmentClear, SegmentsTouchingTheSurfaceAreNeverClear)
{
    // Unit cube, two cells per side: mesh vertices at 0, 0.5 and 1 in each coordinate.
    const ContactSurface cube = surface_of(make_box(Vec3::Zero(), Vec3::Ones(), {2, 2, 2}), "cube");
    const auto clear = [&](const Vec3& p, const Vec3& q) { return cube.tree.segment_clear(cube.vertices, p, q); };
    // Ending on a face, inside a triangle, from inside and from outside.
    EXPECT_FALSE(clear(Vec3(0.3, 0.4, 0.5), Vec3(0.3, 0.4, 1.0)));
    EXPECT_FALSE(clear(Vec3(0.3, 0.4, 1.5), Vec3(0.3, 0.4, 1.0)));
    // Crossing a face.
    EXPECT_FALSE(clear(Vec3(0.3, 0.4, 0.5), Vec3(0.3, 0.4, 1.5)));
    // Lying in a face's plane, on the face.
    EXPECT_FALSE(clear(Vec3(0.2, 0.3, 1.0), Vec3(0.7, 0.6, 1.0)));
    // Through a mesh vertex, through an edge of the cube, through a corner.
    EXPECT_FALSE(clear(Vec3(0.5, 0.5, 0.9), Vec3(0.5, 0.5, 1.1)));
    EXPECT_FALSE(clear(Vec3(0.3, 0.9, 1.1), Vec3(0.3, 1.1, 0.9)));
    EXPECT_FALSE(clear(Vec3(0.9, 0.9, 0.9), Vec3(1.1, 1.1, 1.1)));
    // A point of the surface as a segment of length zero.
    EXPECT_FALSE(clear(Vec3(0.3, 0.4, 1.0), Vec3(0.3, 0.4, 1.0)));

    // Clear: inside, outside, parallel to a face a hair away, zero length off the surface.
    EXPECT_TRUE(clear(Vec3(0.2, 0.3, 0.4), Vec3(0.8, 0.7, 0.6)));
    EXPECT_TRUE(clear(Vec3(1.2, 0.3, 0.4), Vec3(1.8, 1.7, 1.6)));
    EXPECT_TRUE(clear(Vec3(0.1, 0.1, 1.0 + 1e-9), Vec3(0.9, 0.9, 1.0 + 1e-9)));
    EXPECT_TRUE(clear(Vec3(0.1, 0.1, 1.0 - 1e-9), Vec3(0.9, 0.9, 1.0 - 1e-9)));
    EXPECT_TRUE(clear(Vec3(0.3, 0.4, 0.5), Vec3(0.3, 0.4, 0.5)));
}
