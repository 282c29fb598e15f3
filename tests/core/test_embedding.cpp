#include "near.hpp"

#include <corocontact/core/embedding.hpp>
#include <corocontact/core/primitives.hpp>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <random>

using namespace coro;

namespace {
Positions random_points(Index n, double lo, double hi, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(lo, hi);
    Positions p(n, 3);
    for (Index i = 0; i < n; ++i)
        p.row(i) << u(rng), u(rng), u(rng);
    return p;
}
} // namespace

TEST(EmbedPoints, WeightsReproduceThePointsInsideAndJustOutside)
{
    const TetMesh mesh = make_sphere(Vec3::Zero(), 1.0, 6);
    const Positions points = random_points(200, -0.75, 0.75, 3);
    const Embedding embedding = embed_points(mesh, points);
    for (Index i = 0; i < points.rows(); ++i) {
        const Eigen::Vector4d& w = embedding.weights[static_cast<std::size_t>(i)];
        EXPECT_NEAR(w.sum(), 1.0, 1e-12);
        if (points.row(i).norm() < 0.7) {
            EXPECT_GE(w.minCoeff(), -1e-12) << "point " << i << " lies in its tet";
        }
    }
    EXPECT_NEAR_REL(embedded_positions(embedding, mesh.rest_positions), points, 1e-12, 0.0);
    // Points on a slightly larger sphere, partly outside the faceted mesh: still reproduced.
    Positions outside = random_points(50, -1.0, 1.0, 4);
    for (Index i = 0; i < outside.rows(); ++i)
        outside.row(i) *= 1.01 / outside.row(i).norm();
    EXPECT_NEAR_REL(embedded_positions(embed_points(mesh, outside), mesh.rest_positions), outside, 1e-12, 0.0);
}

TEST(EmbedPoints, EmbeddedSurfaceFollowsARigidMotionExactly)
{
    const TetMesh mesh = make_box(Vec3::Zero(), Vec3(2, 1, 1), {4, 2, 2});
    const Positions points = random_points(100, 0.05, 0.95, 5);
    const Embedding embedding = embed_points(mesh, points);
    const Mat3 r = Eigen::AngleAxisd(1.1, Vec3(1, -2, 0.5).normalized()).toRotationMatrix();
    const Vec3 t(3.0, -1.0, 2.0);
    Positions moved = mesh.rest_positions;
    for (Index v = 0; v < moved.rows(); ++v)
        moved.row(v) = (r * mesh.rest_positions.row(v).transpose() + t).transpose();
    const Positions followed = embedded_positions(embedding, moved);
    for (Index i = 0; i < points.rows(); ++i)
        ASSERT_NEAR_REL(followed.row(i).transpose(), Vec3(r * points.row(i).transpose() + t), 1e-12, 0.0) << i;
}
