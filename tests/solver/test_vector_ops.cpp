#include <corocontact/core/error.hpp>
#include <corocontact/solver/vector_ops.hpp>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <limits>
#include <random>

using namespace coro;

TEST(Dot, BitwiseIdenticalForAnyThreadCountAndCloseToSerial)
{
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    VecX a(100003), b(100003);
    for (Eigen::Index i = 0; i < a.size(); ++i) {
        a[i] = u(rng);
        b[i] = u(rng) * 1e3;
    }
    double one = 0, two = 0;
    tbb::task_arena(1).execute([&] { one = dot(a, b); });
    tbb::task_arena(2).execute([&] { two = dot(a, b); });
    EXPECT_EQ(one, two);
    long double serial = 0;
    for (Eigen::Index i = 0; i < a.size(); ++i)
        serial += static_cast<long double>(a[i]) * b[i];
    EXPECT_NEAR(one, static_cast<double>(serial), 1e-9 * std::abs(one) + 1e-9);
}

TEST(Dot, ThrowsOnNonFinite)
{
    VecX a = VecX::Ones(10);
    a[3] = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(dot(a, a), NumericalError);
}

TEST(Axpy, MatchesEigen)
{
    VecX x = VecX::LinSpaced(20000, 0, 1), y = VecX::Constant(20000, 2.0);
    const VecX expected = y + 0.5 * x;
    axpy(0.5, x, y);
    EXPECT_TRUE(y.isApprox(expected, 1e-15));
    const VecX expected2 = x + 3.0 * y;
    xpby(x, 3.0, y);
    EXPECT_TRUE(y.isApprox(expected2, 1e-15));
}
