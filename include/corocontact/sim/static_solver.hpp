#pragma once
/// @file static_solver.hpp
/// @brief Static equilibrium of the co-rotational model under a fraction of the load, by
/// Newton's method with the consistent tangent and a line search.
///
/// Each iteration evaluates the residual r = λ(f_ext + M g) + f(x) (f the co-rotational
/// internal force with rotations R(x), fixed nodes projected), solves K_T Δx = r by PCG with
/// the consistent tangent K_T = −∂f/∂x (fem/corotational_tangent.hpp), and moves to x + αΔx.
///
/// - Tangent: the EXACT one (the Hessian of the co-rotated energy; symmetric, and positive
///   definite unless compression is strong), so a load step converges quadratically. Where PCG
///   meets negative curvature, or the step is no descent direction of the potential
///   Ψ(x) − λ f_ext·x, the iteration is redone with the PROJECTED tangent (⪰ K', positive
///   definite), which converges linearly but always descends.
/// - Line search: on the potential's slope s(α) = Δx·r(x + αΔx) along the step (Crisfield
///   1991, "Non-linear finite element analysis of solids and structures", vol. 1): the full
///   step is taken when |s(1)| ≤ ½ s(0), as it is near the solution; after an overshoot, α is
///   the zero of the secant through s(0) and s(α).
/// - Inexact Newton: each solve's PCG tolerance is the Eisenstat–Walker forcing term (choice
///   2, "Choosing the forcing terms in an inexact Newton method", 1996), loose far from the
///   solution and never tighter than the static tolerance still needs from the step nor than
///   solver.tolerance.
///
/// Stops when ‖r‖ ≤ static_tolerance · ‖reference force‖.

#include <corocontact/sim/body.hpp>
#include <corocontact/sim/phase_times.hpp>
#include <corocontact/solver/pcg.hpp>

namespace coro {

/// Outcome of one load step; non-convergence is data.
struct StaticResult {
    bool converged = false;
    Index iterations = 0;           ///< Newton iterations done
    double residual = 0.0;          ///< final ‖r‖ / ‖reference force‖
    Index solves = 0;               ///< PCG solves (one per iteration, two when it was redone)
    Index cg_iterations = 0;        ///< PCG iterations summed over the solves
    double cg_residual_sum = 0.0;   ///< PCG relative residual after each solve, summed
    Index solves_not_converged = 0; ///< solves that stopped at the PCG cap
    Index projected_steps = 0;      ///< iterations redone with the projected tangent
    Index line_search_cuts = 0;     ///< Newton steps shortened by the line search
};

/// Iterates body.positions() to equilibrium with load_factor × (box loads + gravity).
/// The reference force is the scaled load, or, when that is zero (prescribed displacements
/// only), the internal force at the start.
/// @param[in] settings        PCG settings of the tangent solves (Δx starts from zero);
///                            `tolerance` is the tightest relative tolerance used
/// @param[in] tolerance       relative residual to reach, > 0
/// @param[in] max_iterations  Newton iterations allowed, ≥ 1
/// @throws NumericalError naming the body when a value becomes non-finite
StaticResult solve_static(Body& body, double load_factor, const Vec3& gravity,
                          const PcgSettings& settings, double tolerance, Index max_iterations,
                          PhaseTimes& times);

} // namespace coro
