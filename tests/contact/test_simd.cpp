// The native SIMD lanes of the contact walks against their scalar reference, operation by
// operation, bit for bit, on values that include zeros of both signs, infinities, NaN and
// values beyond the float range.
#include "detail/simd.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

using namespace coro::detail::simd;

namespace {

template <class T>
std::vector<T> special_values(std::mt19937& rng, int count)
{
    const T inf = std::numeric_limits<T>::infinity();
    std::vector<T> v{T(0), -T(0), T(1), T(-1), inf, -inf, std::numeric_limits<T>::quiet_NaN(),
                     std::numeric_limits<T>::max(), std::numeric_limits<T>::lowest(), std::numeric_limits<T>::min(),
                     std::numeric_limits<T>::denorm_min()};
    std::uniform_real_distribution<T> uniform(T(-4), T(4));
    while (static_cast<int>(v.size()) < count)
        v.push_back(uniform(rng));
    std::shuffle(v.begin(), v.end(), rng);
    return v;
}

template <class T>
bool same_bits(T a, T b)
{
    return std::memcmp(&a, &b, sizeof(T)) == 0;
}

/// Every binary operation and comparison of Native against Scalar on `trials` random pairs of
/// lanes drawn from special and ordinary values.
template <class Native, class Scalar, class T>
void expect_lanes_match(int trials)
{
    constexpr int N = Scalar::LANES;
    static_assert(Native::LANES == N);
    std::mt19937 rng(21);
    const std::vector<T> pool = special_values<T>(rng, 64);
    std::uniform_int_distribution<std::size_t> pick(0, pool.size() - 1);
    for (int trial = 0; trial < trials; ++trial) {
        T a[N], b[N];
        for (int k = 0; k < N; ++k) {
            a[k] = pool[pick(rng)];
            b[k] = pool[pick(rng)];
        }
        const Native na = Native::load(a), nb = Native::load(b);
        const Scalar sa = Scalar::load(a), sb = Scalar::load(b);
        const auto check = [&](const Native& n, const Scalar& s, const char* op) {
            T got[N], want[N];
            n.store(got);
            s.store(want);
            for (int k = 0; k < N; ++k)
                ASSERT_TRUE(same_bits(got[k], want[k]))
                    << op << " lane " << k << ": " << a[k] << ", " << b[k] << " gives " << got[k] << ", want " << want[k];
        };
        check(na + nb, sa + sb, "+");
        check(na - nb, sa - sb, "-");
        check(na * nb, sa * sb, "*");
        check(min(na, nb), min(sa, sb), "min");
        check(max(na, nb), max(sa, sb), "max");
        check(abs(na), abs(sa), "abs");
        check(Native::splat(a[0]), Scalar::splat(a[0]), "splat");
        ASSERT_EQ((na <= nb).bits(), (sa <= sb).bits()) << "<=";
        ASSERT_EQ((na >= nb).bits(), (sa >= sb).bits()) << ">=";
        ASSERT_EQ((na < nb).bits(), (sa < sb).bits()) << "<";
        ASSERT_EQ((na > nb).bits(), (sa > sb).bits()) << ">";
        ASSERT_EQ(((na <= nb) & (na >= nb)).bits(), ((sa <= sb) & (sa >= sb)).bits()) << "&";
        ASSERT_EQ(((na < nb) | (na > nb)).bits(), ((sa < sb) | (sa > sb)).bits()) << "|";
    }
}

} // namespace

TEST(SimdLanes, FourFloatsMatchTheScalarLanes) { expect_lanes_match<F4, F4Scalar, float>(2000); }

TEST(SimdLanes, EightFloatsMatchTheScalarLanes) { expect_lanes_match<F8, F8Scalar, float>(2000); }

TEST(SimdLanes, FourDoublesMatchTheScalarLanes) { expect_lanes_match<D4, D4Scalar, double>(2000); }

TEST(SimdLanes, PointLoadConversionAndTransposeMatchTheScalarOnes)
{
    std::mt19937 rng(5);
    const std::vector<double> pool = special_values<double>(rng, 40);
    std::uniform_int_distribution<std::size_t> pick(0, pool.size() - 1);
    for (int trial = 0; trial < 500; ++trial) {
        const double p[3] = {pool[pick(rng)], pool[pick(rng)], pool[pick(rng)]};
        double got[4], want[4];
        load_point(p).store(got);
        load_point_scalar(p).store(want);
        for (int k = 0; k < 4; ++k)
            ASSERT_TRUE(same_bits(got[k], want[k])) << "lane " << k;
        float fgot[4], fwant[4];
        to_float(load_point(p)).store(fgot);
        to_float_scalar(load_point_scalar(p)).store(fwant);
        for (int k = 0; k < 4; ++k)
            ASSERT_TRUE(same_bits(fgot[k], fwant[k])) << "lane " << k;
    }
    float rows[4][4];
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            rows[i][j] = static_cast<float>(10 * i + j);
    F4 r[4] = {F4::load(rows[0]), F4::load(rows[1]), F4::load(rows[2]), F4::load(rows[3])};
    F4Scalar s[4] = {F4Scalar::load(rows[0]), F4Scalar::load(rows[1]), F4Scalar::load(rows[2]), F4Scalar::load(rows[3])};
    transpose(r[0], r[1], r[2], r[3]);
    transpose_scalar(s[0], s[1], s[2], s[3]);
    for (int i = 0; i < 4; ++i) {
        float got[4], want[4];
        r[i].store(got);
        s[i].store(want);
        for (int j = 0; j < 4; ++j) {
            EXPECT_EQ(got[j], want[j]) << i << ", " << j;
            EXPECT_EQ(got[j], rows[j][i]) << i << ", " << j;
        }
    }
}

TEST(SimdLanes, BoxPairsMatchThePortableKernel)
{
    // Random float boxes, some empty (as unused lanes are) or reaching beyond the region.
    std::mt19937 rng(8);
    std::uniform_real_distribution<float> coordinate(-2.0f, 2.0f);
    for (int trial = 0; trial < 3000; ++trial) {
        float a_lo[3][4], a_hi[3][4], b_lo[3][4], b_hi[3][4];
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 4; ++k) {
                const float x = coordinate(rng), y = coordinate(rng);
                a_lo[j][k] = std::min(x, y) * 0.5f;
                a_hi[j][k] = std::max(x, y) * 0.5f;
                const float u = coordinate(rng), v = coordinate(rng);
                b_lo[j][k] = std::min(u, v) * 0.5f;
                b_hi[j][k] = std::max(u, v) * 0.5f;
            }
        if (trial % 7 == 0)
            for (int j = 0; j < 3; ++j) {
                a_lo[j][3] = std::numeric_limits<float>::infinity();
                a_hi[j][3] = -std::numeric_limits<float>::infinity();
            }
        F4 r_lo[3], r_hi[3];
        for (int j = 0; j < 3; ++j) {
            const float x = coordinate(rng), y = coordinate(rng);
            r_lo[j] = F4::splat(std::min(x, y));
            r_hi[j] = F4::splat(std::max(x, y));
        }
        const Boxes4 a{a_lo, a_hi}, b{b_lo, b_hi};
        const int got = box_pairs_meeting(a, b, r_lo, r_hi);
        ASSERT_EQ(got, box_pairs_meeting_portable(a, b, r_lo, r_hi)) << "trial " << trial;
        // And the definition, pair by pair.
        for (int i = 0; i < 4; ++i)
            for (int k = 0; k < 4; ++k) {
                bool meet = true;
                for (int j = 0; j < 3; ++j) {
                    const float lo = std::max({a_lo[j][i], b_lo[j][k], r_lo[j].lane(0)});
                    const float hi = std::min({a_hi[j][i], b_hi[j][k], r_hi[j].lane(0)});
                    meet = meet && lo <= hi;
                }
                ASSERT_EQ(((got >> (4 * i + k)) & 1) != 0, meet) << "trial " << trial << " pair " << i << ", " << k;
            }
    }
}
