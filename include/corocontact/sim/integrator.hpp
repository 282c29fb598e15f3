#pragma once
/// @file integrator.hpp
/// @brief Linearly implicit Euler with the rotations frozen at the start of the step.
///
///   (M + hC + h²K') v⁺ = M v + h (f_ext + f0 − K' x),   x⁺ = x + h v⁺,   C = αM + βK'
///
/// solved by PCG warm-started from v; fixed nodes are projected out (v⁺ = 0 there).

#include <corocontact/sim/body.hpp>
#include <corocontact/sim/phase_times.hpp>
#include <corocontact/solver/pcg.hpp>

namespace coro {

/// Prepares one body's step: rotations from the current positions, the system matrix
/// (M + hC + h²K', fixed nodes projected) in body.system_matrix(), and the right-hand side
/// M v + h (f_ext + m g + f0 − K'x + extra_forces) with fixed rows zeroed.
/// @param[in] extra_forces  #3V forces added for this step (contact), or empty for none [N]
/// @return the right-hand side, #3V
VecX assemble_implicit_euler(Body& body, double dt, const Vec3& gravity, const VecX& extra_forces, PhaseTimes& times);

/// Advances one body by one step.
/// @param[in,out] body    positions and velocities are updated
/// @param[in] dt          time step h [s], > 0
/// @param[in] gravity     acceleration [m/s²]
/// @param[in] settings    PCG cap, tolerance and preconditioner
/// @param[in,out] times   rotation/assembly/solve times are added
/// @return the PCG outcome (non-convergence within the cap is reported, not thrown)
/// @throws NumericalError naming the body and the tet or node when a value becomes non-finite
PcgResult implicit_euler_step(Body& body, double dt, const Vec3& gravity, const PcgSettings& settings,
                              PhaseTimes& times);

/// Kinetic energy ½ vᵀMv of a body [J].
double kinetic_energy(const Body& body);

} // namespace coro
