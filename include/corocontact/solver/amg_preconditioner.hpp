#pragma once
/// @file amg_preconditioner.hpp
/// @brief Algebraic multigrid for PCG on our block matrices: PETSc's smoothed-aggregation GAMG
/// with the rigid-body modes as near-null space (MatNullSpaceCreateRigidBody), and the rule
/// for reusing its hierarchy over steps.
///
/// Why GAMG (tools/bench_amg.cpp, numbers in docs/solver.md): on the SOFA beam's implicit Euler
/// system (58k unknowns) solved to 1e-6 it needs 14–16 CG iterations, about 0.6 of the time of
/// our Jacobi-PCG (410–424 iterations) and 0.7–0.9 of hypre BoomerAMG's best variant here
/// (systems with aggressive coarsening, 14 iterations); its setup costs three times hypre's
/// but is reused over steps (a 20-step-old hierarchy needs 18 iterations). The rigid-body
/// near-null space comes from node coordinates, which serves any number of bodies at once:
/// aggregates never span bodies that do not couple.
///
/// Determinism: the hierarchy and the V-cycle run in this process on one thread (the PETSc
/// build has no threads), so z = M⁻¹r does not depend on the TBB thread count, and two setups
/// of the same matrix give the same bits.
///
/// PETSc is initialised on first use (no signal handlers, errors returned, not printed) and
/// finalised at exit. Not thread-safe: one thread at a time may call into any
/// AmgPreconditioner.

#include <corocontact/solver/bsr_matrix.hpp>

#include <algorithm>
#include <memory>

namespace coro {

/// Wall time spent in setups and V-cycles, and how many ran.
struct AmgTimes {
    double setup_s = 0.0;
    double apply_s = 0.0;
    Index setups = 0;
    Index applies = 0;
};

class AmgPreconditioner {
public:
    AmgPreconditioner();
    ~AmgPreconditioner();
    AmgPreconditioner(AmgPreconditioner&&) noexcept;
    AmgPreconditioner& operator=(AmgPreconditioner&&) noexcept;
    AmgPreconditioner(const AmgPreconditioner&) = delete;
    AmgPreconditioner& operator=(const AmgPreconditioner&) = delete;

    /// Builds the hierarchy of `a`: symmetric positive definite, in upper storage (expanded to
    /// every entry here) or general. The first setup fixes the pattern; later setups with the
    /// same pattern refill the values in place, another pattern starts afresh.
    /// @param[in] a          #N×#N blocks of 3×3
    /// @param[in] positions  #3N node positions [m]: their three translations and three
    ///                       rotations are the near-null space
    /// @throws std::invalid_argument if the sizes differ
    /// @throws NumericalError with PETSc's message if PETSc fails
    void setup(const BsrMatrix& a, CRef<VecX> positions);

    /// True after a successful setup().
    bool ready() const;

    /// z = M⁻¹ r: one V-cycle of the hierarchy of the last setup (symmetric, so PCG may use it).
    /// @param[in] r   #3N
    /// @param[out] z  #3N, must not alias r
    /// @throws std::logic_error before the first setup; NumericalError if PETSc fails
    void apply(CRef<VecX> r, Eigen::Ref<VecX> z);

    const AmgTimes& times() const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

/// When to rebuild a reused hierarchy. The matrix changes a little every step (rotations,
/// contact), and the hierarchy of an older matrix preconditions it a little worse: the first
/// solve after a setup sets the baseline, and a solve needing more than `growth` × that many
/// iterations asks for a new setup before the next solve.
class HierarchyReuse {
public:
    /// @param[in] growth  > 1
    explicit HierarchyReuse(double growth = 1.5) : m_growth(growth) {}

    /// True before the first setup and after a solve grew past the limit.
    bool setup_due() const { return m_due; }
    /// A setup was done: the next solve sets the baseline.
    void record_setup()
    {
        m_due = false;
        m_baseline = -1;
    }
    /// A solve preconditioned by the current hierarchy took `iterations`.
    void record_solve(Index iterations)
    {
        if (m_baseline < 0)
            m_baseline = iterations;
        else if (static_cast<double>(iterations) > m_growth * static_cast<double>(std::max<Index>(m_baseline, 1)))
            m_due = true;
    }

private:
    double m_growth;
    bool m_due = true;
    Index m_baseline = -1;
};

} // namespace coro
