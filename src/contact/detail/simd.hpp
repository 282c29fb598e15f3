#pragma once
/// @file simd.hpp
/// @brief The SIMD lanes of the contact library's tree walks: 4 floats, 8 floats and 4 doubles,
/// held in SSE/AVX2 registers where the build has them and in plain arrays otherwise.
///
/// Apart from the segment–triangle kernel (segment_triangle.hpp, with its own scalar
/// fallback), every intrinsic of the contact library is in this file. Both implementations of
/// a type give the same result lane by lane:
///  - min(a, b) = a < b ? a : b and max(a, b) = a > b ? a : b: the second operand when either
///    is NaN, as the SSE/AVX min and max instructions;
///  - comparisons are ordered (false when either operand is NaN) and give a Mask, whose bits()
///    hold lane k in bit k;
///  - each operation rounds once (the functions are single operations: nothing to fuse).
/// The scalar types exist in every build, so that a test compares them with the native ones.
/// F4 is native on every x86-64 build (SSE2 is part of the baseline); F8 and D4 are native
/// with AVX2 and FMA (CORO_CONTACT_AVX2), else F8 is two F4 and D4 the scalar type.

#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__AVX2__) && defined(__FMA__)
#define CORO_CONTACT_AVX2 1
#include <immintrin.h>
#else
#define CORO_CONTACT_AVX2 0
#endif

namespace coro::detail::simd {

/// Lane bits of a comparison, combined with & and |.
struct BitMask {
    int lanes;
    int bits() const { return lanes; }
    friend BitMask operator&(BitMask a, BitMask b) { return {a.lanes & b.lanes}; }
    friend BitMask operator|(BitMask a, BitMask b) { return {a.lanes | b.lanes}; }
};

/// N lanes of T as a plain array: the reference semantics of every native type below.
template <class T, int N>
struct ScalarLanes {
    using Mask = BitMask;
    static constexpr int LANES = N;
    T v[N];

    static ScalarLanes load(const T* p) // p: N values (no alignment needed)
    {
        ScalarLanes r;
        for (int k = 0; k < N; ++k)
            r.v[k] = p[k];
        return r;
    }
    static ScalarLanes splat(T x)
    {
        ScalarLanes r;
        for (int k = 0; k < N; ++k)
            r.v[k] = x;
        return r;
    }
    static ScalarLanes zero() { return splat(T(0)); }
    void store(T* p) const
    {
        for (int k = 0; k < N; ++k)
            p[k] = v[k];
    }
    T lane(int k) const { return v[k]; }

    template <class F>
    static ScalarLanes map(ScalarLanes a, ScalarLanes b, F f)
    {
        ScalarLanes r;
        for (int k = 0; k < N; ++k)
            r.v[k] = f(a.v[k], b.v[k]);
        return r;
    }
    template <class F>
    static Mask test(ScalarLanes a, ScalarLanes b, F f)
    {
        int bits = 0;
        for (int k = 0; k < N; ++k)
            bits |= f(a.v[k], b.v[k]) ? 1 << k : 0;
        return {bits};
    }
    friend ScalarLanes operator+(ScalarLanes a, ScalarLanes b) { return map(a, b, [](T x, T y) { return x + y; }); }
    friend ScalarLanes operator-(ScalarLanes a, ScalarLanes b) { return map(a, b, [](T x, T y) { return x - y; }); }
    friend ScalarLanes operator*(ScalarLanes a, ScalarLanes b) { return map(a, b, [](T x, T y) { return x * y; }); }
    friend ScalarLanes min(ScalarLanes a, ScalarLanes b) { return map(a, b, [](T x, T y) { return x < y ? x : y; }); }
    friend ScalarLanes max(ScalarLanes a, ScalarLanes b) { return map(a, b, [](T x, T y) { return x > y ? x : y; }); }
    friend ScalarLanes abs(ScalarLanes a)
    {
        ScalarLanes r;
        for (int k = 0; k < N; ++k)
            r.v[k] = std::fabs(a.v[k]);
        return r;
    }
    friend Mask operator<=(ScalarLanes a, ScalarLanes b) { return test(a, b, [](T x, T y) { return x <= y; }); }
    friend Mask operator>=(ScalarLanes a, ScalarLanes b) { return test(a, b, [](T x, T y) { return x >= y; }); }
    friend Mask operator<(ScalarLanes a, ScalarLanes b) { return test(a, b, [](T x, T y) { return x < y; }); }
    friend Mask operator>(ScalarLanes a, ScalarLanes b) { return test(a, b, [](T x, T y) { return x > y; }); }
};

using F4Scalar = ScalarLanes<float, 4>;
using F8Scalar = ScalarLanes<float, 8>;
using D4Scalar = ScalarLanes<double, 4>;

/// (x, y, z, 0) from a point of 3 doubles (nothing read past them).
inline D4Scalar load_point_scalar(const double* p)
{
    const double a[4] = {p[0], p[1], p[2], 0.0};
    return D4Scalar::load(a);
}
/// Four doubles rounded to the nearest floats.
inline F4Scalar to_float_scalar(D4Scalar d)
{
    F4Scalar r;
    for (int k = 0; k < 4; ++k)
        r.v[k] = static_cast<float>(d.v[k]);
    return r;
}
/// Rows r0..r3 of a 4×4 matrix become its columns.
inline void transpose_scalar(F4Scalar& r0, F4Scalar& r1, F4Scalar& r2, F4Scalar& r3)
{
    F4Scalar* r[4] = {&r0, &r1, &r2, &r3};
    for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) {
            const float t = r[i]->v[j];
            r[i]->v[j] = r[j]->v[i];
            r[j]->v[i] = t;
        }
}

#if defined(__SSE2__)
/// Four floats in an SSE register.
struct F4Sse {
    struct Mask {
        __m128 m;
        int bits() const { return _mm_movemask_ps(m); }
        friend Mask operator&(Mask a, Mask b) { return {_mm_and_ps(a.m, b.m)}; }
        friend Mask operator|(Mask a, Mask b) { return {_mm_or_ps(a.m, b.m)}; }
    };
    static constexpr int LANES = 4;
    __m128 v;

    static F4Sse load(const float* p) { return {_mm_loadu_ps(p)}; }
    static F4Sse splat(float x) { return {_mm_set1_ps(x)}; }
    static F4Sse zero() { return {_mm_setzero_ps()}; }
    void store(float* p) const { _mm_storeu_ps(p, v); }
    float lane(int k) const
    {
        float a[4];
        _mm_storeu_ps(a, v);
        return a[k];
    }
    friend F4Sse operator+(F4Sse a, F4Sse b) { return {_mm_add_ps(a.v, b.v)}; }
    friend F4Sse operator-(F4Sse a, F4Sse b) { return {_mm_sub_ps(a.v, b.v)}; }
    friend F4Sse operator*(F4Sse a, F4Sse b) { return {_mm_mul_ps(a.v, b.v)}; }
    // minps/maxps give the second operand when either is NaN: min(a, b) = a < b ? a : b.
    friend F4Sse min(F4Sse a, F4Sse b) { return {_mm_min_ps(a.v, b.v)}; }
    friend F4Sse max(F4Sse a, F4Sse b) { return {_mm_max_ps(a.v, b.v)}; }
    friend F4Sse abs(F4Sse a) { return {_mm_andnot_ps(_mm_set1_ps(-0.0f), a.v)}; }
    friend Mask operator<=(F4Sse a, F4Sse b) { return {_mm_cmple_ps(a.v, b.v)}; }
    friend Mask operator>=(F4Sse a, F4Sse b) { return {_mm_cmpge_ps(a.v, b.v)}; }
    friend Mask operator<(F4Sse a, F4Sse b) { return {_mm_cmplt_ps(a.v, b.v)}; }
    friend Mask operator>(F4Sse a, F4Sse b) { return {_mm_cmpgt_ps(a.v, b.v)}; }
};
using F4 = F4Sse;
inline void transpose(F4& r0, F4& r1, F4& r2, F4& r3) { _MM_TRANSPOSE4_PS(r0.v, r1.v, r2.v, r3.v); }
#else
using F4 = F4Scalar;
inline void transpose(F4& r0, F4& r1, F4& r2, F4& r3) { transpose_scalar(r0, r1, r2, r3); }
#endif

#if CORO_CONTACT_AVX2
/// Eight floats in an AVX register.
struct F8Avx {
    struct Mask {
        __m256 m;
        int bits() const { return _mm256_movemask_ps(m); }
        friend Mask operator&(Mask a, Mask b) { return {_mm256_and_ps(a.m, b.m)}; }
        friend Mask operator|(Mask a, Mask b) { return {_mm256_or_ps(a.m, b.m)}; }
    };
    static constexpr int LANES = 8;
    __m256 v;

    static F8Avx load(const float* p) { return {_mm256_loadu_ps(p)}; }
    static F8Avx splat(float x) { return {_mm256_set1_ps(x)}; }
    static F8Avx zero() { return {_mm256_setzero_ps()}; }
    void store(float* p) const { _mm256_storeu_ps(p, v); }
    friend F8Avx operator+(F8Avx a, F8Avx b) { return {_mm256_add_ps(a.v, b.v)}; }
    friend F8Avx operator-(F8Avx a, F8Avx b) { return {_mm256_sub_ps(a.v, b.v)}; }
    friend F8Avx operator*(F8Avx a, F8Avx b) { return {_mm256_mul_ps(a.v, b.v)}; }
    friend F8Avx min(F8Avx a, F8Avx b) { return {_mm256_min_ps(a.v, b.v)}; }
    friend F8Avx max(F8Avx a, F8Avx b) { return {_mm256_max_ps(a.v, b.v)}; }
    friend F8Avx abs(F8Avx a) { return {_mm256_andnot_ps(_mm256_set1_ps(-0.0f), a.v)}; }
    friend Mask operator<=(F8Avx a, F8Avx b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_LE_OQ)}; }
    friend Mask operator>=(F8Avx a, F8Avx b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_GE_OQ)}; }
    friend Mask operator<(F8Avx a, F8Avx b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_LT_OQ)}; }
    friend Mask operator>(F8Avx a, F8Avx b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_GT_OQ)}; }
};
using F8 = F8Avx;

/// Four doubles in an AVX register.
struct D4Avx {
    struct Mask {
        __m256d m;
        int bits() const { return _mm256_movemask_pd(m); }
        friend Mask operator&(Mask a, Mask b) { return {_mm256_and_pd(a.m, b.m)}; }
        friend Mask operator|(Mask a, Mask b) { return {_mm256_or_pd(a.m, b.m)}; }
    };
    static constexpr int LANES = 4;
    __m256d v;

    static D4Avx load(const double* p) { return {_mm256_loadu_pd(p)}; }
    static D4Avx splat(double x) { return {_mm256_set1_pd(x)}; }
    static D4Avx zero() { return {_mm256_setzero_pd()}; }
    void store(double* p) const { _mm256_storeu_pd(p, v); }
    friend D4Avx operator+(D4Avx a, D4Avx b) { return {_mm256_add_pd(a.v, b.v)}; }
    friend D4Avx operator-(D4Avx a, D4Avx b) { return {_mm256_sub_pd(a.v, b.v)}; }
    friend D4Avx operator*(D4Avx a, D4Avx b) { return {_mm256_mul_pd(a.v, b.v)}; }
    friend D4Avx min(D4Avx a, D4Avx b) { return {_mm256_min_pd(a.v, b.v)}; }
    friend D4Avx max(D4Avx a, D4Avx b) { return {_mm256_max_pd(a.v, b.v)}; }
    friend D4Avx abs(D4Avx a) { return {_mm256_andnot_pd(_mm256_set1_pd(-0.0), a.v)}; }
    friend Mask operator<=(D4Avx a, D4Avx b) { return {_mm256_cmp_pd(a.v, b.v, _CMP_LE_OQ)}; }
    friend Mask operator>=(D4Avx a, D4Avx b) { return {_mm256_cmp_pd(a.v, b.v, _CMP_GE_OQ)}; }
    friend Mask operator<(D4Avx a, D4Avx b) { return {_mm256_cmp_pd(a.v, b.v, _CMP_LT_OQ)}; }
    friend Mask operator>(D4Avx a, D4Avx b) { return {_mm256_cmp_pd(a.v, b.v, _CMP_GT_OQ)}; }
};
using D4 = D4Avx;

inline D4 load_point(const double* p) { return {_mm256_maskload_pd(p, _mm256_setr_epi64x(-1, -1, -1, 0))}; }
inline F4 to_float(D4 d) { return {_mm256_cvtpd_ps(d.v)}; }
#else
/// Eight floats as two F4.
struct F8Pair {
    using Mask = BitMask;
    static constexpr int LANES = 8;
    F4 lo, hi;

    static F8Pair load(const float* p) { return {F4::load(p), F4::load(p + 4)}; }
    static F8Pair splat(float x) { return {F4::splat(x), F4::splat(x)}; }
    static F8Pair zero() { return {F4::zero(), F4::zero()}; }
    void store(float* p) const
    {
        lo.store(p);
        hi.store(p + 4);
    }
    friend F8Pair operator+(F8Pair a, F8Pair b) { return {a.lo + b.lo, a.hi + b.hi}; }
    friend F8Pair operator-(F8Pair a, F8Pair b) { return {a.lo - b.lo, a.hi - b.hi}; }
    friend F8Pair operator*(F8Pair a, F8Pair b) { return {a.lo * b.lo, a.hi * b.hi}; }
    friend F8Pair min(F8Pair a, F8Pair b) { return {min(a.lo, b.lo), min(a.hi, b.hi)}; }
    friend F8Pair max(F8Pair a, F8Pair b) { return {max(a.lo, b.lo), max(a.hi, b.hi)}; }
    friend F8Pair abs(F8Pair a) { return {abs(a.lo), abs(a.hi)}; }
    static Mask join(F4::Mask lo, F4::Mask hi) { return {lo.bits() | (hi.bits() << 4)}; }
    friend Mask operator<=(F8Pair a, F8Pair b) { return join(a.lo <= b.lo, a.hi <= b.hi); }
    friend Mask operator>=(F8Pair a, F8Pair b) { return join(a.lo >= b.lo, a.hi >= b.hi); }
    friend Mask operator<(F8Pair a, F8Pair b) { return join(a.lo < b.lo, a.hi < b.hi); }
    friend Mask operator>(F8Pair a, F8Pair b) { return join(a.lo > b.lo, a.hi > b.hi); }
};
using F8 = F8Pair;
using D4 = D4Scalar;

inline D4 load_point(const double* p) { return load_point_scalar(p); }
inline F4 to_float(D4 d)
{
    float f[4];
    to_float_scalar(d).store(f);
    return F4::load(f);
}
#endif

/// Four float boxes, one register per coordinate bound: lo[coordinate][box], hi[coordinate][box].
struct Boxes4 {
    const float (*lo)[4];
    const float (*hi)[4];
};

/// Bit 4i + k set: box i of `a` and box k of `b` meet each other and the box [region_lo,
/// region_hi] (closed). Three intervals meet when the largest lower bound is at most the
/// smallest upper bound: both sets are clipped to the region, then each pair compared. Empty
/// boxes (+∞, −∞) meet nothing.
inline int box_pairs_meeting_portable(Boxes4 a, Boxes4 b, const F4* region_lo, const F4* region_hi)
{
    float a_lo[3][4], a_hi[3][4];
    F4 b_lo[3], b_hi[3];
    for (int j = 0; j < 3; ++j) {
        max(F4::load(a.lo[j]), region_lo[j]).store(a_lo[j]);
        min(F4::load(a.hi[j]), region_hi[j]).store(a_hi[j]);
        b_lo[j] = max(F4::load(b.lo[j]), region_lo[j]);
        b_hi[j] = min(F4::load(b.hi[j]), region_hi[j]);
    }
    int bits = 0;
    for (int i = 0; i < 4; ++i) {
        auto meet = (F4::splat(a_lo[0][i]) <= b_hi[0]) & (F4::splat(a_hi[0][i]) >= b_lo[0]);
        for (int j = 1; j < 3; ++j)
            meet = meet & (F4::splat(a_lo[j][i]) <= b_hi[j]) & (F4::splat(a_hi[j][i]) >= b_lo[j]);
        bits |= meet.bits() << (4 * i);
    }
    return bits;
}

#if CORO_CONTACT_AVX2
/// box_pairs_meeting_portable(), all sixteen pairs in two AVX registers: boxes i = 0, 1 of `a`
/// against the four of `b` in one, i = 2, 3 in the other.
inline int box_pairs_meeting(Boxes4 a, Boxes4 b, const F4* region_lo, const F4* region_hi)
{
    const __m256i first = _mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1);
    const __m256i second = _mm256_setr_epi32(2, 2, 2, 2, 3, 3, 3, 3);
    __m256 meet01 = _mm256_castsi256_ps(_mm256_set1_epi32(-1)), meet23 = meet01;
    for (int j = 0; j < 3; ++j) {
        const __m128 a_lo = _mm_max_ps(_mm_loadu_ps(a.lo[j]), region_lo[j].v);
        const __m128 a_hi = _mm_min_ps(_mm_loadu_ps(a.hi[j]), region_hi[j].v);
        const __m128 b_lo = _mm_max_ps(_mm_loadu_ps(b.lo[j]), region_lo[j].v);
        const __m128 b_hi = _mm_min_ps(_mm_loadu_ps(b.hi[j]), region_hi[j].v);
        const __m256 a_lo8 = _mm256_castps128_ps256(a_lo), a_hi8 = _mm256_castps128_ps256(a_hi);
        const __m256 b_lo8 = _mm256_set_m128(b_lo, b_lo), b_hi8 = _mm256_set_m128(b_hi, b_hi);
        const auto meet = [&](const __m256i& lanes) {
            return _mm256_and_ps(_mm256_cmp_ps(_mm256_permutevar8x32_ps(a_lo8, lanes), b_hi8, _CMP_LE_OQ),
                                 _mm256_cmp_ps(_mm256_permutevar8x32_ps(a_hi8, lanes), b_lo8, _CMP_GE_OQ));
        };
        meet01 = _mm256_and_ps(meet01, meet(first));
        meet23 = _mm256_and_ps(meet23, meet(second));
    }
    return _mm256_movemask_ps(meet01) | (_mm256_movemask_ps(meet23) << 8);
}
#else
inline int box_pairs_meeting(Boxes4 a, Boxes4 b, const F4* region_lo, const F4* region_hi)
{
    return box_pairs_meeting_portable(a, b, region_lo, region_hi);
}
#endif

} // namespace coro::detail::simd
