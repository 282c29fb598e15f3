#pragma once
/// @file corotational_tangent.hpp
/// @brief The consistent tangent −∂f/∂x of the co-rotational internal force, rotation
/// derivative included (McAdams et al. 2011, "Efficient elasticity for character skinning
/// with contact and collisions", §4; Chao et al. 2010).
///
/// The force f = −Σ_e R_e K_e (R_eᵀ x_e − X_e) of CorotationalFem is, with R_e the polar
/// rotation of F_e = R_e S_e, the exact gradient of the co-rotated energy
/// Ψ = Σ V (μ ‖S − I‖² + λ/2 tr(S − I)²): its first Piola stress is P = R σ(S − I). So the
/// tangent is the Hessian of Ψ and is **symmetric** everywhere; what it is not, in general, is
/// positive definite. Differentiating P with dR = R W (W skew, from the symmetry of dS:
/// WS + SW = RᵀdF − dFᵀR) gives, per element, with G_a = R g_a the rotated gradients:
///
///   K_ab = K'_ab + (V/2) [G_a]×ᵀ R M Rᵀ [G_b]×,
///   M = 2μ I + 2(λ(tr S − 3) − 2μ) (tr S · I − S)⁻¹,
///
/// where K' is the rotated stiffness of the dynamic step. M acts on the skew part of RᵀdF
/// (the sym part is K's): its eigenvalues along the eigenvectors of S are
/// m_k = (ψ_i + ψ_j)/(σ_i + σ_j), ψ_i = 2μ(σ_i − 1) + λ(tr S − 3), {i, j, k} = {0, 1, 2} —
/// zero at rest, positive in tension, negative in compression (the geometric, initial-stress
/// stiffness). EXACT keeps them: Newton with it converges quadratically, and PCG applies as
/// long as compression does not make the whole matrix indefinite (buckling). PROJECTED clamps
/// negative m_k to zero (McAdams' definiteness fix): the element matrices are then positive
/// semi-definite and the tangent ⪰ K', so PCG always applies and a Newton step is a descent
/// direction of Ψ − f_ext·x, at the price of linear convergence where elements are compressed.

#include <corocontact/fem/corotational_fem.hpp>
#include <corocontact/solver/bsr_matrix.hpp>

#include <cstdint>
#include <vector>

namespace coro {

/// What the tangent does with the negative eigenvalues of M (see the file comment).
enum class TangentDefiniteness {
    EXACT,     ///< the Hessian of the co-rotated energy; indefinite in strongly compressed elements
    PROJECTED, ///< negative m_k clamped to 0: positive definite wherever K' is
};

/// Assembles the consistent tangent of one body's co-rotational model into its BsrMatrix
/// pattern. Holds, per block of the pattern, the (tet, corner, corner) terms that add into it,
/// so a fill is a parallel loop over tets and then one over blocks, each block summed in tet
/// order: the result does not depend on the thread count.
class CorotationalTangent {
public:
    /// Precomputes the rest gradients and, per matrix block, the tets that touch it.
    /// @param[in] fem  the body's model (its mesh, rest state and matrix pattern)
    explicit CorotationalTangent(const CorotationalFem& fem);

    /// Fills `tangent` (from fem.make_matrix()) with K' + the rotation-derivative term at
    /// positions `x`, using fem's current rotations: call fem.update_rotations(x) first, so
    /// that R_e is the polar rotation of F_e(x). Rows and columns of fixed nodes are replaced
    /// by identity (projection), as in CorotationalFem::assemble().
    /// @param[in,out] fem  the model this object was built from (assembles K' into `tangent`)
    /// @throws std::invalid_argument if `fem` has another tet count than at construction
    /// @param[in] x        #3V positions [m]
    /// @param[in] fixed    #V flags, non-zero for a fixed node (empty: none fixed)
    /// @param[in] kind     EXACT or PROJECTED (see TangentDefiniteness)
    /// @param[out] tangent the matrix, symmetric in upper storage [N/m]
    void assemble(CorotationalFem& fem, CRef<VecX> x, const std::vector<char>& fixed, TangentDefiniteness kind,
                  BsrMatrix& tangent);

private:
    struct TetTerms {
        Mat34 rotated_gradients; // G_a = R g_a
        Mat3 weight;             // (V/2) R M Rᵀ
    };
    // One term of a block (r, c), r ≤ c: [G_a]×ᵀ W [G_b]× of `tet`, whose corner a is node r
    // and corner b node c.
    struct BlockTerm {
        Index tet;
        std::uint8_t a;
        std::uint8_t b;
    };
    std::vector<Mat34> m_gradients; // rest g_0..g_3 per tet
    std::vector<TetTerms> m_terms;  // per tet, refilled by assemble()
    // CSR over matrix blocks (pattern order): the terms of each block, ascending in tet.
    std::vector<Index> m_block_offsets;
    std::vector<BlockTerm> m_block_terms;
};

} // namespace coro
