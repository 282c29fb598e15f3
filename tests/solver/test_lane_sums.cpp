// The fixed-order dot products of the PCG chunks (src/solver/detail/lane_sums.hpp): the order
// they promise, element i in running sum i mod 16, then the sums pairwise, checked bit for bit
// against a plain scalar loop in that order; the same bits wherever the data lies in memory.
#include "detail/lane_sums.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace coro;

namespace {

// Values of at most 20 significant bits over a wide range of magnitudes: every product is
// exact in double (so an FMA and a multiply-then-add round alike), and sums depend on their
// order.
std::vector<double> wide_values(std::size_t n, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> mantissa(-(1 << 20), 1 << 20), exponent(-30, 30);
    std::vector<double> v(n);
    for (double& x : v)
        x = std::ldexp(static_cast<double>(mantissa(rng)), exponent(rng));
    return v;
}

double scalar_in_lane_order(const double* x, const double* y, std::size_t n)
{
    double s[detail::DOT_LANES] = {};
    for (std::size_t i = 0; i < n; ++i)
        s[i % detail::DOT_LANES] += x[i] * y[i];
    double pairs[detail::DOT_LANES];
    for (int k = 0; k < detail::DOT_LANES; ++k)
        pairs[k] = s[k];
    for (int width = detail::DOT_LANES / 2; width > 0; width /= 2)
        for (int k = 0; k < width; ++k)
            pairs[k] = pairs[2 * k] + pairs[2 * k + 1];
    return pairs[0];
}

double sequential(const double* x, const double* y, std::size_t n)
{
    double s = 0.0;
    for (std::size_t i = 0; i < n; ++i)
        s += x[i] * y[i];
    return s;
}

} // namespace

TEST(LaneSums, DotIsTheScalarSumInLaneOrderBitForBit)
{
    const std::vector<double> x = wide_values(200, 1), y = wide_values(200, 2);
    int order_matters = 0; // the data must tell the lane order from a plain running sum
    for (std::size_t n = 0; n <= x.size(); ++n) {
        const double expected = scalar_in_lane_order(x.data(), y.data(), n);
        EXPECT_EQ(detail::lane_dot(x.data(), y.data(), static_cast<std::ptrdiff_t>(n)), expected) << "n = " << n;
        order_matters += sequential(x.data(), y.data(), n) != expected ? 1 : 0;
    }
    EXPECT_GT(order_matters, 100);
}

TEST(LaneSums, TwoDotsInOnePassEqualTwoSeparateDots)
{
    const std::vector<double> r = wide_values(131, 3), z = wide_values(131, 4);
    for (std::size_t n = 0; n <= r.size(); ++n) {
        double rr = -1.0, rz = -1.0;
        detail::lane_dots(r.data(), z.data(), static_cast<std::ptrdiff_t>(n), rr, rz);
        EXPECT_EQ(rr, scalar_in_lane_order(r.data(), r.data(), n)) << "n = " << n;
        EXPECT_EQ(rz, scalar_in_lane_order(r.data(), z.data(), n)) << "n = " << n;
    }
}

TEST(LaneSums, SameBitsAtAnyAddress)
{
    const std::vector<double> x = wide_values(97, 5), y = wide_values(97, 6);
    const double at_start = detail::lane_dot(x.data(), y.data(), 97);
    for (std::size_t shift = 1; shift < 8; ++shift) {
        std::vector<double> xs(shift, 0.0), ys(shift, 0.0);
        xs.insert(xs.end(), x.begin(), x.end());
        ys.insert(ys.end(), y.begin(), y.end());
        EXPECT_EQ(detail::lane_dot(xs.data() + shift, ys.data() + shift, 97), at_start) << "shift " << shift;
    }
}

TEST(LaneSums, DotIsAccurate)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<double> x(10007), y(10007);
    long double exact = 0.0L, magnitude = 0.0L;
    for (std::size_t i = 0; i < x.size(); ++i) {
        x[i] = u(rng);
        y[i] = u(rng);
        exact += static_cast<long double>(x[i]) * y[i];
        magnitude += std::abs(static_cast<long double>(x[i]) * y[i]);
    }
    const double dot = detail::lane_dot(x.data(), y.data(), static_cast<std::ptrdiff_t>(x.size()));
    EXPECT_LE(std::abs(dot - static_cast<double>(exact)), 1e-13 * static_cast<double>(magnitude));
}
