// segment_misses_triangles (up to four triangles per call, AVX2 lanes where the build has them)
// against segment_misses_triangle, one triangle at a time: the same answer for every triangle,
// on random configurations and on degenerate ones where signs are zero or within rounding.
#include "detail/segment_triangle.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

using coro::detail::segment_misses_triangle;
using coro::detail::segment_misses_triangles;
using coro::detail::TRIANGLE_LANES;

namespace {

using Point = std::array<double, 3>;

struct Triangle {
    Point a, b, c;
};

/// For every count 1..TRIANGLE_LANES and every window of `triangles`: each bit of the batched
/// answer equals the single test. Returns how many single tests said "misses".
int expect_batches_match_single_tests(const Point& p, const Point& q, const std::vector<Triangle>& triangles)
{
    int misses = 0;
    for (const Triangle& t : triangles)
        misses += segment_misses_triangle(p.data(), q.data(), t.a.data(), t.b.data(), t.c.data()) ? 1 : 0;
    for (int count = 1; count <= TRIANGLE_LANES; ++count)
        for (std::size_t first = 0; first + static_cast<std::size_t>(count) <= triangles.size(); ++first) {
            const double *a[TRIANGLE_LANES], *b[TRIANGLE_LANES], *c[TRIANGLE_LANES];
            int expected = 0;
            for (int k = 0; k < count; ++k) {
                const Triangle& t = triangles[first + static_cast<std::size_t>(k)];
                a[k] = t.a.data();
                b[k] = t.b.data();
                c[k] = t.c.data();
                expected |= segment_misses_triangle(p.data(), q.data(), a[k], b[k], c[k]) ? 1 << k : 0;
            }
            EXPECT_EQ(segment_misses_triangles(p.data(), q.data(), a, b, c, count), expected)
                << "segment (" << p[0] << ", " << p[1] << ", " << p[2] << ") → (" << q[0] << ", " << q[1] << ", "
                << q[2] << "), " << count << " triangles from " << first;
        }
    return misses;
}

} // namespace

TEST(SegmentTriangles, BatchesMatchSingleTestsOnRandomTriangles)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
    // Segments from below z = −0.5 to above z = 0.5, triangles between: many cross.
    const auto point = [&](double z) { return Point{coordinate(rng), coordinate(rng), z + 0.4 * coordinate(rng)}; };
    int misses = 0, tests = 0;
    for (int trial = 0; trial < 400; ++trial) {
        const Point p = point(-1.0), q = point(1.0);
        std::vector<Triangle> triangles;
        for (int t = 0; t < 6; ++t)
            triangles.push_back({point(0.0), point(0.0), point(0.0)});
        misses += expect_batches_match_single_tests(p, q, triangles);
        tests += 6;
    }
    // Both answers occur often: the comparison covers both.
    EXPECT_GT(misses, tests / 10);
    EXPECT_LT(misses, tests - tests / 10);
}

TEST(SegmentTriangles, BatchesMatchSingleTestsOnDegenerateConfigurations)
{
    // Triangles in the plane z = 0 on a coarse integer grid; segments whose ends lie on grid
    // points, on the plane, on edges and vertices, or along a side: many signs are exactly zero.
    std::mt19937 rng(11);
    std::uniform_int_distribution<int> grid(-2, 2);
    const auto point = [&](bool flat) {
        return Point{0.5 * grid(rng), 0.5 * grid(rng), flat ? 0.0 : 0.5 * grid(rng)};
    };
    int misses = 0, tests = 0;
    for (int trial = 0; trial < 600; ++trial) {
        const Point p = point(trial % 3 == 0), q = point(trial % 5 == 0);
        std::vector<Triangle> triangles;
        for (int t = 0; t < 5; ++t)
            triangles.push_back({point(true), point(true), point(t % 2 == 0)});
        triangles.push_back({p, q, point(false)}); // through both ends of the segment
        triangles.push_back({p, p, q});            // degenerate: a repeated vertex
        misses += expect_batches_match_single_tests(p, q, triangles);
        tests += static_cast<int>(triangles.size());
    }
    EXPECT_GT(misses, tests / 10);
    EXPECT_LT(misses, tests - tests / 10);
}

TEST(SegmentTriangles, BatchesMatchSingleTestsNearTheRoundingBounds)
{
    // A segment crossing the plane of a triangle next to one of its edges, at offsets from
    // far outside to far inside in steps that pass through the rounding bounds of the signs.
    const Triangle t{{0.1, 0.2, 0.3}, {1.3, 0.25, 0.31}, {0.4, 1.1, 0.29}};
    std::vector<Triangle> triangles(TRIANGLE_LANES, t);
    const Point mid{0.5 * (t.a[0] + t.b[0]), 0.5 * (t.a[1] + t.b[1]), 0.5 * (t.a[2] + t.b[2])};
    int misses = 0, tests = 0;
    for (int e = -60; e <= -1; ++e)
        for (const double sign : {-1.0, 1.0}) {
            const double offset = sign * std::ldexp(1.0, e);
            const Point p{mid[0], mid[1] + offset, mid[2] - 0.5}, q{mid[0], mid[1] + offset, mid[2] + 0.5};
            misses += expect_batches_match_single_tests(p, q, triangles);
            tests += TRIANGLE_LANES;
        }
    EXPECT_GT(misses, 0);
    EXPECT_LT(misses, tests);
}
