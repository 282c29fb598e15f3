#pragma once
/// @file pcg.hpp
/// @brief Preconditioned conjugate gradients on a scene matrix, deterministic for any thread count.

#include <corocontact/solver/bsr_matrix.hpp>
#include <corocontact/solver/preconditioner.hpp>
#include <corocontact/solver/scene_matrix.hpp>

#include <memory>
#include <vector>

namespace coro {

/// Settings of one solve.
struct PcgSettings {
    Index max_iterations = 100;    ///< iteration cap, ≥ 1
    double tolerance = 1e-6;       ///< stop when ‖b − Ax‖ ≤ tolerance·‖b‖
    PcgPreconditioner preconditioner = PcgPreconditioner::BLOCK_JACOBI;
    AmgSettings amg;               ///< preconditioner = AMG: its knobs (read when it is made)
};

/// Outcome of a solve; non-convergence is data, not an error.
struct PcgResult {
    bool converged = false;
    Index iterations = 0;
    double residual = 0.0;         ///< ‖b − Ax‖/‖b‖ at exit (0 when b = 0)
};

/// A reusable PCG solver: keeps its work vectors and the preconditioner between solves.
/// Each iteration makes three parallel passes over the scene's row chunks: q = A p with the
/// chunks' partial pᵀq; x, r and z = M⁻¹r updated together with the partial r·r and r·z; p = z
/// + βp. A global preconditioner (AMG) is applied between the update of r and the partial sums,
/// which then take a pass of their own. Every dot product adds the chunk partials in chunk
/// order, so the iterates are bitwise the same for any thread count (AMG: see
/// amg_preconditioner.hpp). Once its vectors have the scene's size, a solve allocates nothing.
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
    /// @param[in] a       the scene matrix, #N×#N blocks, SPD (its coupling finished)
    /// @param[in] b       #3N right-hand side
    /// @param[in,out] x   #3N initial guess on entry, solution on exit
    /// @throws NumericalError if a non-finite value appears (A not SPD, NaN in b)
    PcgResult solve(const SceneMatrix& a, CRef<VecX> b, Eigen::Ref<VecX> x, const PcgSettings& settings);

    /// Solves with one body's matrix (upper storage) as a scene of one body.
    PcgResult solve(const BsrMatrix& a, CRef<VecX> b, Eigen::Ref<VecX> x, const PcgSettings& settings);

    /// Set-ups and applications of the preconditioner so far (AMG's hierarchy and V-cycles;
    /// zero for the diagonal kinds and before the first solve).
    PreconditionerTimes preconditioner_times() const;

private:
    struct Sums {
        double rr = 0.0; ///< r·r
        double rz = 0.0; ///< r·z
    };
    /// The preconditioner of the settings' kind, prepared for `a`: the one kept from earlier
    /// solves when it is of this kind, else a new one.
    void prepare_preconditioner(const SceneMatrix& a, const PcgSettings& settings);
    /// One fused pass over the nodes: either r = b − r (r holding A x) when `b` is given, or
    /// x += αp, r −= αq; then z = M⁻¹ r, and r·r, r·z summed per chunk, then in chunk order.
    Sums residual_pass(const RowChunks& chunks, const double* b, double alpha, double* x);
    /// Σ_c chunk_dots[c] in chunk order.
    double sum_chunks(const std::vector<double>& chunk_dots) const;

    PcgPreconditioner m_kind = PcgPreconditioner::JACOBI;
    std::unique_ptr<Preconditioner> m_preconditioner; // of m_kind; null before the first solve
    VecX m_r, m_z, m_p, m_q;
    std::vector<double> m_chunk_dots;     // one partial per chunk
    std::vector<Sums> m_chunk_sums;       // one pair of partials per chunk
};

} // namespace coro
