#pragma once
/// @file pcg.hpp
/// @brief Preconditioned conjugate gradients on a scene matrix, deterministic for any thread count.

#include <corocontact/solver/bsr_matrix.hpp>
#include <corocontact/solver/preconditioner.hpp>
#include <corocontact/solver/scene_exchange.hpp>
#include <corocontact/solver/scene_matrix.hpp>

#include <memory>
#include <vector>

namespace coro {

/// Settings of one solve.
struct PcgSettings {
    Index max_iterations = 100;    ///< iteration cap, ≥ 1
    double tolerance = 1e-6;       ///< stop when ‖b − Ax‖ ≤ tolerance·‖b‖; 0 runs the cap, or
                                   ///< to ‖b − Ax‖ ≤ 1e-30‖b‖, past which double precision has nothing to add
    PcgPreconditioner preconditioner = PcgPreconditioner::BLOCK_JACOBI;
    AmgSettings amg;               ///< preconditioner = AMG: its knobs (read when it is made)
};

/// Outcome of a solve; non-convergence is data, not an error. For a scene of several
/// components (SceneMatrix::num_components) it is that of the slowest component.
struct PcgResult {
    bool converged = false;        ///< every component reached the tolerance
    Index iterations = 0;          ///< iterations of the component that ran longest
    double residual = 0.0;         ///< the largest ‖b_k − A_k x_k‖/‖b_k‖ of a component k (0 for b_k = 0)
};

/// A reusable PCG solver: keeps its work vectors and the preconditioner between solves.
///
/// The scene matrix is block diagonal by component (bodies that contact may join), and each
/// component gets a recurrence of its own — its own α, β and stopping test, exactly the PCG of
/// that component alone — run side by side in the same scene-wide parallel passes. A
/// component stops when its residual falls below tolerance·‖b_k‖ or at the cap, and its chunks
/// are skipped from then on: a pile's resting bodies do not iterate as long as a colliding stack.
///
/// Each iteration makes three parallel passes over the scene's row chunks: q = A p with the
/// chunks' partial pᵀq; x, r and z = M⁻¹r updated together with the partial r·r and r·z; p = z
/// + βp. A component's dot products add its chunk partials in chunk order, so the iterates are
/// bitwise the same for any thread count (AMG: see amg_preconditioner.hpp). Once its vectors
/// have the scene's size, a solve allocates nothing.
///
/// Distributed (an exchange given): this process holds the rows of its bodies, and the
/// components are those of the whole scene (every process runs every component's recurrence);
/// before each product the ghost rows of the multiplied vector are updated, and a component's
/// dot products add the chunk partials of all processes in the global chunk order, so the
/// iterates are bitwise those of one process holding every body.
///
/// A chunk-local preconditioner (Jacobi, block-Jacobi) runs inside the pass over the active
/// chunks. A global one (AMG) is applied to the whole vector between the update of r and the
/// partial sums, which then take a pass of their own: it is block diagonal by component like the
/// matrix (its aggregates follow the matrix's couplings), so each component's z depends only on
/// its own r, and the z it writes on the chunks of stopped components is never read.
class PcgSolver {
public:
    PcgSolver() = default;
    /// A copy holds no work state: its vectors and preconditioner are made at its first solve.
    PcgSolver(const PcgSolver&) {}
    PcgSolver& operator=(const PcgSolver&) { return *this = PcgSolver(); }
    PcgSolver(PcgSolver&&) noexcept = default;
    PcgSolver& operator=(PcgSolver&&) noexcept = default;
    ~PcgSolver() = default;

    /// Solves A x = b for symmetric positive definite A, warm-started from the given x.
    /// @param[in] a       the scene matrix, #N×#N blocks, SPD (its coupling finished, every
    ///                    coupling term within a component); with an exchange, this
    ///                    process's rows, coupling columns up to N + G
    /// @param[in] b       #3N right-hand side
    /// @param[in,out] x   #3N initial guess on entry, solution on exit
    /// @param[in] exchange  null (one process), or the halo and component sums of a distributed
    ///                    scene; then the call is collective, and every process returns the same
    ///                    result or throws the same error
    /// @throws NumericalError if a non-finite value appears (A not SPD, NaN in b)
    PcgResult solve(const SceneMatrix& a, CRef<VecX> b, Eigen::Ref<VecX> x, const PcgSettings& settings,
                    SceneExchange* exchange = nullptr);

    /// Solves with one body's matrix (upper storage) as a scene of one body.
    PcgResult solve(const BsrMatrix& a, CRef<VecX> b, Eigen::Ref<VecX> x, const PcgSettings& settings);

    /// Set-ups and applications of the preconditioner so far (AMG's hierarchy and V-cycles;
    /// zero for the diagonal kinds and before the first solve).
    PreconditionerTimes preconditioner_times() const;

private:
    /// The recurrence of one component.
    struct Component {
        double b_norm = 0.0;
        double r_norm = 0.0;
        double initial_r_norm = 0.0; ///< ‖r‖ of the warm start
        double rz = 0.0;     ///< r·z of the current iterate
        double alpha = 0.0;
        double beta = 0.0;
        Index iterations = 0;
        bool active = false; ///< still iterating
    };
    /// The preconditioner of the settings' kind, prepared for `a`: the one kept from earlier
    /// solves when it is of this kind, else a new one.
    void prepare_preconditioner(const SceneMatrix& a, const PcgSettings& settings);
    /// One fused pass over the active chunks: either r = b − r (r holding A x) when `b` is
    /// given, or x += α_k p, r −= α_k q; then z = M⁻¹ r, and r·r, r·z per chunk.
    void residual_pass(const SceneMatrix& a, const double* b, double* x);
    /// p = z + β_k p over the active chunks.
    void direction_pass(const SceneMatrix& a);
    /// totals[k·width + j] = Σ partials[c·width + j] over the chunks c of component k, in chunk
    /// order (inactive components included only when `all`; with an exchange, the chunks of all
    /// processes and every component).
    void sum_by_component(const SceneMatrix& a, const std::vector<double>& partials, int width, bool all);
    /// The chunk flags of the active components.
    void mark_active_chunks(const SceneMatrix& a);
    /// to = from over the scene's rows (#3N), in parallel.
    void copy_rows(const SceneMatrix& a, const double* from, double* to);
    /// y = A x over the active chunks; with an exchange, x's ghost rows are updated first.
    void multiply(const SceneMatrix& a, double* x, double* y, double* chunk_dots);

    PcgPreconditioner m_kind = PcgPreconditioner::JACOBI;
    std::unique_ptr<Preconditioner> m_preconditioner; // of m_kind; null before the first solve
    VecX m_r, m_z, m_q;
    VecX m_p;                             // #3(N + G): the multiplied vector, with ghost rows
    std::vector<Component> m_components;
    std::vector<char> m_chunk_active;     // one flag per chunk
    std::vector<double> m_partials;       // per chunk, up to two values
    std::vector<double> m_totals;         // per component, up to two values
    SceneExchange* m_exchange = nullptr;  // of the solve in progress
};

} // namespace coro
