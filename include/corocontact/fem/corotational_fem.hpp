#pragma once
/// @file corotational_fem.hpp
/// @brief The simplified co-rotational linear FEM of one body (paper Eq. 1, DESIGN.md).
///
/// Per step: rotations R_e from the polar decomposition of F_e (update_rotations), then the
/// rotated stiffness K' = Σ R_e K_e R_eᵀ and the internal forces f = f0 − K'x from rotated
/// shape gradients G_e = R_e g_e in closed form. Nothing 12×12 is stored or multiplied per
/// element: K'_ij = V (λ G_i G_jᵀ + μ G_j G_iᵀ + μ (G_i·G_j) I).
///
/// Assembly is a parallel gather: every stored block of the matrix sums its element
/// contributions in ascending element order, so the result is bitwise independent of the
/// thread count.

#include <corocontact/core/material.hpp>
#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/fem/tet_element.hpp>
#include <corocontact/solver/bsr_matrix.hpp>

#include <vector>

namespace coro {

class CorotationalFem {
public:
    /// Precomputes shape gradients, volumes, lumped masses and the matrix pattern.
    /// @param[in] mesh      positively oriented tets (see validate_and_orient)
    /// @param[in] material  E, ν, ρ of the body
    /// @throws NumericalError if a tet has non-positive rest volume
    CorotationalFem(const TetMesh& mesh, const Material& material);

    Index num_vertices() const { return static_cast<Index>(m_rest.size() / 3); }
    Index num_tets() const { return static_cast<Index>(m_tets.rows()); }
    const Tets& tets() const { return m_tets; }
    /// Rest positions as DOFs, #3V [m].
    const VecX& rest_dofs() const { return m_rest; }
    /// Lumped mass ρV/4 summed per node, #V [kg].
    const VecX& lumped_masses() const { return m_masses; }
    /// Rest volume of each tet, #T [m³].
    const std::vector<double>& volumes() const { return m_volumes; }
    double lambda() const { return m_lambda; }
    double mu() const { return m_mu; }

    /// Computes R_e for every tet from positions `x` (#3V), warm-started from the previous R_e,
    /// and the rotated gradients used by forces and assembly. Parallel over tets.
    /// @throws NumericalError naming the tet if its deformation gradient is not finite
    void update_rotations(CRef<VecX> x);

    /// Current element rotations (identity before the first update), #T.
    const std::vector<Mat3>& rotations() const { return m_rotations; }

    /// Internal forces f = f0 − K'x = −Σ_e R_e K_e (R_eᵀ x_e − X_e) with the current rotations.
    /// @param[in] x   #3V positions [m]
    /// @param[out] f  #3V forces [N]
    void internal_forces(CRef<VecX> x, Eigen::Ref<VecX> f);

    /// Co-rotated strain energy Σ V (μ ε:ε + λ/2 tr(ε)²), ε = sym(Rᵀ F) − I, with R evaluated
    /// from `x` itself (not the stored rotations); its gradient is −internal_forces(x) [J].
    double strain_energy(CRef<VecX> x) const;

    /// A matrix with this body's node-adjacency pattern (values zero).
    BsrMatrix make_matrix() const;

    /// Fills `matrix` (from make_matrix) with stiffness_scale·K' + mass_scale·M with the current
    /// rotations; rows and columns of fixed nodes are replaced by identity (projection).
    /// @param[in] fixed  #V flags, non-zero for a fixed node (empty: none fixed)
    void assemble(double stiffness_scale, double mass_scale, const std::vector<char>& fixed,
                  BsrMatrix& matrix) const;

    /// Von Mises stress of each tet in the co-rotated frame at positions `x` [Pa], #T.
    VecX von_mises_stress(CRef<VecX> x) const;

private:
    Tets m_tets;
    VecX m_rest;
    VecX m_masses;
    std::vector<double> m_volumes;
    std::vector<Mat34> m_gradients;         // rest g_0..g_3 per tet
    std::vector<Mat3> m_rotations;          // R_e
    std::vector<Mat34> m_rotated_gradients; // G_e = R_e g_e
    std::vector<Mat34> m_force_slots;       // per-tet forces before the gather
    double m_lambda = 0.0;
    double m_mu = 0.0;

    // node → (tet·4 + corner), ascending, for the force gather
    std::vector<Index> m_node_offsets;
    std::vector<Index> m_node_corners;
    // block pattern and, per stored block, its contributions (tet·16 + 4i + j), ascending
    std::vector<Index> m_row_offsets;
    std::vector<Index> m_columns;
    std::vector<Index> m_block_offsets;
    std::vector<Index> m_block_contributions;
};

} // namespace coro
