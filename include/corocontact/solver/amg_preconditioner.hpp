#pragma once
/// @file amg_preconditioner.hpp
/// @brief Algebraic multigrid for the scene PCG: PETSc's smoothed-aggregation GAMG with the
/// rigid-body modes as near-null space (MatNullSpaceCreateRigidBody), built from the whole
/// scene matrix (every body's blocks and the contact coupling written out as blocks), its hierarchy reused over
/// steps while it stays effective.
///
/// Why GAMG (tools/bench_amg.cpp, numbers in docs/solver.md): on the SOFA beam's implicit Euler
/// system it needs 14–18 CG iterations to 1e-6 where Jacobi needs ~400, and it ages well over
/// steps; hypre BoomerAMG's best variant here (systems with aggressive coarsening) sets up
/// faster but solves slower. The near-null space comes from node coordinates, which serves any
/// number of bodies at once (aggregates never span bodies that do not couple).
///
/// The finest level multiplies with the scene matrix itself (SceneMatrix::multiply: TBB threads,
/// upper storage, the matrix's own value precision, and always the current values); PETSc
/// holds a copy of the matrix from the last set-up only to build the coarser levels from and for
/// the smoother's diagonal. So between set-ups the smoothing and the residual on the finest level
/// are those of the current matrix, and only the coarse correction ages.
///
/// Determinism: the coarse levels run in this process on one thread (the PETSc build has no
/// threads) and the finest level's products do not depend on the thread count, so z = M⁻¹r is
/// bitwise the same for any thread count, and two set-ups of the same matrix give the same bits.
/// One process only: PETSc runs on PETSC_COMM_SELF here.
///
/// PETSc is initialised on first use (no signal handlers, errors returned, not printed) and
/// finalised at exit. Not thread-safe: one thread at a time may call into any
/// AmgPreconditioner.

#include <corocontact/solver/preconditioner.hpp>

#include <memory>

namespace coro {

/// When to rebuild a reused hierarchy. The matrix changes a little every step (rotations,
/// contact), and an older hierarchy preconditions it a little worse. Its quality is measured as
/// iterations per decade of residual reduction, which neither a better warm start nor an
/// iteration cap distorts: the first solve after a set-up sets the baseline, and a solve slower
/// than `growth` × the baseline asks for a new set-up before the next solve.
class HierarchyReuse {
public:
    /// @param[in] growth  > 1
    explicit HierarchyReuse(double growth = 1.5) : m_growth(growth) {}

    /// True before the first set-up and after a solve grew past the limit.
    bool setup_due() const { return m_due; }
    /// A set-up was done: the next solve sets the baseline.
    void record_setup()
    {
        m_due = false;
        m_baseline = -1.0;
    }
    /// A solve preconditioned by the current hierarchy took `iterations` and reduced the
    /// residual by `reduction` = ‖r_end‖/‖r_start‖.
    void record_solve(Index iterations, double reduction);

private:
    double m_growth;
    bool m_due = true;
    double m_baseline = -1.0; // iterations per decade of the first solve after the set-up
};

class AmgPreconditioner final : public Preconditioner {
public:
    explicit AmgPreconditioner(const AmgSettings& settings = {});
    ~AmgPreconditioner() override;
    AmgPreconditioner(const AmgPreconditioner&) = delete;
    AmgPreconditioner& operator=(const AmgPreconditioner&) = delete;

    /// Builds the hierarchy of `a` when none serves: before the first solve, after the reuse
    /// rule asked for one, or when the scene's rows changed; otherwise keeps the one it has.
    /// `a` needs node positions (SceneMatrix::set_node_positions).
    /// @throws std::invalid_argument if `a` has no node positions
    /// @throws NumericalError with PETSc's message if PETSc fails
    void prepare(const SceneMatrix& a) override;
    bool is_chunk_local() const override { return false; }
    /// One V-cycle (symmetric, so PCG may use it).
    /// @throws NumericalError if PETSc fails
    void apply(const double* r, double* z) override;
    void record_solve(Index iterations, double reduction) override;
    PreconditionerTimes times() const override;

    /// Rebuilds the hierarchy at the next prepare(), whatever the reuse rule says.
    void request_setup();

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

} // namespace coro
