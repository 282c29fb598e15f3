#include <corocontact/solver/pcg.hpp>

#include <corocontact/core/error.hpp>

#include "detail/lane_sums.hpp"

#include <algorithm>
#include <cmath>

namespace coro {

namespace {
std::size_t at(Index i) { return static_cast<std::size_t>(i); }

/// A component stops at ‖r‖ ≤ max(tolerance, RESIDUAL_FLOOR)·‖b‖. Below the floor the recursive
/// residual is far under what double precision resolves in x, and its squares head for
/// underflow, where pᵀAp would read 0 and look like a matrix that is not positive definite.
constexpr double RESIDUAL_FLOOR = 1e-30;
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

void PcgSolver::sum_by_component(const SceneMatrix& a, const std::vector<double>& partials, int width, bool all)
{
    m_totals.assign(m_components.size() * static_cast<std::size_t>(width), 0.0);
    if (m_exchange) {
        m_exchange->sum_by_component(partials.data(), width, m_totals.data());
        return;
    }
    for (Index c = 0; c < a.chunks().num_chunks(); ++c) {
        const auto k = at(a.chunk_component(c));
        if (!all && !m_components[k].active)
            continue;
        for (int j = 0; j < width; ++j)
            m_totals[k * static_cast<std::size_t>(width) + static_cast<std::size_t>(j)] +=
                partials[at(c) * static_cast<std::size_t>(width) + static_cast<std::size_t>(j)];
    }
}

void PcgSolver::mark_active_chunks(const SceneMatrix& a)
{
    for (Index c = 0; c < a.chunks().num_chunks(); ++c)
        m_chunk_active[at(c)] = m_components[at(a.chunk_component(c))].active ? 1 : 0;
}

void PcgSolver::copy_rows(const SceneMatrix& a, const double* from, double* to)
{
    for_each_chunk(a.chunks(), [&](Index, Index row_begin, Index row_end) {
        std::copy(from + 3 * static_cast<std::ptrdiff_t>(row_begin), from + 3 * static_cast<std::ptrdiff_t>(row_end),
                  to + 3 * static_cast<std::ptrdiff_t>(row_begin));
    });
}

void PcgSolver::multiply(const SceneMatrix& a, double* x, double* y, double* chunk_dots)
{
    if (m_exchange)
        m_exchange->update_ghosts(x);
    a.multiply(x, y, chunk_dots, m_chunk_active.data());
}

void PcgSolver::residual_pass(const SceneMatrix& a, const double* b, double* x)
{
    double* r = m_r.data();
    double* z = m_z.data();
    const double* p = m_p.data();
    const double* q = m_q.data();
    Preconditioner& preconditioner = *m_preconditioner;
    const bool local = preconditioner.is_chunk_local();
    const auto chunk_sums = [&](Index c, std::ptrdiff_t begin, std::ptrdiff_t end) {
        detail::lane_dots(r + begin, z + begin, end - begin, m_partials[2 * at(c)], m_partials[2 * at(c) + 1]);
    };
    for_each_chunk(a.chunks(), [&](Index c, Index row_begin, Index row_end) {
        if (!m_chunk_active[at(c)])
            return;
        const std::ptrdiff_t begin = 3 * static_cast<std::ptrdiff_t>(row_begin);
        const std::ptrdiff_t end = 3 * static_cast<std::ptrdiff_t>(row_end);
        if (b) {
            for (std::ptrdiff_t i = begin; i < end; ++i)
                r[i] = b[i] - r[i];
        } else {
            const double alpha = m_components[at(a.chunk_component(c))].alpha;
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
    if (local)
        return;
    // Block diagonal by component: z of a stopped component is rewritten from its unchanged r
    // and never read.
    preconditioner.apply(r, z);
    for_each_chunk(a.chunks(), [&](Index c, Index row_begin, Index row_end) {
        if (m_chunk_active[at(c)])
            chunk_sums(c, 3 * static_cast<std::ptrdiff_t>(row_begin), 3 * static_cast<std::ptrdiff_t>(row_end));
    });
}

void PcgSolver::direction_pass(const SceneMatrix& a)
{
    double* p = m_p.data();
    const double* z = m_z.data();
    for_each_chunk(a.chunks(), [&](Index c, Index row_begin, Index row_end) {
        if (!m_chunk_active[at(c)])
            return;
        const double beta = m_components[at(a.chunk_component(c))].beta;
        for (std::ptrdiff_t i = 3 * static_cast<std::ptrdiff_t>(row_begin); i < 3 * static_cast<std::ptrdiff_t>(row_end);
             ++i)
            p[i] = z[i] + beta * p[i];
    });
}

PcgResult PcgSolver::solve(const BsrMatrix& a, CRef<VecX> b, Eigen::Ref<VecX> x, const PcgSettings& settings)
{
    return solve(SceneMatrix({&a}), b, x, settings);
}

PcgResult PcgSolver::solve(const SceneMatrix& a, CRef<VecX> b, Eigen::Ref<VecX> x, const PcgSettings& settings,
                           SceneExchange* exchange)
{
    const Index n = a.num_dofs();
    CORO_ASSERT(b.size() == n && x.size() == n);
    const double stop = std::max(settings.tolerance, RESIDUAL_FLOOR);
    const RowChunks& chunks = a.chunks();
    m_r.resize(n);
    m_z.resize(n);
    m_exchange = exchange;
    m_p.resize(n + (exchange ? 3 * exchange->num_ghost_rows() : 0));
    m_q.resize(n);
    m_partials.resize(2 * at(chunks.num_chunks()));
    m_chunk_active.assign(at(chunks.num_chunks()), 1);
    // Components come and go with contact, never more than one per body: room for that many
    // keeps a solve free of allocations when they change.
    m_components.reserve(at(a.num_bodies()));
    m_totals.reserve(2 * at(a.num_bodies()));
    m_components.assign(at(a.num_components()), Component{});

    // ‖b_k‖ per component; a component with b_k = 0 has the solution 0 and takes no iteration.
    for_each_chunk(chunks, [&](Index c, Index begin, Index end) {
        m_partials[at(c)] = b.segment(3 * begin, 3 * (end - begin)).squaredNorm();
    });
    sum_by_component(a, m_partials, 1, true);
    bool any_zero = false;
    for (std::size_t k = 0; k < m_components.size(); ++k) {
        Component& component = m_components[k];
        component.b_norm = std::sqrt(m_totals[k]);
        CORO_CHECK(std::isfinite(component.b_norm), NumericalError,
                   "PCG: the right-hand side is not finite (‖b‖ = " << component.b_norm << ")");
        component.active = component.b_norm > 0.0;
        any_zero = any_zero || !component.active;
    }
    if (any_zero) {
        mark_active_chunks(a);
        for_each_chunk(chunks, [&](Index c, Index begin, Index end) {
            if (!m_chunk_active[at(c)])
                x.segment(3 * begin, 3 * (end - begin)).setZero();
        });
    }
    prepare_preconditioner(a, settings);

    // r = b − A x, z = M⁻¹ r, p = z.
    mark_active_chunks(a);
    copy_rows(a, x.data(), m_p.data()); // x has no ghost rows: multiply a copy that has
    multiply(a, m_p.data(), m_r.data(), nullptr);
    residual_pass(a, b.data(), x.data());
    sum_by_component(a, m_partials, 2, false);
    for (std::size_t k = 0; k < m_components.size(); ++k) {
        Component& component = m_components[k];
        if (!component.active)
            continue;
        const double rr = m_totals[2 * k], rz = m_totals[2 * k + 1];
        CORO_CHECK(std::isfinite(rr) && std::isfinite(rz), NumericalError,
                   "PCG: the initial residual is not finite (rᵀr = " << rr << ", rᵀz = " << rz << ")");
        component.r_norm = std::sqrt(rr);
        component.initial_r_norm = component.r_norm;
        component.rz = rz;
        component.active = component.r_norm > stop * component.b_norm && settings.max_iterations > 0;
    }
    copy_rows(a, m_z.data(), m_p.data());

    for (;;) {
        mark_active_chunks(a);
        if (std::none_of(m_components.begin(), m_components.end(), [](const Component& c) { return c.active; }))
            break;
        multiply(a, m_p.data(), m_q.data(), m_partials.data());
        sum_by_component(a, m_partials, 1, false);
        for (std::size_t k = 0; k < m_components.size(); ++k) {
            Component& component = m_components[k];
            if (!component.active)
                continue;
            const double pq = m_totals[k];
            CORO_CHECK(pq > 0.0, NumericalError,
                       "PCG: pᵀAp = " << pq << " at iteration " << component.iterations
                                      << " (the system matrix is not positive definite)");
            component.alpha = component.rz / pq;
        }
        residual_pass(a, nullptr, x.data()); // x += αp, r −= αq, z = M⁻¹ r
        sum_by_component(a, m_partials, 2, false);
        for (std::size_t k = 0; k < m_components.size(); ++k) {
            Component& component = m_components[k];
            if (!component.active)
                continue;
            const double rr = m_totals[2 * k], rz = m_totals[2 * k + 1];
            CORO_CHECK(std::isfinite(rr) && std::isfinite(rz), NumericalError,
                       "PCG: the residual is not finite at iteration " << component.iterations);
            ++component.iterations;
            component.r_norm = std::sqrt(rr);
            if (component.r_norm <= stop * component.b_norm ||
                component.iterations >= settings.max_iterations) {
                component.active = false;
                continue;
            }
            component.beta = rz / component.rz;
            component.rz = rz;
        }
        mark_active_chunks(a);
        direction_pass(a);
    }

    PcgResult result;
    result.converged = true;
    for (const Component& component : m_components) {
        const double residual = component.b_norm > 0.0 ? component.r_norm / component.b_norm : 0.0;
        result.iterations = std::max(result.iterations, component.iterations);
        result.residual = std::max(result.residual, residual);
        result.converged = result.converged && residual <= stop;
    }
    // The hierarchy's quality is judged by the component that ran longest.
    const auto slowest = std::max_element(m_components.begin(), m_components.end(),
                                          [](const Component& l, const Component& r) { return l.iterations < r.iterations; });
    if (slowest != m_components.end() && slowest->initial_r_norm > 0.0)
        m_preconditioner->record_solve(slowest->iterations, slowest->r_norm / slowest->initial_r_norm);
    return result;
}

} // namespace coro
