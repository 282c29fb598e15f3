#pragma once
/// @file pcg.hpp
/// @brief Preconditioned conjugate gradients on a BsrMatrix, deterministic for any thread count.

#include <corocontact/solver/bsr_matrix.hpp>

#include <vector>

namespace coro {

enum class PcgPreconditioner {
    JACOBI,       ///< inverse of the diagonal entries
    BLOCK_JACOBI, ///< inverse of the 3×3 diagonal blocks (a node's coupling of x, y, z)
};

/// Settings of one solve.
struct PcgSettings {
    Index max_iterations = 100;    ///< iteration cap, ≥ 1
    double tolerance = 1e-6;       ///< stop when ‖b − Ax‖ ≤ tolerance·‖b‖
    PcgPreconditioner preconditioner = PcgPreconditioner::BLOCK_JACOBI;
};

/// Outcome of a solve; non-convergence is data, not an error.
struct PcgResult {
    bool converged = false;
    Index iterations = 0;
    double residual = 0.0;         ///< ‖b − Ax‖/‖b‖ at exit (0 when b = 0)
};

/// A reusable PCG solver: keeps its work vectors and the preconditioner between solves.
/// Each iteration makes three parallel passes: q = A p fused with pᵀq; x, r and z = M⁻¹r
/// updated together with r·r and r·z; p = z + βp. Every reduction has a fixed tree, so the
/// iterates are bitwise the same for any thread count.
class PcgSolver {
public:
    /// Solves A x = b for symmetric positive definite A, warm-started from the given x.
    /// @param[in] a       #N×#N blocks, SPD
    /// @param[in] b       #3N right-hand side
    /// @param[in,out] x   #3N initial guess on entry, solution on exit
    /// @throws NumericalError if a non-finite value appears (A not SPD, NaN in b)
    PcgResult solve(const BsrMatrix& a, CRef<VecX> b, Eigen::Ref<VecX> x, const PcgSettings& settings);

private:
    struct Sums {
        double rr = 0.0; ///< r·r
        double rz = 0.0; ///< r·z
    };
    void build_preconditioner(const BsrMatrix& a, PcgPreconditioner kind);
    /// One fused pass over the nodes: either r = b − r (r holding A x) when `b` is given, or
    /// x += αp, r −= αq; then z = M⁻¹ r, and r·r, r·z with a fixed reduction tree.
    Sums residual_pass(const double* b, double alpha, double* x);

    PcgPreconditioner m_kind = PcgPreconditioner::JACOBI;
    std::vector<Block3> m_inverse_blocks; // BLOCK_JACOBI: one per node
    VecX m_inverse_diagonal;              // JACOBI: one per DOF
    VecX m_r, m_z, m_p, m_q;
};

} // namespace coro
