#include "near.hpp"

#include <corocontact/fem/tet_element.hpp>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <random>

using namespace coro;

namespace {
TetRest random_tet_rest(unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (;;) {
        Vec3 x[4];
        for (auto& p : x)
            p = Vec3(u(rng), u(rng), u(rng));
        Mat3 dm;
        dm << x[1] - x[0], x[2] - x[0], x[3] - x[0];
        if (dm.determinant() > 0.05)
            return make_tet_rest(x[0], x[1], x[2], x[3]);
    }
}
} // namespace

TEST(ShapeGradients, ReproduceLinearFieldsExactly)
{
    // Σ_i φ(X_i) g_i = ∇φ for a linear φ; with φ = a·X that is a.
    const Vec3 x0(0.1, 0.2, 0.3), x1(1.2, 0.1, 0.0), x2(0.2, 1.1, 0.4), x3(0.3, 0.2, 0.9);
    const TetRest rest = make_tet_rest(x0, x1, x2, x3);
    const Mat34 g = shape_gradients(rest);
    const Vec3 a(0.7, -1.3, 2.1);
    const Vec3 gradient = a.dot(x0) * g.col(0) + a.dot(x1) * g.col(1) + a.dot(x2) * g.col(2) + a.dot(x3) * g.col(3);
    EXPECT_NEAR_REL(gradient, a, 1e-13, 1e-13);
    EXPECT_NEAR_REL(g.rowwise().sum(), Vec3::Zero(), 1e-13, 0.0);
}

TEST(ElementStiffness, FreeElementHasExactlySixZeroModes)
{
    for (unsigned seed = 1; seed <= 5; ++seed) {
        const Mat12 k = element_stiffness(random_tet_rest(seed), 2.0, 1.5);
        EXPECT_NEAR_REL(k, k.transpose(), 1e-12, 1e-12);
        const Eigen::SelfAdjointEigenSolver<Mat12> eigen(k);
        const auto& values = eigen.eigenvalues();
        const double largest = values.maxCoeff();
        int zero = 0;
        for (int i = 0; i < 12; ++i) {
            EXPECT_GT(values[i], -1e-12 * largest);
            zero += values[i] < 1e-10 * largest ? 1 : 0;
        }
        EXPECT_EQ(zero, 6) << "seed " << seed << ", eigenvalues " << values.transpose();
        EXPECT_GT(values[6], 1e-4 * largest) << "seed " << seed; // the seventh is clearly not zero
    }
}

TEST(ElementStiffness, MatchesClassicalBTDBForm)
{
    // Independent construction: K = V Bᵀ D B with the 6×12 strain-displacement matrix B
    // (engineering shear strains) and the isotropic 6×6 elasticity matrix D.
    const double lambda = 3.0, mu = 1.25;
    const TetRest rest = random_tet_rest(7);
    const Mat34 g = shape_gradients(rest);
    Eigen::Matrix<double, 6, 12> b = Eigen::Matrix<double, 6, 12>::Zero();
    for (int i = 0; i < 4; ++i) {
        const double gx = g(0, i), gy = g(1, i), gz = g(2, i);
        b(0, 3 * i) = gx;
        b(1, 3 * i + 1) = gy;
        b(2, 3 * i + 2) = gz;
        b(3, 3 * i) = gy, b(3, 3 * i + 1) = gx;
        b(4, 3 * i + 1) = gz, b(4, 3 * i + 2) = gy;
        b(5, 3 * i) = gz, b(5, 3 * i + 2) = gx;
    }
    Eigen::Matrix<double, 6, 6> d = Eigen::Matrix<double, 6, 6>::Zero();
    d.topLeftCorner<3, 3>().setConstant(lambda);
    d.topLeftCorner<3, 3>().diagonal().array() += 2 * mu;
    d.bottomRightCorner<3, 3>().diagonal().setConstant(mu);
    const Mat12 reference = rest.volume * b.transpose() * d * b;
    EXPECT_NEAR_REL(element_stiffness(rest, lambda, mu), reference, 1e-12, 1e-12);
}

TEST(VonMises, UniaxialAndPureShear)
{
    Mat3 s = Mat3::Zero();
    s(0, 0) = 5.0;
    EXPECT_NEAR(von_mises(s), 5.0, 1e-14);
    s.setZero();
    s(0, 1) = s(1, 0) = 2.0;
    EXPECT_NEAR(von_mises(s), 2.0 * std::sqrt(3.0), 1e-14);
    EXPECT_NEAR(von_mises(Mat3::Identity() * 7.0), 0.0, 1e-14); // hydrostatic
}
