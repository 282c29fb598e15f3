#pragma once
// The inner loops of the upper-storage product (see BsrMatrix): one chunk's rows, and the
// gather of mirrored blocks into one row, for values stored as double or as float (converted
// to double as they are loaded; vectors and sums are double either way).
//
// Two implementations: `scalar`, always built, and `avx2` with AVX2 and FMA, where a 3×3 block
// is three 4-wide rows (the fourth lane is never stored). The product uses avx2 when it is
// built; tests/solver/test_upper_block_kernels.cpp compares the two. Either way a row's sums run
// in a fixed order, so results do not depend on the thread count.

#include <corocontact/core/types.hpp>

#include <array>
#include <cstddef>

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#define CORO_UPPER_BLOCK_AVX2 1
#endif

namespace coro::detail {

namespace scalar {

template <class Value>
inline void upper_chunk_rows(const Value* values, const Index* columns, const Index* offsets, const double* x,
                             double* y, Index begin, Index end)
{
    for (Index r = begin; r != end; ++r) {
        const double* xr = x + 3 * static_cast<std::ptrdiff_t>(r);
        double y0 = 0.0, y1 = 0.0, y2 = 0.0;
        for (Index k = offsets[r]; k < offsets[r + 1]; ++k) {
            const Value* v = values + 9 * static_cast<std::ptrdiff_t>(k);
            const double a[9] = {double(v[0]), double(v[1]), double(v[2]), double(v[3]), double(v[4]),
                                 double(v[5]), double(v[6]), double(v[7]), double(v[8])};
            const Index c = columns[k];
            const double* xc = x + 3 * static_cast<std::ptrdiff_t>(c);
            y0 += a[0] * xc[0] + a[1] * xc[1] + a[2] * xc[2];
            y1 += a[3] * xc[0] + a[4] * xc[1] + a[5] * xc[2];
            y2 += a[6] * xc[0] + a[7] * xc[1] + a[8] * xc[2];
            if (c != r && c < end) { // the mirrored block A_rcᵀ x_r, row c in this chunk
                double* yc = y + 3 * static_cast<std::ptrdiff_t>(c);
                yc[0] += a[0] * xr[0] + a[3] * xr[1] + a[6] * xr[2];
                yc[1] += a[1] * xr[0] + a[4] * xr[1] + a[7] * xr[2];
                yc[2] += a[2] * xr[0] + a[5] * xr[1] + a[8] * xr[2];
            }
        }
        double* yr = y + 3 * static_cast<std::ptrdiff_t>(r);
        yr[0] += y0;
        yr[1] += y1;
        yr[2] += y2;
    }
}

template <class Value>
inline void gather_row(const Value* values, const std::array<Index, 2>* blocks, Index first, Index last,
                       const double* x, double* y_row)
{
    double y0 = y_row[0], y1 = y_row[1], y2 = y_row[2];
    for (Index e = first; e < last; ++e) {
        const Value* a = values + 9 * static_cast<std::ptrdiff_t>(blocks[e][0]);
        const double* xs = x + 3 * static_cast<std::ptrdiff_t>(blocks[e][1]);
        y0 += double(a[0]) * xs[0] + double(a[3]) * xs[1] + double(a[6]) * xs[2];
        y1 += double(a[1]) * xs[0] + double(a[4]) * xs[1] + double(a[7]) * xs[2];
        y2 += double(a[2]) * xs[0] + double(a[5]) * xs[1] + double(a[8]) * xs[2];
    }
    y_row[0] = y0;
    y_row[1] = y1;
    y_row[2] = y2;
}

} // namespace scalar

#if defined(CORO_UPPER_BLOCK_AVX2)

namespace avx2 {

// Lanes 0..2 from p[0..2], lane 3 zero; reads nothing beyond p[2].
inline __m256d load3(const double* p)
{
    return _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(p)), _mm_load_sd(p + 2), 1);
}

// Writes lanes 0..2 to p[0..2].
inline void store3(double* p, __m256d v)
{
    _mm_storeu_pd(p, _mm256_castpd256_pd128(v));
    _mm_store_sd(p + 2, _mm256_extractf128_pd(v, 1));
}

// The rows of a row-major 3×3 block in lanes 0..2 (lane 3: whatever follows; never stored).
// Every load stays inside the block's 9 values.
struct BlockRows {
    __m256d r0, r1, r2;
    explicit BlockRows(const double* a)
        : r0(_mm256_loadu_pd(a)), r1(_mm256_loadu_pd(a + 3)),
          r2(_mm256_permute4x64_pd(_mm256_loadu_pd(a + 5), _MM_SHUFFLE(3, 3, 2, 1)))
    {
    }
    explicit BlockRows(const float* a)
        : r0(_mm256_cvtps_pd(_mm_loadu_ps(a))), r1(_mm256_cvtps_pd(_mm_loadu_ps(a + 3))),
          r2(_mm256_permute4x64_pd(_mm256_cvtps_pd(_mm_loadu_ps(a + 5)), _MM_SHUFFLE(3, 3, 2, 1)))
    {
    }
    // Aᵀ x = Σ_i row_i x_i, added to acc.
    __m256d transposed_times(__m256d x0, __m256d x1, __m256d x2, __m256d acc) const
    {
        return _mm256_fmadd_pd(r2, x2, _mm256_fmadd_pd(r1, x1, _mm256_fmadd_pd(r0, x0, acc)));
    }
};

inline double sum3(__m256d v)
{
    alignas(32) double lanes[4];
    _mm256_store_pd(lanes, v);
    return (lanes[0] + lanes[1]) + lanes[2];
}

template <class Value>
inline void upper_chunk_rows(const Value* values, const Index* columns, const Index* offsets, const double* x,
                             double* y, Index begin, Index end)
{
    for (Index r = begin; r != end; ++r) {
        const double* xr = x + 3 * static_cast<std::ptrdiff_t>(r);
        const __m256d xr0 = _mm256_broadcast_sd(xr), xr1 = _mm256_broadcast_sd(xr + 1),
                      xr2 = _mm256_broadcast_sd(xr + 2);
        // Row i of A x accumulates lane-wise (row_i ⊙ x_c), summed across lanes at the end.
        __m256d acc0 = _mm256_setzero_pd(), acc1 = _mm256_setzero_pd(), acc2 = _mm256_setzero_pd();
        for (Index k = offsets[r]; k < offsets[r + 1]; ++k) {
            const BlockRows a(values + 9 * static_cast<std::ptrdiff_t>(k));
            const Index c = columns[k];
            const __m256d xc = load3(x + 3 * static_cast<std::ptrdiff_t>(c));
            acc0 = _mm256_fmadd_pd(a.r0, xc, acc0);
            acc1 = _mm256_fmadd_pd(a.r1, xc, acc1);
            acc2 = _mm256_fmadd_pd(a.r2, xc, acc2);
            if (c != r && c < end) { // the mirrored block A_rcᵀ x_r, row c in this chunk
                double* yc = y + 3 * static_cast<std::ptrdiff_t>(c);
                store3(yc, a.transposed_times(xr0, xr1, xr2, load3(yc)));
            }
        }
        double* yr = y + 3 * static_cast<std::ptrdiff_t>(r);
        yr[0] += sum3(acc0);
        yr[1] += sum3(acc1);
        yr[2] += sum3(acc2);
    }
}

template <class Value>
inline void gather_row(const Value* values, const std::array<Index, 2>* blocks, Index first, Index last,
                       const double* x, double* y_row)
{
    __m256d acc = load3(y_row);
    for (Index e = first; e < last; ++e) {
        const BlockRows a(values + 9 * static_cast<std::ptrdiff_t>(blocks[e][0]));
        const double* xs = x + 3 * static_cast<std::ptrdiff_t>(blocks[e][1]);
        acc = a.transposed_times(_mm256_broadcast_sd(xs), _mm256_broadcast_sd(xs + 1), _mm256_broadcast_sd(xs + 2),
                                 acc);
    }
    store3(y_row, acc);
}

} // namespace avx2

using avx2::gather_row;
using avx2::upper_chunk_rows;

#else

using scalar::gather_row;
using scalar::upper_chunk_rows;

#endif

} // namespace coro::detail
