#include <corocontact/fem/corotational_tangent.hpp>

#include <corocontact/fem/tet_element.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace coro {

namespace {
constexpr Index TET_GRAIN = 512;
constexpr Index ROW_GRAIN = 256;

std::size_t at(Index i) { return static_cast<std::size_t>(i); }

Mat3 cross_matrix(const Vec3& v)
{
    Mat3 m;
    m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
    return m;
}

// M of the file comment. EXACT: M = 2μ I + 2(λ(tr S − 3) − 2μ)(tr S · I − S)⁻¹ directly.
// PROJECTED, or tr S · I − S close to singular (only in a strongly inverted element, where R is
// the sign-fixed rotation): in the frame of S's eigenvectors, m_k = (ψ_i + ψ_j)/(σ_i + σ_j),
// clamped to ≥ 0 when projecting; a pair with σ_i + σ_j ≤ 0 has no defined rotation
// derivative and gets no term.
Mat3 rotation_weight(const Mat3& s, double lambda, double mu, TangentDefiniteness kind)
{
    constexpr double SINGULAR = 1e-12;
    const double trace = s.trace();
    if (kind == TangentDefiniteness::EXACT) {
        const Mat3 shifted = trace * Mat3::Identity() - s;
        const double det = shifted.determinant();
        if (det > SINGULAR * trace * trace * trace)
            return 2.0 * mu * Mat3::Identity() + 2.0 * (lambda * (trace - 3.0) - 2.0 * mu) * shifted.inverse();
    }
    const Eigen::SelfAdjointEigenSolver<Mat3> eigen(s);
    const Vec3& sigma = eigen.eigenvalues();
    Vec3 m;
    for (int k = 0; k < 3; ++k) {
        const double pair = trace - sigma[k]; // σ_i + σ_j
        const double psi_pair = 2.0 * mu * (pair - 2.0) + 2.0 * lambda * (trace - 3.0);
        m[k] = pair > SINGULAR * std::abs(trace) ? psi_pair / pair : 0.0;
        if (kind == TangentDefiniteness::PROJECTED && m[k] < 0.0)
            m[k] = 0.0;
    }
    return eigen.eigenvectors() * m.asDiagonal() * eigen.eigenvectors().transpose();
}
} // namespace

CorotationalTangent::CorotationalTangent(const CorotationalFem& fem)
{
    const Tets& tets = fem.tets();
    const VecX& rest = fem.rest_dofs();
    const Index n_tets = fem.num_tets();
    m_gradients.resize(at(n_tets));
    m_terms.resize(at(n_tets));
    for (Index t = 0; t < n_tets; ++t) {
        const auto node = [&](int a) { return Vec3(rest.segment<3>(3 * tets(t, a))); };
        m_gradients[at(t)] = shape_gradients(make_tet_rest(node(0), node(1), node(2), node(3)));
    }

    // Terms per block: count, then fill in tet order (CSR).
    const BsrMatrix pattern = fem.make_matrix();
    std::vector<Index> block_of(16 * at(n_tets), -1);
    m_block_offsets.assign(at(pattern.num_blocks()) + 1, 0);
    for (Index t = 0; t < n_tets; ++t)
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b)
                if (a == b || tets(t, a) < tets(t, b)) {
                    const Index k = pattern.find(tets(t, a), tets(t, b));
                    block_of[16 * at(t) + at(4 * a + b)] = k;
                    ++m_block_offsets[at(k) + 1];
                }
    for (std::size_t k = 1; k < m_block_offsets.size(); ++k)
        m_block_offsets[k] += m_block_offsets[k - 1];
    m_block_terms.resize(at(m_block_offsets.back()));
    std::vector<Index> next(m_block_offsets.begin(), m_block_offsets.end() - 1);
    for (Index t = 0; t < n_tets; ++t)
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b)
                if (const Index k = block_of[16 * at(t) + at(4 * a + b)]; k >= 0)
                    m_block_terms[at(next[at(k)]++)] = {t, static_cast<std::uint8_t>(a), static_cast<std::uint8_t>(b)};
}

void CorotationalTangent::assemble(CorotationalFem& fem, CRef<VecX> x, const std::vector<char>& fixed,
                                   TangentDefiniteness kind, BsrMatrix& tangent)
{
    if (fem.num_tets() != static_cast<Index>(m_terms.size()))
        throw std::invalid_argument("CorotationalTangent::assemble: the model has " + std::to_string(fem.num_tets()) +
                                    " tets, the tangent was built for " + std::to_string(m_terms.size()));
    fem.assemble(1.0, 0.0, fixed, tangent);

    const Tets& tets = fem.tets();
    const std::vector<Mat3>& rotations = fem.rotations();
    const double lambda = fem.lambda(), mu = fem.mu();
    const tbb::blocked_range<Index> all_tets(0, fem.num_tets(), TET_GRAIN);
    tbb::parallel_for(all_tets, [&](const tbb::blocked_range<Index>& range) {
        for (Index t = range.begin(); t != range.end(); ++t) {
            const Mat34& g = m_gradients[at(t)];
            const Mat3& r = rotations[at(t)];
            Mat34 nodes;
            for (int a = 0; a < 4; ++a)
                nodes.col(a) = x.segment<3>(3 * tets(t, a));
            const Mat3 rs = r.transpose() * (nodes * g.transpose()); // S = Rᵀ F
            const Mat3 s = 0.5 * (rs + rs.transpose());
            TetTerms& terms = m_terms[at(t)];
            terms.rotated_gradients = r * g;
            terms.weight = (0.5 * fem.volumes()[at(t)]) * (r * rotation_weight(s, lambda, mu, kind) * r.transpose());
        }
    });

    const std::vector<Index>& row_offsets = tangent.row_offsets();
    const std::vector<Index>& columns = tangent.columns();
    const auto is_fixed = [&](Index node) { return !fixed.empty() && fixed[at(node)] != 0; };
    tbb::parallel_for(tbb::blocked_range<Index>(0, tangent.num_block_rows(), ROW_GRAIN),
                      [&](const tbb::blocked_range<Index>& range) {
                          for (Index row = range.begin(); row != range.end(); ++row) {
                              if (is_fixed(row))
                                  continue;
                              for (Index k = row_offsets[at(row)]; k < row_offsets[at(row) + 1]; ++k) {
                                  if (is_fixed(columns[at(k)]))
                                      continue;
                                  Mat3 sum = Mat3::Zero();
                                  for (Index e = m_block_offsets[at(k)]; e < m_block_offsets[at(k) + 1]; ++e) {
                                      const BlockTerm& term = m_block_terms[at(e)];
                                      const TetTerms& terms = m_terms[at(term.tet)];
                                      const Mat3 ga = cross_matrix(terms.rotated_gradients.col(term.a));
                                      const Mat3 gb = cross_matrix(terms.rotated_gradients.col(term.b));
                                      sum.noalias() -= ga * terms.weight * gb; // [G_a]×ᵀ = −[G_a]×
                                  }
                                  tangent.add_to_block(k, sum);
                              }
                          }
                      });
}

} // namespace coro
