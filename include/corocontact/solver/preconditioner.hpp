#pragma once
/// @file preconditioner.hpp
/// @brief z = M⁻¹ r inside the scene PCG: the interface the PCG calls, the kinds a case may
/// choose, and the factory that makes them.
///
/// A preconditioner is prepared once per solve from the solve's matrix and then applied once
/// per iteration. A chunk-local one (the diagonal kinds) maps a chunk's rows of r to the same
/// rows of z, so PCG applies it inside its own pass over the chunks; a global one (AMG) maps
/// the whole vector at once, between two such passes.

#include <corocontact/core/types.hpp>

#include <memory>

namespace coro {

class SceneMatrix;

enum class PcgPreconditioner {
    JACOBI,       ///< inverse of the diagonal entries
    BLOCK_JACOBI, ///< inverse of the 3×3 diagonal blocks (a node's coupling of x, y, z)
    AMG,          ///< algebraic multigrid: one V-cycle of PETSc GAMG (AmgPreconditioner)
};

/// Knobs of the AMG kind's hierarchy and cycle (AmgPreconditioner; defaults chosen with
/// tools/bench_amg.cpp, docs/solver.md).
struct AmgSettings {
    double growth = 1.5;           ///< rebuild the hierarchy when a solve needs more than this
                                   ///< many times the iterations per decade of the first solve
                                   ///< after the last set-up (HierarchyReuse), > 1
    int fine_degree = 2;           ///< Chebyshev (Jacobi) degree of pre- and post-smoothing on
                                   ///< the finest level, ≥ 1
    int coarse_degree = 2;         ///< the same on the coarser levels, ≥ 1
    int aggregation_smoothing = 1; ///< prolongator smoothing steps: 1 smoothed aggregation, 0 plain
    double threshold = 0.0;        ///< GAMG's drop tolerance of weak couplings, ≥ 0
    bool scene_fine_level = true;  ///< the finest level multiplies with the scene matrix itself;
                                   ///< false: with PETSc's copy from the last set-up
};

/// What a preconditioner spent on set-ups and on applications, counted from its creation.
/// The diagonal kinds are built and applied inside PCG's passes and report nothing.
struct PreconditionerTimes {
    Index setups = 0;      ///< hierarchies built from scratch or refreshed
    double setup_s = 0.0;  ///< wall time of those set-ups [s]
    Index applies = 0;     ///< applications z = M⁻¹ r
    double apply_s = 0.0;  ///< wall time of those applications [s]
};

class Preconditioner {
public:
    virtual ~Preconditioner() = default;

    /// Before a solve: makes M from the matrix `a` of this solve, or decides that the M it has
    /// still serves. `a` stays referenced until the solve ends (apply() may multiply with it).
    /// @throws NumericalError if M cannot be formed (a singular diagonal block, a library error)
    virtual void prepare(const SceneMatrix& a) = 0;

    /// True if z on the rows of one chunk depends only on r on those rows.
    virtual bool is_chunk_local() const = 0;

    /// Chunk-local kinds: z = M⁻¹ r on the rows [begin, end) of one chunk of the prepared
    /// matrix (3·begin … 3·end in r and z). Distinct chunks may run in parallel.
    virtual void apply_rows(Index begin, Index end, const double* r, double* z) const;

    /// Global kinds: z = M⁻¹ r on every row of the prepared matrix. Called from one thread.
    /// @param[in] r   #3N
    /// @param[out] z  #3N, must not alias r
    virtual void apply(const double* r, double* z);

    /// After a solve that used this M: its iterations, and the residual's reduction over them
    /// ‖r_end‖/‖r_start‖ (AMG decides from the rate whether its hierarchy still serves).
    virtual void record_solve(Index iterations, double reduction);

    /// Set-ups and applications so far.
    virtual PreconditionerTimes times() const;
};

/// A new preconditioner of the given kind (`amg`: the AMG kind's knobs).
/// @throws InputError for AMG when this build has no AMG (CORO_WITH_AMG off)
std::unique_ptr<Preconditioner> make_preconditioner(PcgPreconditioner kind, const AmgSettings& amg = {});

/// The name a case file uses for the kind: "jacobi", "block_jacobi", "amg".
const char* preconditioner_name(PcgPreconditioner kind);

} // namespace coro
