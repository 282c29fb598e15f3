#pragma once
// Dot products over one chunk of a vector, summed in an order fixed by the chunk alone.
//
// One running sum is a chain of dependent additions: the loop runs at one element per add
// latency (4 cycles), far below what the caches deliver, and a PCG iteration has two such dots.
// Here element i goes to running sum i mod DOT_LANES, each kept in element order, and the
// DOT_LANES sums are then added pairwise. The compiler keeps the sums in vector registers (the
// lanes are independent, so no reassociation is needed); scalar, SSE, AVX2 and AVX-512 builds
// add the same numbers in the same order. A chunk's result depends on its own elements only,
// never on the thread count.

#include <cstddef>
#include <cstring>

namespace coro::detail {

inline constexpr int DOT_LANES = 16;

/// t[0] + … + t[DOT_LANES − 1], added pairwise: ((t0 + t1) + (t2 + t3)) + … (t is overwritten).
inline double sum_lanes(double (&t)[DOT_LANES])
{
    for (int width = DOT_LANES / 2; width > 0; width /= 2)
        for (int k = 0; k < width; ++k)
            t[k] = t[2 * k] + t[2 * k + 1];
    return t[0];
}

/// Four lanes in one value; the compiler maps it to one AVX register, or two SSE2 ones. (Not in
/// a function signature: that would tie the calling convention to the instruction set.)
using Lanes4 = double __attribute__((vector_size(32)));

/// The DOT_LANES running sums, as four Lanes4 (sums 0–3, 4–7, 8–11, 12–15).
struct LaneSums {
    Lanes4 part[DOT_LANES / 4] = {};

    /// Adds x[k]·y[k] to sum k for k < DOT_LANES.
    void add_products(const double* x, const double* y)
    {
        for (int j = 0; j < DOT_LANES / 4; ++j) {
            Lanes4 a, b;
            std::memcpy(&a, x + 4 * j, sizeof a);
            std::memcpy(&b, y + 4 * j, sizeof b);
            part[j] += a * b;
        }
    }
    /// Adds x[k]·y[k] to sum k for k < count < DOT_LANES.
    void add_tail(const double* x, const double* y, int count)
    {
        for (int k = 0; k < count; ++k)
            part[k / 4][k % 4] += x[k] * y[k];
    }
    double total() const
    {
        double s[DOT_LANES];
        for (int k = 0; k < DOT_LANES; ++k)
            s[k] = part[k / 4][k % 4];
        return sum_lanes(s);
    }
};

/// Σ x[i]·y[i] for i in [0, n).
inline double lane_dot(const double* x, const double* y, std::ptrdiff_t n)
{
    LaneSums s;
    std::ptrdiff_t i = 0;
    for (; i + DOT_LANES <= n; i += DOT_LANES)
        s.add_products(x + i, y + i);
    s.add_tail(x + i, y + i, static_cast<int>(n - i));
    return s.total();
}

/// Σ r[i]² and Σ r[i]·z[i] for i in [0, n), in one pass.
inline void lane_dots(const double* r, const double* z, std::ptrdiff_t n, double& rr, double& rz)
{
    LaneSums s, t;
    std::ptrdiff_t i = 0;
    for (; i + DOT_LANES <= n; i += DOT_LANES) {
        s.add_products(r + i, r + i);
        t.add_products(r + i, z + i);
    }
    s.add_tail(r + i, r + i, static_cast<int>(n - i));
    t.add_tail(r + i, z + i, static_cast<int>(n - i));
    rr = s.total();
    rz = t.total();
}

} // namespace coro::detail
