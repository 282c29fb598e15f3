#include "contact_scenes.hpp"

#include <corocontact/contact/aabb_tree.hpp>
#include <corocontact/core/primitives.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

using namespace coro;
using namespace coro::test;

namespace {

/// Box of face f, from its vertices (not the tree's).
Aabb face_box(const SurfaceMesh& m, Index f)
{
    Aabb box;
    for (int c = 0; c < 3; ++c)
        box.extend(m.vertices.row(m.faces(f, c)).transpose());
    return box;
}

/// L∞ distance from p to the nearest face box, by scanning every face.
double brute_force_distance(const SurfaceMesh& m, const Vec3& p)
{
    double best = std::numeric_limits<double>::infinity();
    for (Index f = 0; f < m.faces.rows(); ++f) {
        const Aabb b = face_box(m, f);
        const Vec3 gap = (b.min - p).cwiseMax(p - b.max).cwiseMax(0.0);
        best = std::min(best, gap.maxCoeff());
    }
    return best;
}

/// The closed cube [p − h, p + h], computed in double as documented, meets no face box.
void expect_cube_misses_every_face(const SurfaceMesh& m, const Vec3& p, double h)
{
    const Aabb cube{p.array() - h, p.array() + h};
    for (Index f = 0; f < m.faces.rows(); ++f)
        ASSERT_FALSE(cube.overlaps(face_box(m, f))) << "face " << f << ", point " << p.transpose() << ", h " << h;
}

/// For random points near and far: h is the brute-force distance (capped), a hair below it, the
/// cube misses every face box, the walk gives up below the minimum, and a hint changes nothing.
void expect_cubes_match_brute_force(const AabbTree& tree, const SurfaceMesh& m, const Aabb& region, int queries,
                                    std::mt19937& rng)
{
    int capped = 0, refused = 0, exact = 0;
    Index hint = -1;
    for (int q = 0; q < queries; ++q) {
        const Vec3 p = random_point(region.min, region.max, rng);
        const double distance = brute_force_distance(m, p);
        const double cap = q % 3 == 0 ? 0.05 : 10.0;
        const double min_half_size = q % 5 == 0 ? 0.02 : 0.0;
        const double h = tree.empty_cube(m.vertices, p, min_half_size, cap);
        EXPECT_EQ(tree.empty_cube(m.vertices, p, min_half_size, cap, &hint), h) << "hint " << hint; // bitwise
        const double wanted = std::min(distance, cap);
        if (wanted < min_half_size * (1.0 - 1e-9)) {
            EXPECT_EQ(h, 0.0) << p.transpose();
            ++refused;
            continue;
        }
        EXPECT_LE(h, wanted);
        // Below it by the documented margin: relative 2⁻³⁰ and 2⁻⁴⁰ of the coordinates' size.
        EXPECT_GE(h, wanted * (1.0 - 1e-8) - p.cwiseAbs().maxCoeff() * 0x1p-39)
            << p.transpose() << ", distance " << distance;
        if (h > 0.0) // 0: the point lies in a face box
            expect_cube_misses_every_face(m, p, h);
        capped += distance > cap ? 1 : 0;
        exact += distance <= cap ? 1 : 0;
    }
    EXPECT_GT(capped, queries / 20);
    EXPECT_GT(exact, queries / 4);
    EXPECT_GT(refused, 0);
}

} // namespace

TEST(EmptyCube, EqualsTheBruteForceDistanceToTheFaceBoxesOfRandomTriangles)
{
    std::mt19937 rng(41);
    const SurfaceMesh m = random_triangles(300, rng);
    AabbTree tree;
    tree.build(m.vertices, m.faces);
    expect_cubes_match_brute_force(tree, m, tree.bounds().inflated(0.3), 600, rng);
}

TEST(EmptyCube, EqualsTheBruteForceDistanceOnASphereInsideAndOutside)
{
    std::mt19937 rng(42);
    const TetMesh ball = make_sphere(Vec3(0.3, -0.2, 0.1), 1.0, 10);
    const SurfaceMesh m{ball.rest_positions, boundary_faces(ball)};
    AabbTree tree;
    tree.build(m.vertices, m.faces);
    expect_cubes_match_brute_force(tree, m, tree.bounds().inflated(0.2), 400, rng);
}

TEST(EmptyCube, PointOnTheSurfaceOrFarCoordinatesGetASafeCube)
{
    std::mt19937 rng(43);
    // A surface far from the origin: the margin must cover the rounding of p ± h there.
    TetMesh ball = make_sphere(Vec3(1e6, -2e6, 3e5), 1.0, 6);
    const SurfaceMesh m{ball.rest_positions, boundary_faces(ball)};
    AabbTree tree;
    tree.build(m.vertices, m.faces);
    for (Index f = 0; f < m.faces.rows(); ++f) // surface vertices: no cube
        EXPECT_EQ(tree.empty_cube(m.vertices, m.vertices.row(m.faces(f, 0)).transpose(), 0.0, 1.0), 0.0) << "face " << f;
    expect_cubes_match_brute_force(tree, m, tree.bounds().inflated(0.5), 200, rng);
    // Points a hair outside the surface's box (gaps down to the margin): any cube is still clear.
    const Aabb bounds = tree.bounds();
    int cubes = 0;
    for (const double gap : {1e-4, 1e-5, 3e-6, 1e-6}) {
        for (int q = 0; q < 30; ++q) {
            Vec3 p = random_point(bounds.min, bounds.max, rng);
            const int axis = q % 3;
            p[axis] = q % 2 == 0 ? bounds.max[axis] + gap : bounds.min[axis] - gap;
            const double h = tree.empty_cube(m.vertices, p, 0.0, 1.0);
            if (h > 0.0) {
                expect_cube_misses_every_face(m, p, h);
                ++cubes;
            }
        }
    }
    EXPECT_GT(cubes, 40);
}

TEST(EmptyCube, EmptyTreeGivesTheCap)
{
    AabbTree tree;
    tree.build(Positions(0, 3), Tris(0, 3));
    EXPECT_EQ(tree.empty_cube(Positions(0, 3), Vec3(1, 2, 3), 0.5, 2.0) , 2.0 * (1.0 - 0x1p-30) - 3.0 * 0x1p-40);
    EXPECT_EQ(tree.empty_cube(Positions(0, 3), Vec3(1, 2, 3), 0.5, 0.0), 0.0);
}
