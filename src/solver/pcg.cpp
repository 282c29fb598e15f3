#include <corocontact/solver/pcg.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/solver/vector_ops.hpp>

#include <cmath>

namespace coro {

namespace {
std::size_t at(Index i) { return static_cast<std::size_t>(i); }
} // namespace

void PcgSolver::prepare_preconditioner(const SceneMatrix& a, const PcgSettings& settings)
{
    if (!m_preconditioner || settings.preconditioner != m_kind) {
        m_preconditioner = make_preconditioner(settings.preconditioner, settings.amg);
        m_kind = settings.preconditioner;
    }
    m_preconditioner->prepare(a);
}

PreconditionerTimes PcgSolver::preconditioner_times() const
{
    return m_preconditioner ? m_preconditioner->times() : PreconditionerTimes{};
}

double PcgSolver::sum_chunks(const std::vector<double>& chunk_dots) const
{
    double sum = 0.0;
    for (const double d : chunk_dots)
        sum += d;
    return sum;
}

PcgSolver::Sums PcgSolver::residual_pass(const RowChunks& chunks, const double* b, double alpha, double* x)
{
    double* r = m_r.data();
    double* z = m_z.data();
    const double* p = m_p.data();
    const double* q = m_q.data();
    Preconditioner& preconditioner = *m_preconditioner;
    const bool local = preconditioner.is_chunk_local();
    const auto chunk_sums = [&](Index c, std::ptrdiff_t begin, std::ptrdiff_t end) {
        Sums sums;
        for (std::ptrdiff_t i = begin; i < end; ++i) {
            sums.rr += r[i] * r[i];
            sums.rz += r[i] * z[i];
        }
        m_chunk_sums[at(c)] = sums;
    };
    for_each_chunk(chunks, [&](Index c, Index row_begin, Index row_end) {
        const std::ptrdiff_t begin = 3 * static_cast<std::ptrdiff_t>(row_begin);
        const std::ptrdiff_t end = 3 * static_cast<std::ptrdiff_t>(row_end);
        if (b) {
            for (std::ptrdiff_t i = begin; i < end; ++i)
                r[i] = b[i] - r[i];
        } else {
            for (std::ptrdiff_t i = begin; i < end; ++i) {
                x[i] += alpha * p[i];
                r[i] -= alpha * q[i];
            }
        }
        if (!local)
            return;
        preconditioner.apply_rows(row_begin, row_end, r, z);
        chunk_sums(c, begin, end);
    });
    if (!local) {
        preconditioner.apply(r, z);
        for_each_chunk(chunks, [&](Index c, Index row_begin, Index row_end) {
            chunk_sums(c, 3 * static_cast<std::ptrdiff_t>(row_begin), 3 * static_cast<std::ptrdiff_t>(row_end));
        });
    }
    Sums total;
    for (const Sums& sums : m_chunk_sums) {
        total.rr += sums.rr;
        total.rz += sums.rz;
    }
    return total;
}

PcgResult PcgSolver::solve(const BsrMatrix& a, CRef<VecX> b, Eigen::Ref<VecX> x, const PcgSettings& settings)
{
    return solve(SceneMatrix({&a}), b, x, settings);
}

PcgResult PcgSolver::solve(const SceneMatrix& a, CRef<VecX> b, Eigen::Ref<VecX> x, const PcgSettings& settings)
{
    const Index n = a.num_dofs();
    CORO_ASSERT(b.size() == n && x.size() == n);
    const RowChunks& chunks = a.chunks();
    m_r.resize(n);
    m_z.resize(n);
    m_p.resize(n);
    m_q.resize(n);
    m_chunk_dots.resize(at(chunks.num_chunks()));
    m_chunk_sums.resize(at(chunks.num_chunks()));

    PcgResult result;
    for_each_chunk(chunks, [&](Index c, Index begin, Index end) {
        m_chunk_dots[at(c)] = b.segment(3 * begin, 3 * (end - begin)).squaredNorm();
    });
    const double b_norm = std::sqrt(sum_chunks(m_chunk_dots));
    CORO_CHECK(std::isfinite(b_norm), NumericalError, "PCG: the right-hand side is not finite (‖b‖ = " << b_norm << ")");
    if (b_norm == 0.0) {
        x.setZero();
        result.converged = true;
        return result;
    }
    prepare_preconditioner(a, settings);

    a.multiply(x.data(), m_r.data(), nullptr);
    Sums sums = residual_pass(chunks, b.data(), 0.0, x.data()); // r = b − A x, z = M⁻¹ r
    CORO_CHECK(std::isfinite(sums.rr) && std::isfinite(sums.rz), NumericalError,
               "PCG: the initial residual is not finite (rᵀr = " << sums.rr << ", rᵀz = " << sums.rz << ")");
    double r_norm = std::sqrt(sums.rr);
    const double initial_norm = r_norm;
    double rz = sums.rz;
    m_p = m_z;

    const double target = settings.tolerance * b_norm;
    Index iteration = 0;
    while (r_norm > target && iteration < settings.max_iterations) {
        a.multiply(m_p.data(), m_q.data(), m_chunk_dots.data());
        const double pq = sum_chunks(m_chunk_dots);
        CORO_CHECK(pq > 0.0, NumericalError,
                   "PCG: pᵀAp = " << pq << " at iteration " << iteration
                                  << " (the system matrix is not positive definite)");
        const double alpha = rz / pq;
        sums = residual_pass(chunks, nullptr, alpha, x.data()); // x += αp, r −= αq, z = M⁻¹ r
        CORO_CHECK(std::isfinite(sums.rr) && std::isfinite(sums.rz), NumericalError,
                   "PCG: the residual is not finite at iteration " << iteration);
        ++iteration;
        r_norm = std::sqrt(sums.rr);
        if (r_norm <= target)
            break;
        xpby(m_z, sums.rz / rz, m_p);
        rz = sums.rz;
    }
    m_preconditioner->record_solve(iteration, initial_norm > 0.0 ? r_norm / initial_norm : 0.0);
    result.iterations = iteration;
    result.residual = r_norm / b_norm;
    result.converged = r_norm <= target;
    return result;
}

} // namespace coro
