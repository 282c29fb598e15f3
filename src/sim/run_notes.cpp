#include <corocontact/sim/run_notes.hpp>

#include <cstdio>
#include <sstream>

namespace coro {

bool contact_applies(const CaseSpec& spec)
{
    return spec.contact.enabled && spec.simulation.analysis == Analysis::DYNAMIC;
}

std::optional<std::string> contact_not_applied_note(const CaseSpec& spec)
{
    if (!spec.contact.enabled || contact_applies(spec))
        return std::nullopt;
    return spec.file.string() +
           ": note: contact.enabled = true is not applied in static analysis: each body is solved "
           "alone, contact is not detected and contact_force stays zero (use analysis = \"dynamic\" for contact)";
}

std::optional<std::string> iteration_cap_warning(const RunSummary& summary, const SolverSettings& solver)
{
    if (solver.tolerance == 0.0 || summary.solves == 0 || 10 * summary.solves_not_converged <= summary.solves)
        return std::nullopt;
    char residual[32], tolerance[32];
    std::snprintf(residual, sizeof residual, "%.2e", summary.cg_residual_mean);
    std::snprintf(tolerance, sizeof tolerance, "%.2g", solver.tolerance);
    std::ostringstream out;
    out << "warning: " << summary.solves_not_converged << " of " << summary.solves
        << " PCG solves stopped at solver.max_iterations = " << solver.max_iterations
        << " before reaching solver.tolerance = " << tolerance << " (mean relative residual of all solves " << residual
        << "), so the results depend on the cap. Raise max_iterations";
    if (solver.preconditioner == PcgPreconditioner::JACOBI)
        out << ", use preconditioner = \"block_jacobi\"";
    out << ", or set tolerance = 0 to run the cap on every solve on purpose";
    return out.str();
}

} // namespace coro
