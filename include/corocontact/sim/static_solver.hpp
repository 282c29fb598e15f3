#pragma once
/// @file static_solver.hpp
/// @brief Static equilibrium of the co-rotational model under a fraction of the load.
///
/// Each iteration updates the rotations from the current positions, evaluates the residual
/// r = λ(f_ext + M g) + f0 − K'x and solves K' Δx = r by PCG (fixed nodes projected),
/// until ‖r‖ ≤ static_tolerance · ‖reference force‖.

#include <corocontact/sim/body.hpp>
#include <corocontact/sim/phase_times.hpp>
#include <corocontact/solver/pcg.hpp>

namespace coro {

/// Outcome of one load step; non-convergence is data.
struct StaticResult {
    bool converged = false;
    Index iterations = 0;      ///< co-rotation updates done
    Index cg_iterations = 0;   ///< PCG iterations summed over them
    double residual = 0.0;     ///< final ‖r‖ / ‖reference force‖
};

/// Iterates body.positions() to equilibrium with load_factor × (box loads + gravity).
/// The reference force is the scaled load, or, when that is zero (prescribed displacements
/// only), the internal force at the first iteration.
/// @param[in] tolerance       relative residual to reach, > 0
/// @param[in] max_iterations  co-rotation updates allowed, ≥ 1
/// @throws NumericalError naming the body when a value becomes non-finite
StaticResult solve_static(Body& body, double load_factor, const Vec3& gravity,
                          const PcgSettings& settings, double tolerance, Index max_iterations,
                          PhaseTimes& times);

} // namespace coro
