#include <corocontact/solver/pcg.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/solver/vector_ops.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/LU>

#include <cmath>

namespace coro {

namespace {
constexpr Index PRECONDITIONER_GRAIN = 1024; // block rows per task
}

void PcgSolver::build_preconditioner(const BsrMatrix& a, PcgPreconditioner kind)
{
    m_inverse_blocks.resize(static_cast<std::size_t>(a.num_block_rows()));
    tbb::parallel_for(tbb::blocked_range<Index>(0, a.num_block_rows(), PRECONDITIONER_GRAIN),
                      [&](const tbb::blocked_range<Index>& range) {
                          for (Index r = range.begin(); r != range.end(); ++r) {
                              const Block3 d = a.block(a.diagonal(r));
                              Block3& inv = m_inverse_blocks[static_cast<std::size_t>(r)];
                              if (kind == PcgPreconditioner::BLOCK_JACOBI)
                                  inv = d.inverse();
                              else
                                  inv = d.diagonal().cwiseInverse().asDiagonal();
                          }
                      });
}

void PcgSolver::apply_preconditioner(CRef<VecX> r, Eigen::Ref<VecX> z) const
{
    const auto n = static_cast<Index>(m_inverse_blocks.size());
    tbb::parallel_for(tbb::blocked_range<Index>(0, n, PRECONDITIONER_GRAIN),
                      [&](const tbb::blocked_range<Index>& range) {
                          for (Index i = range.begin(); i != range.end(); ++i)
                              z.segment<3>(3 * i) = m_inverse_blocks[static_cast<std::size_t>(i)] *
                                                    r.segment<3>(3 * i);
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
    xpby(b, -1.0, m_r); // r = b − A x
    double r_norm = norm(m_r);
    apply_preconditioner(m_r, m_z);
    m_p = m_z;
    double rz = dot(m_r, m_z);

    const double target = settings.tolerance * b_norm;
    Index iteration = 0;
    while (r_norm > target && iteration < settings.max_iterations) {
        a.multiply(m_p, m_q);
        const double pq = dot(m_p, m_q);
        CORO_CHECK(pq > 0.0, NumericalError,
                   "PCG: pᵀAp = " << pq << " at iteration " << iteration
                                  << " (the system matrix is not positive definite)");
        const double alpha = rz / pq;
        axpy(alpha, m_p, x);
        axpy(-alpha, m_q, m_r);
        ++iteration;
        r_norm = norm(m_r);
        if (r_norm <= target)
            break;
        apply_preconditioner(m_r, m_z);
        const double rz_next = dot(m_r, m_z);
        xpby(m_z, rz_next / rz, m_p);
        rz = rz_next;
    }
    result.iterations = iteration;
    result.residual = r_norm / b_norm;
    result.converged = r_norm <= target;
    return result;
}

} // namespace coro
