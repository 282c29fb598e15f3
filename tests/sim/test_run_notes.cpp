#include <corocontact/sim/run_notes.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

using namespace coro;
using ::testing::HasSubstr;

namespace {
RunSummary solves(Index total, Index at_cap, double residual_mean)
{
    RunSummary summary;
    summary.solves = total;
    summary.solves_not_converged = at_cap;
    summary.cg_residual_mean = residual_mean;
    return summary;
}

SolverSettings solver(double tolerance, PcgPreconditioner preconditioner = PcgPreconditioner::BLOCK_JACOBI)
{
    SolverSettings settings;
    settings.max_iterations = 10;
    settings.tolerance = tolerance;
    settings.preconditioner = preconditioner;
    return settings;
}
} // namespace

TEST(IterationCapWarning, NamesCountResidualAndRemedies)
{
    const auto warning = iteration_cap_warning(solves(353, 289, 0.97), solver(1e-6));
    ASSERT_TRUE(warning.has_value());
    EXPECT_THAT(*warning, HasSubstr("289 of 353 PCG solves stopped at solver.max_iterations = 10"));
    EXPECT_THAT(*warning, HasSubstr("solver.tolerance = 1e-06"));
    EXPECT_THAT(*warning, HasSubstr("mean relative residual of all solves 9.70e-01"));
    EXPECT_THAT(*warning, HasSubstr("Raise max_iterations"));
    EXPECT_THAT(*warning, HasSubstr("tolerance = 0"));
    EXPECT_THAT(*warning, ::testing::Not(HasSubstr("block_jacobi")));
}

TEST(IterationCapWarning, SuggestsBlockJacobiWhenRunningJacobi)
{
    const auto warning = iteration_cap_warning(solves(10, 10, 0.5), solver(1e-6, PcgPreconditioner::JACOBI));
    ASSERT_TRUE(warning.has_value());
    EXPECT_THAT(*warning, HasSubstr("preconditioner = \"block_jacobi\""));
}

TEST(IterationCapWarning, SilentUpToATenthOfTheSolves)
{
    EXPECT_FALSE(iteration_cap_warning(solves(100, 10, 0.1), solver(1e-6)).has_value());
    EXPECT_TRUE(iteration_cap_warning(solves(100, 11, 0.1), solver(1e-6)).has_value());
    EXPECT_FALSE(iteration_cap_warning(solves(0, 0, 0.0), solver(1e-6)).has_value());
}

TEST(IterationCapWarning, SilentWhenToleranceZeroAsksForTheCap)
{
    EXPECT_FALSE(iteration_cap_warning(solves(100, 100, 1e-3), solver(0.0)).has_value());
}

TEST(ContactNotAppliedNote, OnlyForStaticAnalysisWithContactEnabled)
{
    CaseSpec spec;
    spec.file = "case.toml";
    spec.contact.enabled = true;
    spec.simulation.analysis = Analysis::DYNAMIC;
    EXPECT_TRUE(contact_applies(spec));
    EXPECT_FALSE(contact_not_applied_note(spec).has_value());

    spec.simulation.analysis = Analysis::STATIC;
    EXPECT_FALSE(contact_applies(spec));
    const auto note = contact_not_applied_note(spec);
    ASSERT_TRUE(note.has_value());
    EXPECT_THAT(*note, HasSubstr("case.toml: note: contact.enabled = true is not applied in static analysis"));

    spec.contact.enabled = false;
    EXPECT_FALSE(contact_applies(spec));
    EXPECT_FALSE(contact_not_applied_note(spec).has_value());
}
