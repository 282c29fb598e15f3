// The hull slabs that keep candidate vertices out of inside tests
// (src/contact/detail/hull_slabs.hpp): they never exclude a point of a surface's convex hull
// (so never a point inside a closed surface), checked on hull points and against an independent
// point-in-polyhedron test; and they exclude most of the box around a rotated box or a ball,
// the reason they exist.
#include "contact_scenes.hpp"

#include <corocontact/core/primitives.hpp>

#include "detail/hull_slabs.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace coro;
using coro::detail::HullSlabs;

namespace {

// A cube of side 1 turned by 40° about (1, 2, 3) and moved far from the origin (so that the
// slabs' rounding is exercised at a large |x|₁).
ContactSurface turned_cube()
{
    ContactSurface s = test::surface_of(make_box(Vec3(0, 0, 0), Vec3(1, 1, 1), {2, 2, 2}), "cube");
    const Mat3 r = Eigen::AngleAxisd(40.0 * M_PI / 180.0, Vec3(1, 2, 3).normalized()).toRotationMatrix();
    for (Eigen::Index v = 0; v < s.vertices.rows(); ++v)
        s.vertices.row(v) = (r * s.vertices.row(v).transpose() + Vec3(1e3, -2e3, 5e2)).transpose();
    return s;
}

Vec3 box_min(const ContactSurface& s) { return s.vertices.colwise().minCoeff().transpose(); }
Vec3 box_max(const ContactSurface& s) { return s.vertices.colwise().maxCoeff().transpose(); }

} // namespace

TEST(HullSlabs, KeepEveryVertexAndEveryPointBetweenVertices)
{
    for (const ContactSurface& s : {turned_cube(), test::deformed_ball(Vec3(0.3, -7, 2), 0.8, 3, 0.05, "ball")}) {
        const HullSlabs hull = HullSlabs::of(s.vertices);
        std::mt19937 rng(11);
        std::uniform_int_distribution<Eigen::Index> pick(0, s.vertices.rows() - 1);
        std::uniform_real_distribution<double> u(0.0, 1.0);
        for (Eigen::Index v = 0; v < s.vertices.rows(); ++v)
            EXPECT_TRUE(hull.may_contain(s.vertices.row(v).transpose())) << s.name << " vertex " << v;
        for (int i = 0; i < 20000; ++i) {
            // A point on a segment, or in a triangle, of vertices: in the convex hull.
            const Vec3 a = s.vertices.row(pick(rng)).transpose(), b = s.vertices.row(pick(rng)).transpose(),
                       c = s.vertices.row(pick(rng)).transpose();
            const double t = u(rng), w = u(rng) * (1.0 - t);
            const Vec3 p = i % 2 == 0 ? Vec3(a + t * (b - a)) : Vec3(t * a + w * b + (1.0 - t - w) * c);
            EXPECT_TRUE(hull.may_contain(p)) << s.name << " point " << p.transpose();
        }
    }
}

TEST(HullSlabs, ExcludeOnlyPointsOutsideAndMostOfTheBoxAround)
{
    for (const ContactSurface& s : {turned_cube(), test::deformed_ball(Vec3(0.3, -7, 2), 0.8, 3, 0.05, "ball")}) {
        const HullSlabs hull = HullSlabs::of(s.vertices);
        std::mt19937 rng(5);
        int excluded = 0, outside = 0;
        const int n = 4000;
        for (int i = 0; i < n; ++i) {
            const Vec3 p = test::random_point(box_min(s), box_max(s), rng);
            const bool inside = test::ray_parity_inside(s.vertices, s.faces, p, rng);
            outside += inside ? 0 : 1;
            if (!hull.may_contain(p)) {
                ++excluded;
                EXPECT_FALSE(inside) << s.name << ": excluded a point inside, " << p.transpose();
            }
        }
        // Points of the box outside the body: 73 % for the turned cube, 47 % for the ball; the
        // slabs exclude 64 % and 76 % of those.
        EXPECT_GT(excluded, outside / 2) << s.name << ": " << excluded << " excluded of " << outside << " outside";
    }
}

TEST(HullSlabs, NeverExcludeANaN)
{
    const HullSlabs hull = HullSlabs::of(turned_cube().vertices);
    EXPECT_TRUE(hull.may_contain(Vec3(std::nan(""), 0, 0)));
}
