#pragma once
/// @file contact_step.hpp
/// @brief One linearly implicit Euler step of all bodies with contact terms: bodies that
/// contact couples are solved together as one system, so contact forces stay equal and
/// opposite through the implicit solve (momentum is conserved to the solver tolerance).

#include <corocontact/sim/body.hpp>
#include <corocontact/sim/contact_response.hpp>
#include <corocontact/sim/phase_times.hpp>
#include <corocontact/solver/pcg.hpp>

#include <vector>

namespace coro {

/// Advances every body by one step: (M + hC + h²K' + contact terms) v⁺ = M v + h (f_ext + f0 − K'x
/// + f_contact), x⁺ = x + h v⁺. Groups of bodies joined by contact terms share one PCG solve
/// (their matrices merged, coupling blocks added); other bodies are solved alone.
/// @return one PCG outcome per solve (group), in order of the group's first body
/// @throws NumericalError naming the body when a value becomes non-finite
std::vector<PcgResult> implicit_euler_step_with_contact(std::vector<Body>& bodies, const ContactResponse& response,
                                                        double dt, const Vec3& gravity, const PcgSettings& settings,
                                                        PhaseTimes& times);

} // namespace coro
