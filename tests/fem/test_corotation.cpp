#include "near.hpp"

#include <corocontact/core/error.hpp>
#include <corocontact/fem/corotation.hpp>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <random>

using namespace coro;

namespace {
Mat3 random_rotation(std::mt19937& rng)
{
    std::normal_distribution<double> n;
    return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}
Mat3 random_spd(std::mt19937& rng, double spread)
{
    std::uniform_real_distribution<double> u(-spread, spread);
    Mat3 a;
    for (int i = 0; i < 9; ++i)
        a(i) = u(rng);
    return Mat3::Identity() + 0.5 * (a + a.transpose());
}
} // namespace

TEST(PolarRotation, RecoversRotationOfStretchedRotation)
{
    std::mt19937 rng(11);
    for (int trial = 0; trial < 200; ++trial) {
        const Mat3 r = random_rotation(rng);
        const Mat3 s = random_spd(rng, 0.4);
        const Mat3 f = r * s;
        EXPECT_NEAR_REL(polar_rotation_svd(f), r, 1e-10, 0.0);
        // Warm start from a rotation 20 degrees away, and from the identity.
        const Mat3 nearby = Eigen::AngleAxisd(0.35, Vec3(1, 2, 3).normalized()).toRotationMatrix() * r;
        EXPECT_NEAR_REL(polar_rotation(f, nearby), r, 1e-10, 0.0) << "trial " << trial;
        EXPECT_NEAR_REL(polar_rotation(f, Mat3::Identity()), r, 1e-10, 0.0) << "trial " << trial;
    }
}

TEST(PolarRotation, ProperRotationForInvertedElements)
{
    std::mt19937 rng(5);
    for (int trial = 0; trial < 100; ++trial) {
        const Mat3 r = random_rotation(rng);
        Mat3 s = random_spd(rng, 0.2);
        s.col(2) *= -1.0; // reflect: det F < 0
        const Mat3 f = r * s;
        ASSERT_LT(f.determinant(), 0.0);
        const Mat3 svd = polar_rotation_svd(f);
        EXPECT_NEAR(svd.determinant(), 1.0, 1e-12);
        EXPECT_NEAR_REL(svd * svd.transpose(), Mat3::Identity(), 1e-12, 0.0);
        // It maximises tr(RᵀF) over rotations: no small rotation improves it.
        for (int axis = 0; axis < 3; ++axis)
            for (const double angle : {1e-3, -1e-3}) {
                const Mat3 perturbed = Eigen::AngleAxisd(angle, Vec3::Unit(axis)).toRotationMatrix() * svd;
                EXPECT_LE((perturbed.transpose() * f).trace(), (svd.transpose() * f).trace() + 1e-12);
            }
        const Mat3 iterative = polar_rotation(f, svd);
        EXPECT_NEAR_REL(iterative, svd, 1e-9, 0.0);
        EXPECT_NEAR(iterative.determinant(), 1.0, 1e-12);
    }
}

TEST(PolarRotation, RejectsNonFinite)
{
    Mat3 f = Mat3::Identity();
    f(1, 2) = std::numeric_limits<double>::infinity();
    EXPECT_THROW(polar_rotation(f, Mat3::Identity()), NumericalError);
}
