#pragma once
/// @file diagonal_preconditioner.hpp
/// @brief Jacobi and block-Jacobi preconditioning: the inverse of the matrix's diagonal
/// entries, or of its 3×3 diagonal blocks (a node's coupling of x, y, z, contact included).

#include <corocontact/solver/bsr_matrix.hpp>
#include <corocontact/solver/preconditioner.hpp>

#include <vector>

namespace coro {

/// Chunk-local: prepare() inverts the diagonal of each chunk's rows in parallel over the
/// chunks, apply_rows() multiplies a chunk's rows by it. Results never depend on the thread
/// count. Buffers are kept between solves: once sized, a solve allocates nothing.
class DiagonalPreconditioner final : public Preconditioner {
public:
    /// @param[in] blocks  true: block-Jacobi (3×3 blocks); false: Jacobi (diagonal entries)
    explicit DiagonalPreconditioner(bool blocks) : m_blocks(blocks) {}

    /// A zero diagonal entry or a singular block gives non-finite values, which the PCG reports.
    void prepare(const SceneMatrix& a) override;
    bool is_chunk_local() const override { return true; }
    void apply_rows(Index begin, Index end, const double* r, double* z) const override;

private:
    bool m_blocks;
    std::vector<Block3> m_inverse_blocks; // one per node: the diagonal blocks, then (blocks) their inverses
    std::vector<double> m_inverse_diagonal; // Jacobi: one per DOF
};

} // namespace coro
