#pragma once
// Adds one 3×3 block of a tet's rotated stiffness to its slot (stored in double, or in float:
// then each entry is added in double and rounded once): K'_ij or its transpose, with
// the gradients pre-scaled (L = sλ G, M = sμ G, d = M_j·G_i):
//   K'_ij[a][b] = L_i[a] G_j[b] + M_j[a] G_i[b] + d δ_ab.
// Row a of K'_ij is L_i[a] G_j + M_j[a] G_i (+ d e_a); row a of K'_ijᵀ is G_j[a] L_i + G_i[a] M_j
// (+ d e_a). With AVX2 and FMA a row is one 4-wide vector whose fourth lane is zero, so the
// 4-wide update of rows 0 and 1 leaves the element after them unchanged (it is the next row
// of the same block); row 2 is written in 2 + 1 lanes, never touching the next block.

#include <corocontact/core/types.hpp>

#include <array>

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#endif

namespace coro::detail {

/// The 10 blocks (i, j), i ≤ j, of a tet's symmetric 4×4 block matrix, in target order.
inline constexpr std::array<std::array<int, 2>, 10> TET_BLOCK_PAIRS{
    {{0, 0}, {0, 1}, {0, 2}, {0, 3}, {1, 1}, {1, 2}, {1, 3}, {2, 2}, {2, 3}, {3, 3}}};

/// Entry by entry, in double: the form every build has (the AVX2 build uses it for float).
template <class Value>
inline void add_tet_block_entries(Value* k, int i, int j, bool transposed, const Mat34& g, const Mat34& l,
                                  const Mat34& m)
{
    const double* gi = g.col(i).data();
    const double* gj = g.col(j).data();
    const double* li = l.col(i).data();
    const double* mj = m.col(j).data();
    const double d = mj[0] * gi[0] + mj[1] * gi[1] + mj[2] * gi[2];
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            const double value = li[a] * gj[b] + mj[a] * gi[b] + (a == b ? d : 0.0);
            Value& entry = k[transposed ? 3 * b + a : 3 * a + b];
            entry = static_cast<Value>(static_cast<double>(entry) + value);
        }
}

#if defined(__AVX2__) && defined(__FMA__)

/// The 4 columns of a 3×4 matrix as 4-wide vectors with a zero fourth lane.
struct PaddedColumns {
    __m256d col[4];
    explicit PaddedColumns(const Mat34& m)
    {
        for (int c = 0; c < 4; ++c)
            col[c] = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(m.col(c).data())),
                                          _mm_load_sd(m.col(c).data() + 2), 1);
    }
};

// k += (row a: s1[a] v1 + s2[a] v2 + d e_a), a = 0, 1, 2; k is a row-major 3×3 block.
// All of k is loaded before anything is stored: a 4-wide load overlapping the previous row's
// 4-wide store would wait for it (no store-to-load forwarding across partial overlaps).
inline void add_rows(double* k, const double* s1, __m256d v1, const double* s2, __m256d v2, double d)
{
    const __m256d old0 = _mm256_loadu_pd(k), old1 = _mm256_loadu_pd(k + 3);
    const __m128d old2 = _mm_loadu_pd(k + 6), old8 = _mm_load_sd(k + 8);
    const __m256d dv = _mm256_set1_pd(d), zero = _mm256_setzero_pd();
    const __m256d row0 = _mm256_fmadd_pd(_mm256_broadcast_sd(s1), v1,
                                         _mm256_fmadd_pd(_mm256_broadcast_sd(s2), v2, _mm256_blend_pd(zero, dv, 1)));
    const __m256d row1 = _mm256_fmadd_pd(_mm256_broadcast_sd(s1 + 1), v1,
                                         _mm256_fmadd_pd(_mm256_broadcast_sd(s2 + 1), v2, _mm256_blend_pd(zero, dv, 2)));
    const __m256d row2 = _mm256_fmadd_pd(_mm256_broadcast_sd(s1 + 2), v1,
                                         _mm256_fmadd_pd(_mm256_broadcast_sd(s2 + 2), v2, _mm256_blend_pd(zero, dv, 4)));
    // In this order: row 1's store rewrites k[3] after row 0's (unchanged) copy of it, row 2's
    // rewrites k[6] after row 1's.
    _mm256_storeu_pd(k, _mm256_add_pd(old0, row0));
    _mm256_storeu_pd(k + 3, _mm256_add_pd(old1, row1));
    _mm_storeu_pd(k + 6, _mm_add_pd(old2, _mm256_castpd256_pd128(row2)));
    _mm_store_sd(k + 8, _mm_add_sd(old8, _mm256_extractf128_pd(row2, 1)));
}

/// Adds block (i, j) (transposed if `transposed`) of the tet whose rotated gradients are
/// `g`, `l` = sλ g and `m` = sμ g (3×4 each; pg, pl, pm their padded columns) to `k`.
inline void add_tet_block(double* k, int i, int j, bool transposed, const Mat34& g, const Mat34& l, const Mat34& m,
                          const PaddedColumns& pg, const PaddedColumns& pl, const PaddedColumns& pm)
{
    const double* gi = g.col(i).data();
    const double* mj = m.col(j).data();
    const double d = mj[0] * gi[0] + mj[1] * gi[1] + mj[2] * gi[2];
    if (transposed)
        add_rows(k, g.col(j).data(), pl.col[i], gi, pm.col[j], d);
    else
        add_rows(k, l.col(i).data(), pg.col[j], mj, pg.col[i], d);
}

inline void add_tet_block(float* k, int i, int j, bool transposed, const Mat34& g, const Mat34& l, const Mat34& m,
                          const PaddedColumns&, const PaddedColumns&, const PaddedColumns&)
{
    add_tet_block_entries(k, i, j, transposed, g, l, m);
}

#else

struct PaddedColumns {
    explicit PaddedColumns(const Mat34&) {}
};

template <class Value>
inline void add_tet_block(Value* k, int i, int j, bool transposed, const Mat34& g, const Mat34& l, const Mat34& m,
                          const PaddedColumns&, const PaddedColumns&, const PaddedColumns&)
{
    add_tet_block_entries(k, i, j, transposed, g, l, m);
}

#endif

} // namespace coro::detail
