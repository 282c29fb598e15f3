#include <corocontact/sim/static_solver.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/fem/corotational_tangent.hpp>
#include <corocontact/solver/scene_matrix.hpp>
#include <corocontact/solver/vector_ops.hpp>

#include <algorithm>
#include <cmath>

namespace coro {

namespace {
// Line search: the full step is kept when the potential's slope along it has fallen to this
// fraction of its start (Crisfield's tolerance); at most this many steps are tried, and a
// shortened step stays within these fractions of the one it replaces.
constexpr double SLOPE_RATIO = 0.5;
constexpr int MAX_TRIALS = 5;
constexpr double MIN_CUT = 0.1;
constexpr double MAX_CUT = 0.9;

// Relative PCG tolerance of each tangent solve (Eisenstat & Walker 1996, choice 2 with
// γ = 0.9, α = 2 and their safeguard): loose while Newton is far from the solution, tighter as
// it converges quadratically, never tighter than what the static tolerance still asks for from
// this step, and never looser than η_max or tighter than the user's solver.tolerance.
class ForcingTerm {
public:
    ForcingTerm(double static_tolerance, double pcg_tolerance)
        : m_static_tolerance(static_tolerance), m_pcg_tolerance(pcg_tolerance)
    {
    }
    /// @param[in] residual  the relative static residual before the solve
    double next(double residual)
    {
        if (m_previous > 0.0) {
            const double ratio = residual / m_previous;
            double eta = GAMMA * ratio * ratio;
            if (GAMMA * m_eta * m_eta > SAFEGUARD)
                eta = std::max(eta, GAMMA * m_eta * m_eta);
            m_eta = std::min(eta, ETA_MAX);
        }
        m_previous = residual;
        return std::max({m_eta, 0.5 * m_static_tolerance / residual, m_pcg_tolerance});
    }

private:
    static constexpr double GAMMA = 0.9;
    static constexpr double SAFEGUARD = 0.1;
    static constexpr double ETA_MAX = 0.1;
    double m_static_tolerance;
    double m_pcg_tolerance;
    double m_eta = ETA_MAX;
    double m_previous = 0.0;
};
} // namespace

StaticResult solve_static(Body& body, double load_factor, const Vec3& gravity,
                          const PcgSettings& settings, double tolerance, Index max_iterations,
                          PhaseTimes& times)
{
    CorotationalFem& fem = body.fem();
    VecX& x = body.positions();
    const VecX& masses = fem.lumped_masses();

    VecX load = body.load_forces();
    for (Eigen::Index v = 0; v < masses.size(); ++v)
        load.segment<3>(3 * v) += masses[v] * gravity;
    load *= load_factor;
    body.project_fixed(load);

    // r(x) = load + f(x), fixed nodes projected, with the rotations updated to x.
    const auto residual_at = [&](CRef<VecX> at, VecX& r) {
        {
            ScopedTimer timer(times.rotation);
            fem.update_rotations(at);
        }
        ScopedTimer timer(times.assembly);
        fem.internal_forces(at, r);
        r += load;
        body.project_fixed(r);
    };
    StaticResult result;
    CorotationalTangent tangent(fem);
    SceneMatrix system({&body.system_matrix()}); // with the node positions AMG needs
    system.set_node_positions({&x});
    PcgSettings solve_settings = settings;
    // Δx = K_T⁻¹ r; false if PCG met negative curvature (it throws NumericalError on pᵀAp ≤ 0).
    const auto solve_step = [&](TangentDefiniteness kind, CRef<VecX> r, VecX& step, bool may_fail) {
        {
            ScopedTimer timer(times.assembly);
            tangent.assemble(fem, x, body.fixed(), kind, body.system_matrix());
        }
        ScopedTimer timer(times.solve);
        step.setZero();
        PcgResult solve;
        try {
            solve = body.pcg().solve(system, r, step, solve_settings);
        } catch (const NumericalError&) {
            if (!may_fail)
                throw;
            return false;
        }
        ++result.solves;
        result.cg_iterations += solve.iterations;
        result.cg_residual_sum += solve.residual;
        result.solves_not_converged += solve.converged ? 0 : 1;
        return true;
    };

    VecX residual(x.size()), step(x.size()), trial(x.size()), trial_residual(x.size());
    residual_at(x, residual);
    double reference = norm(load);
    if (reference == 0.0)
        reference = norm(residual);
    ForcingTerm forcing(tolerance, settings.tolerance);
    for (Index iteration = 0;; ++iteration) {
        result.residual = reference > 0.0 ? norm(residual) / reference : 0.0;
        CORO_CHECK(std::isfinite(result.residual), NumericalError,
                   "body '" << body.name() << "': static residual is not finite at Newton iteration " << iteration);
        result.iterations = iteration;
        if (result.residual <= tolerance) {
            result.converged = true;
            break;
        }
        if (iteration >= max_iterations)
            break;

        // The exact tangent, unless it is indefinite here: then the projected one, which is
        // positive definite and gives a descent direction.
        solve_settings.tolerance = forcing.next(result.residual);
        if (!solve_step(TangentDefiniteness::EXACT, residual, step, true) || !(dot(step, residual) > 0.0)) {
            solve_step(TangentDefiniteness::PROJECTED, residual, step, false);
            ++result.projected_steps;
        }

        // Line search on the slope s(α) = Δx·r(x + αΔx) of the potential along the step.
        const double slope0 = dot(step, residual);
        double alpha = 1.0;
        for (int t = 1;; ++t) {
            trial = x + alpha * step;
            residual_at(trial, trial_residual);
            const double slope = dot(step, trial_residual);
            if (!(slope0 > 0.0) || std::abs(slope) <= SLOPE_RATIO * slope0 || slope > 0.0 || t == MAX_TRIALS)
                break; // converging, no descent left to find (PCG stopped early), still descending, or out of trials
            alpha *= std::clamp(slope0 / (slope0 - slope), MIN_CUT, MAX_CUT);
        }
        result.line_search_cuts += alpha < 1.0 ? 1 : 0;
        x.swap(trial);
        residual.swap(trial_residual);
    }
    return result;
}

} // namespace coro
