#pragma once
/// @file near.hpp
/// @brief One tolerance helper for the whole suite: |a − b| ≤ abs + rel·max(|a|, |b|),
/// reporting the first failing entry (i, j).

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace coro::test {

/// Entry-wise comparison of two equally shaped Eigen objects.
template <class A, class B>
::testing::AssertionResult is_near(const Eigen::MatrixBase<A>& a, const Eigen::MatrixBase<B>& b,
                                   double abs_tol, double rel_tol)
{
    if (a.rows() != b.rows() || a.cols() != b.cols())
        return ::testing::AssertionFailure() << "shapes differ: " << a.rows() << "x" << a.cols()
                                             << " vs " << b.rows() << "x" << b.cols();
    for (Eigen::Index j = 0; j < a.cols(); ++j)
        for (Eigen::Index i = 0; i < a.rows(); ++i) {
            const double x = static_cast<double>(a(i, j)), y = static_cast<double>(b(i, j));
            const double tol = abs_tol + rel_tol * std::max(std::abs(x), std::abs(y));
            if (!(std::abs(x - y) <= tol))
                return ::testing::AssertionFailure()
                       << "entry (" << i << ", " << j << "): " << x << " vs " << y << ", |diff| "
                       << std::abs(x - y) << " > tol " << tol;
        }
    return ::testing::AssertionSuccess();
}

/// Scalar version.
inline ::testing::AssertionResult is_near(double x, double y, double abs_tol, double rel_tol)
{
    const double tol = abs_tol + rel_tol * std::max(std::abs(x), std::abs(y));
    if (std::abs(x - y) <= tol)
        return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << x << " vs " << y << ", |diff| " << std::abs(x - y)
                                         << " > tol " << tol;
}

} // namespace coro::test

#define EXPECT_NEAR_REL(a, b, abs_tol, rel_tol) EXPECT_TRUE(::coro::test::is_near((a), (b), (abs_tol), (rel_tol)))
#define ASSERT_NEAR_REL(a, b, abs_tol, rel_tol) ASSERT_TRUE(::coro::test::is_near((a), (b), (abs_tol), (rel_tol)))
