#pragma once
/// @file corotational_fem.hpp
/// @brief The simplified co-rotational linear FEM of one body (paper Eq. 1, DESIGN.md).
///
/// Per step: rotations R_e from the polar decomposition of F_e (update_rotations), then the
/// rotated stiffness K' = Σ R_e K_e R_eᵀ and the internal forces f = f0 − K'x from rotated
/// shape gradients G_e = R_e g_e in closed form. Nothing 12×12 is stored or multiplied per
/// element: K'_ij = V (λ G_i G_jᵀ + μ G_j G_iᵀ + μ (G_i·G_j) I).
///
/// The element loop runs part by part (METIS parts, see partition/part_layout.hpp) under TBB:
/// each part adds its tets' blocks and forces straight into the rows of its interior nodes and
/// into private buffers for interface rows, which are then summed in ascending part order. So
/// the result depends on the partition but never on the thread count.

#include <corocontact/core/material.hpp>
#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/fem/tet_element.hpp>
#include <corocontact/partition/part_layout.hpp>
#include <corocontact/solver/bsr_matrix.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace coro {

class CorotationalFem {
public:
    /// Precomputes shape gradients, volumes, lumped masses, the matrix pattern and where every
    /// tet's blocks go.
    /// @param[in] mesh      positively oriented tets, in the layout's internal order
    /// @param[in] material  E, ν, ρ of the body
    /// @param[in] layout    parts of the mesh (reorder_mesh applied to `mesh`); an empty layout
    ///                      (num_parts = 0 offsets) means one part holding everything
    /// @throws NumericalError if a tet has non-positive rest volume
    CorotationalFem(const TetMesh& mesh, const Material& material, PartLayout layout = {});

    Index num_vertices() const { return static_cast<Index>(m_rest.size() / 3); }
    Index num_tets() const { return static_cast<Index>(m_tets.rows()); }
    const Tets& tets() const { return m_tets; }
    const PartLayout& layout() const { return m_layout; }
    /// Rest positions as DOFs, #3V [m].
    const VecX& rest_dofs() const { return m_rest; }
    /// Lumped mass ρV/4 summed per node, #V [kg].
    const VecX& lumped_masses() const { return m_masses; }
    /// Rest volume of each tet, #T [m³].
    const std::vector<double>& volumes() const { return m_volumes; }
    double lambda() const { return m_lambda; }
    double mu() const { return m_mu; }

    /// Computes R_e for every tet from positions `x` (#3V), warm-started from the previous R_e.
    /// @throws NumericalError naming the tet if its deformation gradient is not finite
    void update_rotations(CRef<VecX> x);

    /// Current element rotations (identity before the first update), #T.
    const std::vector<Mat3>& rotations() const { return m_rotations; }

    /// Replaces the element rotations, e.g. from a checkpoint: the next update_rotations()
    /// starts its polar iteration from them.
    /// @param[in] rotations  #T rotations, in this object's tet order
    /// @throws std::invalid_argument if the count is not #T
    void set_rotations(std::vector<Mat3> rotations);

    /// Internal forces f = f0 − K'x = −Σ_e R_e K_e (R_eᵀ x_e − X_e) with the current rotations.
    /// @param[in] x   #3V positions [m]
    /// @param[out] f  #3V forces [N]; contiguous, must not alias x
    void internal_forces(CRef<VecX> x, Eigen::Ref<VecX> f);

    /// Co-rotated strain energy Σ V (μ ε:ε + λ/2 tr(ε)²), ε = sym(Rᵀ F) − I, with R evaluated
    /// from `x` itself (not the stored rotations); its gradient is −internal_forces(x) [J].
    double strain_energy(CRef<VecX> x) const;

    /// A matrix with this body's node-adjacency pattern (values zero), symmetric in upper
    /// storage with the parts as its product chunks.
    /// @param[in] precision  how the matrix stores its values: the element loop adds each
    ///                       tet's contribution in double to the stored value and stores the
    ///                       sum in this precision
    BsrMatrix make_matrix(MatrixPrecision precision = MatrixPrecision::DOUBLE) const;

    /// Fills `matrix` (from make_matrix) with stiffness_scale·K' + mass_scale·M with the current
    /// rotations; rows and columns of fixed nodes are replaced by identity (projection).
    /// @param[in] fixed  #V flags, non-zero for a fixed node (empty: none fixed)
    void assemble(double stiffness_scale, double mass_scale, const std::vector<char>& fixed, BsrMatrix& matrix);

    /// assemble() and internal_forces() in one pass over the tets (current rotations).
    void assemble_with_forces(CRef<VecX> x, double stiffness_scale, double mass_scale,
                             const std::vector<char>& fixed, BsrMatrix& matrix, Eigen::Ref<VecX> forces);

    /// update_rotations(x), then assemble_with_forces(), in one pass over the tets: each part
    /// rotates a chunk of its tets and assembles it while its data is still in cache. The
    /// results are bit for bit those of the two calls.
    /// @throws NumericalError naming the tet if its deformation gradient is not finite
    void rotate_and_assemble_with_forces(CRef<VecX> x, double stiffness_scale, double mass_scale,
                                         const std::vector<char>& fixed, BsrMatrix& matrix, Eigen::Ref<VecX> forces);

    /// One pass over the tets, for callers that schedule the parts themselves (a scene runs
    /// the parts of all its bodies as one parallel loop): element_part() for every part, then
    /// finish_rows() for every row.
    struct ElementPass {
        const double* x = nullptr;     ///< #3V positions [m]: read for rotations and forces
        bool rotate = false;           ///< update R_e from x first (x required)
        double* forces = nullptr;      ///< #3V output: internal forces f0 − K'x [N], or null
        BsrMatrix* matrix = nullptr;   ///< output (from make_matrix): stiffness_scale·K' +
                                       ///< mass_scale·M, or null
        double stiffness_scale = 0.0;
        double mass_scale = 0.0;
        const char* fixed = nullptr;   ///< #V flags, non-zero for a fixed node whose matrix row
                                       ///< and column become identity; null: none fixed
    };

    /// The tets of one part: rotations (pass.rotate), then their blocks and forces, written to
    /// the part's interior rows and to the part's own buffers for interface rows. Distinct parts
    /// may run in parallel; the result never depends on how they are scheduled.
    /// @throws NumericalError naming the tet if its deformation gradient is not finite
    void element_part(Index part, const ElementPass& pass);

    /// After element_part() of every part: the rows [row_begin, row_end) completed — interface
    /// rows summed from the part buffers in ascending part order with their mass added, rows and
    /// columns of fixed nodes replaced by identity. Disjoint row ranges may run in parallel.
    void finish_rows(Index row_begin, Index row_end, const ElementPass& pass);

    /// Von Mises stress of each tet in the co-rotated frame at positions `x` [Pa], #T.
    VecX von_mises_stress(CRef<VecX> x) const;

private:
    using Pass = ElementPass;
    // Where a tet's contributions go: a target ≥ 0 is a matrix block or node of an interior
    // row, a target < 0 the interface buffer entry −1 − target. Blocks are stored in the
    // matrix's precision (Value: double or float), forces in double.
    template <class Value> struct Slots {
        Value* values;        // matrix values, or null when no matrix is assembled
        Value* block_buffer;
        double* forces;       // #3V, or null when no forces are computed
        double* force_buffer;
        Value* block(Index target) const
        {
            return target >= 0 ? values + 9 * static_cast<std::ptrdiff_t>(target)
                               : block_buffer + 9 * static_cast<std::ptrdiff_t>(-1 - target);
        }
        double* force(Index target) const
        {
            return target >= 0 ? forces + 3 * static_cast<std::ptrdiff_t>(target)
                               : force_buffer + 3 * static_cast<std::ptrdiff_t>(-1 - target);
        }
    };
    void run_pass(const Pass& pass);
    // element_part() with the matrix values and interface buffer of the matrix's precision.
    template <class Value> void element_part_in(Index part, const Pass& pass, Value* values, Value* block_buffer);
    template <class Value> void tet_range(Index t_begin, Index t_end, const Pass& pass, const Slots<Value>& slots);
    template <class Value> void one_tet(Index t, const Pass& pass, const Slots<Value>& slots);
    // Tets first .. first + count − 1 (count ≤ 4) as one AVX2 pack (detail/tet_pack_kernel.hpp).
    template <class Value> void tet_pack(Index first, int count, const Pass& pass, const Slots<Value>& slots);
    // Σ of the part buffers' entries of interface block b (in ascending part order), in double.
    template <class Value> Block3 interface_block_sum(Index b, const Value* block_buffer) const;
    void project_fixed_rows(Index row_begin, Index row_end, const char* fixed, BsrMatrix& matrix) const;

    Tets m_tets;
    PartLayout m_layout;
    VecX m_rest;
    VecX m_masses;
    std::vector<double> m_volumes;
    std::vector<Mat34> m_gradients; // rest g_0..g_3 per tet
    std::vector<Mat3> m_rotations;  // R_e
    double m_lambda = 0.0;
    double m_mu = 0.0;

    // Pattern of the matrix.
    std::vector<Index> m_row_offsets;
    std::vector<Index> m_columns;
    // Where tet t's block (i, j), i ≤ j, goes (the 10 pairs in TET_BLOCK_PAIRS order): ≥ 0 a
    // block of the matrix (interior row), < 0 the interface buffer entry −1 − target; bit
    // `pair` of m_block_transposed set when the block is stored transposed (node i > node j).
    // Likewise for the 4 corner forces.
    std::vector<std::array<Index, 10>> m_block_targets;
    std::vector<std::uint16_t> m_block_transposed;
    std::vector<std::array<Index, 4>> m_force_targets;
    // Interface buffers, part by part, and per interface block / node the buffer entries to
    // sum, in ascending part order.
    std::vector<double> m_block_buffer;         // 9 per entry, for a double-precision matrix
    std::vector<float> m_single_block_buffer;   // 9 per entry, for a single-precision matrix
    std::vector<double> m_force_buffer;  // 3 per entry
    std::vector<Index> m_part_block_buffer_offsets; // #parts+1
    std::vector<Index> m_part_force_buffer_offsets; // #parts+1
    std::vector<Index> m_interface_block_offsets;   // per block of an interface row, into entries
    std::vector<Index> m_interface_block_entries;
    std::vector<Index> m_interface_force_offsets;   // per interface node, into entries
    std::vector<Index> m_interface_force_entries;
};

} // namespace coro
