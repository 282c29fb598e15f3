#include <corocontact/solver/pcg.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/solver/vector_ops.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/LU>

#include <cmath>

namespace coro {

namespace {
constexpr Index PRECONDITIONER_GRAIN = 1024; // block rows per task
constexpr Index UPDATE_GRAIN = 1024;         // nodes per reduction leaf of the fused update
} // namespace

void PcgSolver::build_preconditioner(const BsrMatrix& a, PcgPreconditioner kind)
{
    m_kind = kind;
    const auto n = static_cast<std::size_t>(a.num_block_rows());
    if (kind == PcgPreconditioner::BLOCK_JACOBI)
        m_inverse_blocks.resize(n);
    else
        m_inverse_diagonal.resize(a.num_dofs());
    tbb::parallel_for(tbb::blocked_range<Index>(0, a.num_block_rows(), PRECONDITIONER_GRAIN),
                      [&](const tbb::blocked_range<Index>& range) {
                          for (Index r = range.begin(); r != range.end(); ++r) {
                              const Block3 d = a.block(a.diagonal(r));
                              if (kind == PcgPreconditioner::BLOCK_JACOBI)
                                  m_inverse_blocks[static_cast<std::size_t>(r)] = d.inverse();
                              else
                                  m_inverse_diagonal.segment<3>(3 * r) = d.diagonal().cwiseInverse();
                          }
                      });
}

PcgSolver::Sums PcgSolver::residual_pass(const double* b, double alpha, double* x)
{
    const auto n_nodes = static_cast<Index>(m_r.size() / 3);
    double* r = m_r.data();
    double* z = m_z.data();
    const double* p = m_p.data();
    const double* q = m_q.data();
    const double* inv_diag = m_inverse_diagonal.data();
    const bool block = m_kind == PcgPreconditioner::BLOCK_JACOBI;
    return tbb::parallel_deterministic_reduce(
        tbb::blocked_range<Index>(0, n_nodes, UPDATE_GRAIN), Sums{},
        [&](const tbb::blocked_range<Index>& range, Sums acc) {
            const std::ptrdiff_t begin = 3 * static_cast<std::ptrdiff_t>(range.begin());
            const std::ptrdiff_t end = 3 * static_cast<std::ptrdiff_t>(range.end());
            if (b) {
                for (std::ptrdiff_t i = begin; i < end; ++i)
                    r[i] = b[i] - r[i];
            } else {
                for (std::ptrdiff_t i = begin; i < end; ++i) {
                    x[i] += alpha * p[i];
                    r[i] -= alpha * q[i];
                }
            }
            if (block) {
                for (Index v = range.begin(); v != range.end(); ++v)
                    Eigen::Map<Vec3>(z + 3 * v) =
                        m_inverse_blocks[static_cast<std::size_t>(v)] * Eigen::Map<const Vec3>(r + 3 * v);
            } else {
                for (std::ptrdiff_t i = begin; i < end; ++i)
                    z[i] = inv_diag[i] * r[i];
            }
            double rr = 0.0, rz = 0.0;
            for (std::ptrdiff_t i = begin; i < end; ++i) {
                rr += r[i] * r[i];
                rz += r[i] * z[i];
            }
            acc.rr += rr;
            acc.rz += rz;
            return acc;
        },
        [](Sums left, const Sums& right) {
            left.rr += right.rr;
            left.rz += right.rz;
            return left;
        });
}

PcgResult PcgSolver::solve(const BsrMatrix& a, CRef<VecX> b, Eigen::Ref<VecX> x,
                           const PcgSettings& settings)
{
    const Index n = a.num_dofs();
    CORO_ASSERT(b.size() == n && x.size() == n);
    m_r.resize(n);
    m_z.resize(n);
    m_p.resize(n);
    m_q.resize(n);

    PcgResult result;
    const double b_norm = norm(b);
    if (b_norm == 0.0) {
        x.setZero();
        result.converged = true;
        return result;
    }
    build_preconditioner(a, settings.preconditioner);

    a.multiply(x, m_r);
    Sums sums = residual_pass(b.data(), 0.0, x.data()); // r = b − A x, z = M⁻¹ r
    CORO_CHECK(std::isfinite(sums.rr) && std::isfinite(sums.rz), NumericalError,
               "PCG: the initial residual is not finite (rᵀr = " << sums.rr << ", rᵀz = " << sums.rz << ")");
    double r_norm = std::sqrt(sums.rr);
    double rz = sums.rz;
    m_p = m_z;

    const double target = settings.tolerance * b_norm;
    Index iteration = 0;
    while (r_norm > target && iteration < settings.max_iterations) {
        const double pq = a.multiply_dot(m_p, m_q);
        CORO_CHECK(pq > 0.0, NumericalError,
                   "PCG: pᵀAp = " << pq << " at iteration " << iteration
                                  << " (the system matrix is not positive definite)");
        const double alpha = rz / pq;
        sums = residual_pass(nullptr, alpha, x.data()); // x += αp, r −= αq, z = M⁻¹ r
        CORO_CHECK(std::isfinite(sums.rr) && std::isfinite(sums.rz), NumericalError,
                   "PCG: the residual is not finite at iteration " << iteration);
        ++iteration;
        r_norm = std::sqrt(sums.rr);
        if (r_norm <= target)
            break;
        xpby(m_z, sums.rz / rz, m_p);
        rz = sums.rz;
    }
    result.iterations = iteration;
    result.residual = r_norm / b_norm;
    result.converged = r_norm <= target;
    return result;
}

} // namespace coro
