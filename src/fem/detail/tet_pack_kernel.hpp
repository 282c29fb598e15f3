#pragma once
// The element kernel four tets at a time, one tet per lane of an AVX2 vector: gather, the
// polar rotation (the Newton iteration of polar_rotation, lane by lane), the rotated gradients,
// the internal forces and the 10 rotated stiffness blocks. Per-tet data stays in its usual
// array-of-structures layout and is transposed on the way in and out (4×4 transposes), so
// nothing else changes shape. Lanes follow the tets' order, and so do the additions into the
// matrix and the forces, so a part's result does not depend on the thread count.
//
// Only built with AVX2 and FMA (CORO_TET_PACKS); otherwise corotational_fem.cpp uses its
// one-tet loop.

#if defined(__AVX2__) && defined(__FMA__)
#define CORO_TET_PACKS 1

#include "tet_block_kernel.hpp"

#include <corocontact/core/types.hpp>

#include <immintrin.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>

namespace coro::detail {

using Pack = __m256d;
constexpr int LANES = 4;

inline Pack splat(double v) { return _mm256_set1_pd(v); }
inline Pack add(Pack a, Pack b) { return _mm256_add_pd(a, b); }
inline Pack sub(Pack a, Pack b) { return _mm256_sub_pd(a, b); }
inline Pack mul(Pack a, Pack b) { return _mm256_mul_pd(a, b); }
inline Pack fma(Pack a, Pack b, Pack c) { return _mm256_fmadd_pd(a, b, c); }  // a·b + c
inline Pack fms(Pack a, Pack b, Pack c) { return _mm256_fmsub_pd(a, b, c); }  // a·b − c
inline Pack select(Pack mask, Pack if_set, Pack if_clear) { return _mm256_blendv_pd(if_clear, if_set, mask); }
inline int lanes_of(Pack mask) { return _mm256_movemask_pd(mask); }

/// Rows r0..r3 of a 4×4 matrix become its columns (the transpose is its own inverse).
inline void transpose4(Pack& r0, Pack& r1, Pack& r2, Pack& r3)
{
    const Pack t0 = _mm256_unpacklo_pd(r0, r1), t1 = _mm256_unpackhi_pd(r0, r1);
    const Pack t2 = _mm256_unpacklo_pd(r2, r3), t3 = _mm256_unpackhi_pd(r2, r3);
    r0 = _mm256_permute2f128_pd(t0, t2, 0x20);
    r1 = _mm256_permute2f128_pd(t1, t3, 0x20);
    r2 = _mm256_permute2f128_pd(t0, t2, 0x31);
    r3 = _mm256_permute2f128_pd(t1, t3, 0x31);
}

/// Entries [first, first + 4) of four arrays as four packs: out[k] lane l = rows[l][first + k].
inline void load_transposed(const double* const rows[LANES], int first, Pack out[4])
{
    for (int l = 0; l < LANES; ++l)
        out[l] = _mm256_loadu_pd(rows[l] + first);
    transpose4(out[0], out[1], out[2], out[3]);
}

/// Entry `k` of four arrays as one pack.
inline Pack load_lanes(const double* const rows[LANES], int k)
{
    return _mm256_set_pd(rows[3][k], rows[2][k], rows[1][k], rows[0][k]);
}

/// 3×3 matrices, one per lane, m[r][c].
struct Mat3Pack {
    Pack m[3][3];
};

/// Column-major 3×3 matrices (Eigen's Mat3) of four tets as one Mat3Pack.
inline Mat3Pack load_mat3(const double* const mats[LANES])
{
    Pack e[8];
    load_transposed(mats, 0, e);
    load_transposed(mats, 4, e + 4);
    Mat3Pack out;
    for (int k = 0; k < 8; ++k)
        out.m[k % 3][k / 3] = e[k];
    out.m[2][2] = load_lanes(mats, 8);
    return out;
}

/// Stores lane l of `a` to the column-major 3×3 matrix mats[l], for lanes l < count.
inline void store_mat3(const Mat3Pack& a, double* const mats[LANES], int count)
{
    Pack e[8];
    for (int k = 0; k < 8; ++k)
        e[k] = a.m[k % 3][k / 3];
    transpose4(e[0], e[1], e[2], e[3]);
    transpose4(e[4], e[5], e[6], e[7]);
    alignas(32) double last[LANES];
    _mm256_store_pd(last, a.m[2][2]);
    for (int l = 0; l < count; ++l) {
        _mm256_storeu_pd(mats[l], e[l]);
        _mm256_storeu_pd(mats[l] + 4, e[4 + l]);
        mats[l][8] = last[l];
    }
}

/// Column-major 3×4 matrices (Eigen's Mat34: column a = g_a) of four tets: out[a][c].
inline void load_mat34(const double* const mats[LANES], Pack out[4][3])
{
    Pack e[12];
    load_transposed(mats, 0, e);
    load_transposed(mats, 4, e + 4);
    load_transposed(mats, 8, e + 8);
    for (int k = 0; k < 12; ++k)
        out[k / 3][k % 3] = e[k];
}

/// Node positions of four tets: p[a][c] lane l = x[3·tets(tet[l], a) + c].
inline void gather_nodes(const Tets& tets, const Index tet[LANES], const double* x, Pack p[4][3])
{
    for (int a = 0; a < 4; ++a) {
        __m128d xy[LANES], z[LANES];
        for (int l = 0; l < LANES; ++l) {
            const double* node = x + 3 * static_cast<std::ptrdiff_t>(tets(tet[l], a));
            xy[l] = _mm_loadu_pd(node);
            z[l] = _mm_load_sd(node + 2);
        }
        p[a][0] = _mm256_set_m128d(_mm_unpacklo_pd(xy[2], xy[3]), _mm_unpacklo_pd(xy[0], xy[1]));
        p[a][1] = _mm256_set_m128d(_mm_unpackhi_pd(xy[2], xy[3]), _mm_unpackhi_pd(xy[0], xy[1]));
        p[a][2] = _mm256_set_m128d(_mm_unpacklo_pd(z[2], z[3]), _mm_unpacklo_pd(z[0], z[1]));
    }
}

/// F = Σ_a p_a g_aᵀ (the deformation gradient, as nodes · gᵀ in the one-tet loop).
inline Mat3Pack deformation_gradient(const Pack p[4][3], const Pack g[4][3])
{
    Mat3Pack f;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            f.m[r][c] = fma(p[3][r], g[3][c], fma(p[2][r], g[2][c], fma(p[1][r], g[1][c], mul(p[0][r], g[0][c]))));
    return f;
}

/// Lanes whose matrix has a NaN or infinite entry.
inline int non_finite_lanes(const Mat3Pack& a)
{
    Pack sum = splat(0.0);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            sum = add(sum, sub(a.m[r][c], a.m[r][c])); // 0 when finite, NaN otherwise
    return lanes_of(_mm256_cmp_pd(sum, sum, _CMP_UNORD_Q));
}

/// aᵀ b.
inline Mat3Pack transpose_times(const Mat3Pack& a, const Mat3Pack& b)
{
    Mat3Pack out;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            out.m[r][c] = fma(a.m[2][r], b.m[2][c], fma(a.m[1][r], b.m[1][c], mul(a.m[0][r], b.m[0][c])));
    return out;
}

/// a b.
inline Mat3Pack times(const Mat3Pack& a, const Mat3Pack& b)
{
    Mat3Pack out;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            out.m[r][c] = fma(a.m[r][2], b.m[2][c], fma(a.m[r][1], b.m[1][c], mul(a.m[r][0], b.m[0][c])));
    return out;
}

/// X⁻ᵀ = cof(X) / det(X); `det` receives det(X).
inline Mat3Pack inverse_transpose(const Mat3Pack& a, Pack& det)
{
    const auto& x = a.m;
    Mat3Pack cof;
    cof.m[0][0] = fms(x[1][1], x[2][2], mul(x[1][2], x[2][1]));
    cof.m[0][1] = fms(x[1][2], x[2][0], mul(x[1][0], x[2][2]));
    cof.m[0][2] = fms(x[1][0], x[2][1], mul(x[1][1], x[2][0]));
    cof.m[1][0] = fms(x[0][2], x[2][1], mul(x[0][1], x[2][2]));
    cof.m[1][1] = fms(x[0][0], x[2][2], mul(x[0][2], x[2][0]));
    cof.m[1][2] = fms(x[0][1], x[2][0], mul(x[0][0], x[2][1]));
    cof.m[2][0] = fms(x[0][1], x[1][2], mul(x[0][2], x[1][1]));
    cof.m[2][1] = fms(x[0][2], x[1][0], mul(x[0][0], x[1][2]));
    cof.m[2][2] = fms(x[0][0], x[1][1], mul(x[0][1], x[1][0]));
    det = fma(x[0][2], cof.m[0][2], fma(x[0][1], cof.m[0][1], mul(x[0][0], cof.m[0][0])));
    const Pack inv_det = _mm256_div_pd(splat(1.0), det);
    for (auto& row : cof.m)
        for (Pack& v : row)
            v = mul(v, inv_det);
    return cof;
}

/// The rotation of the polar decomposition of F for each lane, by polar_rotation's Newton
/// iteration on guessᵀF (see corotation.cpp): each lane stops when its own update is below the
/// tolerance. Returns the lanes that need the SVD instead (inverted or nearly singular guessᵀF,
/// or no convergence in 30 iterations); their `rotation` is meaningless.
inline int polar_rotation_lanes(const Mat3Pack& f, const Mat3Pack& guess, double tolerance, Mat3Pack& rotation)
{
    Mat3Pack x = transpose_times(guess, f);
    Pack norm2 = splat(0.0);
    for (const auto& row : x.m)
        for (const Pack v : row)
            norm2 = fma(v, v, norm2);
    const Pack scale3 = mul(norm2, _mm256_sqrt_pd(norm2));
    Pack det;
    Mat3Pack inverse = inverse_transpose(x, det);
    // Not (det > 1e-6 scale³): NaN compares false, so it goes to the SVD too.
    Pack fallback = _mm256_cmp_pd(det, mul(splat(1e-6), scale3), _CMP_NGT_UQ);
    Pack active = _mm256_andnot_pd(fallback, _mm256_castsi256_pd(_mm256_set1_epi64x(-1)));
    const Pack half = splat(0.5), tolerance2 = splat(tolerance * tolerance);
    for (int iteration = 0; iteration < 30 && lanes_of(active) != 0; ++iteration) {
        Pack change = splat(0.0);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) {
                const Pack next = mul(half, add(x.m[r][c], inverse.m[r][c]));
                const Pack step = sub(next, x.m[r][c]);
                change = fma(step, step, change);
                x.m[r][c] = select(active, next, x.m[r][c]);
            }
        const Pack converged = _mm256_and_pd(active, _mm256_cmp_pd(mul(change, change), tolerance2, _CMP_LT_OQ));
        active = _mm256_andnot_pd(converged, active);
        if (lanes_of(active) == 0)
            break;
        inverse = inverse_transpose(x, det);
        const Pack singular = _mm256_and_pd(active, _mm256_cmp_pd(det, splat(0.0), _CMP_NGT_UQ));
        fallback = _mm256_or_pd(fallback, singular);
        active = _mm256_andnot_pd(singular, active);
    }
    rotation = times(guess, x);
    return lanes_of(_mm256_or_pd(fallback, active));
}

/// R g_a for the 4 gradients: out[a][r].
inline void rotate_gradients(const Mat3Pack& rotation, const Pack g[4][3], Pack out[4][3])
{
    const auto& r = rotation.m;
    for (int a = 0; a < 4; ++a)
        for (int i = 0; i < 3; ++i)
            out[a][i] = fma(r[i][2], g[a][2], fma(r[i][1], g[a][1], mul(r[i][0], g[a][0])));
}

/// Internal forces f_a = −V σ(ε) G_a with ε = sym(F Rᵀ) − I, F Rᵀ = Σ_a p_a G_aᵀ: out[a][r].
inline void corner_forces(const Pack p[4][3], const Pack rg[4][3], Pack volume, double lambda, double mu,
                          Pack out[4][3])
{
    Pack m[3][3];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            m[r][c] = fma(p[3][r], rg[3][c], fma(p[2][r], rg[2][c], fma(p[1][r], rg[1][c], mul(p[0][r], rg[0][c]))));
    // −V σ = −V (λ tr(ε) I + 2μ ε), with ε_rc = (m_rc + m_cr)/2 − δ_rc.
    const Pack one = splat(1.0);
    const Pack trace = add(add(sub(m[0][0], one), sub(m[1][1], one)), sub(m[2][2], one));
    const Pack minus_v = sub(splat(0.0), volume);
    const Pack two_mu_v = mul(splat(2.0 * mu), minus_v), mu_v = mul(splat(mu), minus_v);
    const Pack lambda_trace_v = mul(mul(splat(lambda), trace), minus_v);
    Pack s[3][3];
    for (int r = 0; r < 3; ++r) {
        s[r][r] = fma(two_mu_v, sub(m[r][r], one), lambda_trace_v);
        for (int c = r + 1; c < 3; ++c)
            s[r][c] = s[c][r] = mul(mu_v, add(m[r][c], m[c][r]));
    }
    for (int a = 0; a < 4; ++a)
        for (int r = 0; r < 3; ++r)
            out[a][r] = fma(s[r][2], rg[a][2], fma(s[r][1], rg[a][1], mul(s[r][0], rg[a][0])));
}

/// Lane `lane` of a Mat3Pack.
inline Mat3 lane_of(const Mat3Pack& a, int lane)
{
    Mat3 out;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            alignas(32) double lanes[LANES];
            _mm256_store_pd(lanes, a.m[r][c]);
            out(r, c) = lanes[lane];
        }
    return out;
}

/// Adds the 12 corner forces f[a][r] of lane l to the 3 doubles at corner(l, a), a = 0..3, for
/// lanes l < count, lane by lane.
template <class Corner>
inline void add_corner_forces(const Pack f[4][3], int count, const Corner& corner)
{
    Pack e[12];
    for (int k = 0; k < 12; ++k)
        e[k] = f[k / 3][k % 3];
    for (int q = 0; q < 3; ++q)
        transpose4(e[4 * q], e[4 * q + 1], e[4 * q + 2], e[4 * q + 3]);
    for (int l = 0; l < count; ++l) {
        alignas(32) double row[12]; // f_0, f_1, f_2, f_3 of lane l
        _mm256_store_pd(row, e[l]);
        _mm256_store_pd(row + 4, e[4 + l]);
        _mm256_store_pd(row + 8, e[8 + l]);
        for (int a = 0; a < 4; ++a) {
            double* out = corner(l, a);
            out[0] += row[3 * a];
            out[1] += row[3 * a + 1];
            out[2] += row[3 * a + 2];
        }
    }
}

/// Adds block `Pair` (TET_BLOCK_PAIRS order) of every lane to block(lane, Pair); see
/// Adds row-major entries 0..3 (`low`), 4..7 (`high`) and 8 (`last`) to a 3×3 block stored in
/// double or, rounded after the addition, in float.
inline void add_block_entries(double* target, Pack low, Pack high, double last)
{
    _mm256_storeu_pd(target, add(_mm256_loadu_pd(target), low));
    _mm256_storeu_pd(target + 4, add(_mm256_loadu_pd(target + 4), high));
    target[8] += last;
}
inline void add_block_entries(float* target, Pack low, Pack high, double last)
{
    _mm_storeu_ps(target, _mm256_cvtpd_ps(add(_mm256_cvtps_pd(_mm_loadu_ps(target)), low)));
    _mm_storeu_ps(target + 4, _mm256_cvtpd_ps(add(_mm256_cvtps_pd(_mm_loadu_ps(target + 4)), high)));
    target[8] = static_cast<float>(static_cast<double>(target[8]) + last);
}

/// add_stiffness_blocks. A template so that the block's gradient indices are constants.
template <int Pair, class BlockSlot>
inline void add_stiffness_block(const Pack rg[4][3], const Pack l[4][3], const Pack m[4][3], __m256i transposed,
                                int count, const BlockSlot& block)
{
    constexpr int i = TET_BLOCK_PAIRS[Pair][0], j = TET_BLOCK_PAIRS[Pair][1];
    const __m256i bit = _mm256_set1_epi64x(1LL << Pair);
    const Pack flip = _mm256_castsi256_pd(_mm256_cmpeq_epi64(_mm256_and_si256(transposed, bit), bit));
    const Pack d = fma(m[j][2], rg[i][2], fma(m[j][1], rg[i][1], mul(m[j][0], rg[i][0])));
    Pack k[3][3];
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
            k[a][b] = fma(l[i][a], rg[j][b], mul(m[j][a], rg[i][b]));
    for (int a = 0; a < 3; ++a)
        k[a][a] = add(k[a][a], d);
    for (int a = 0; a < 3; ++a)
        for (int b = a + 1; b < 3; ++b) {
            const Pack ab = k[a][b];
            k[a][b] = select(flip, k[b][a], ab);
            k[b][a] = select(flip, ab, k[b][a]);
        }
    Pack low[LANES] = {k[0][0], k[0][1], k[0][2], k[1][0]};  // row-major entries 0..3
    Pack high[LANES] = {k[1][1], k[1][2], k[2][0], k[2][1]}; // entries 4..7
    transpose4(low[0], low[1], low[2], low[3]);
    transpose4(high[0], high[1], high[2], high[3]);
    alignas(32) double last[LANES]; // entry 8
    _mm256_store_pd(last, k[2][2]);
    for (int lane = 0; lane < count; ++lane)
        add_block_entries(block(lane, Pair), low[lane], high[lane], last[lane]);
}

template <class BlockSlot, int... Pair>
inline void add_stiffness_block_list(const Pack rg[4][3], const Pack l[4][3], const Pack m[4][3], __m256i transposed,
                                     int count, const BlockSlot& block, std::integer_sequence<int, Pair...>)
{
    (add_stiffness_block<Pair>(rg, l, m, transposed, count, block), ...);
}

/// Adds the rotated stiffness blocks K'_ij, i ≤ j in TET_BLOCK_PAIRS order, of lane l to the
/// row-major 3×3 block at block(l, pair) (double* or float*: see add_block_entries), transposed where bit `pair` of transposed[l] is set,
/// for lanes l < count. K'_ij[a][b] = L_i[a] G_j[b] + M_j[a] G_i[b] + (M_j·G_i) δ_ab with
/// L = sλ G and M = sμ G (s = stiffness scale × V). A tet's 10 blocks go to 10 different
/// blocks; two tets of a pack may share one, and then they add in a fixed (pair, lane) order.
template <class BlockSlot>
inline void add_stiffness_blocks(const Pack rg[4][3], Pack scale, double lambda, double mu,
                                 const std::uint16_t transposed[LANES], int count, const BlockSlot& block)
{
    Pack l[4][3], m[4][3];
    const Pack s_lambda = mul(scale, splat(lambda)), s_mu = mul(scale, splat(mu));
    for (int a = 0; a < 4; ++a)
        for (int r = 0; r < 3; ++r) {
            l[a][r] = mul(s_lambda, rg[a][r]);
            m[a][r] = mul(s_mu, rg[a][r]);
        }
    const __m256i bits = _mm256_set_epi64x(transposed[3], transposed[2], transposed[1], transposed[0]);
    add_stiffness_block_list(rg, l, m, bits, count, block, std::make_integer_sequence<int, 10>{});
}

} // namespace coro::detail

#endif
