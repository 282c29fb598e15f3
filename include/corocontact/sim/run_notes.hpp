#pragma once
/// @file run_notes.hpp
/// @brief What a run tells its user besides the numbers: settings it does not apply (at load)
/// and results that depend on a cap rather than on convergence (at the end).

#include <corocontact/sim/case_spec.hpp>
#include <corocontact/sim/simulation.hpp>

#include <optional>
#include <string>

namespace coro {

/// True when contact is detected and applied: [contact] enabled in a dynamic analysis. Static
/// analysis solves each body's load steps alone and does not detect contact at all.
bool contact_applies(const CaseSpec& spec);

/// The note for a case whose [contact] table is enabled but not applied (static analysis), to
/// show at load; nothing otherwise.
std::optional<std::string> contact_not_applied_note(const CaseSpec& spec);

/// A warning when more than a tenth of the run's PCG solves stopped at solver.max_iterations
/// instead of reaching solver.tolerance: how many, their mean relative residual, and what to
/// change. Nothing when tolerance = 0, which asks for the cap on every solve.
/// @param[in] summary  a finished run's summary (means, not sums)
std::optional<std::string> iteration_cap_warning(const RunSummary& summary, const SolverSettings& solver);

} // namespace coro
