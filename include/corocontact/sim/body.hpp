#pragma once
/// @file body.hpp
/// @brief One deformable body: its mesh, FEM model, state, constraints and loads.

#include <corocontact/core/embedding.hpp>
#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/core/tet_mesh.hpp>
#include <corocontact/fem/corotational_fem.hpp>
#include <corocontact/sim/case_spec.hpp>
#include <corocontact/solver/bsr_matrix.hpp>
#include <corocontact/solver/pcg.hpp>

#include <string>
#include <vector>

namespace coro {

class Body {
public:
    /// Builds a body from its mesh (already transformed and oriented) and the case's settings.
    /// The mesh is split into `num_parts` METIS parts and renumbered internally (see
    /// partition/part_layout.hpp): every index a Body takes or returns is internal;
    /// input_node() and input_tet() map back to the input's order.
    /// @param[in] mesh       positively oriented tets, positions after the body transform [m]
    /// @param[in] spec       material, damping, initial velocity, fixed regions and box loads
    /// @param[in] num_parts  parts of the parallel element loop, ≥ 1
    /// @param[in] precision  how the system matrix stores its values
    /// @throws InputError naming spec.location if a fixed or load box contains no node
    Body(const TetMesh& mesh, const BodySpec& spec, Index num_parts = 1,
         MatrixPrecision precision = MatrixPrecision::DOUBLE);

    const std::string& name() const { return m_name; }
    /// The mesh in internal order.
    const TetMesh& mesh() const { return m_mesh; }
    /// Input (file) index of internal node v.
    Index input_node(Index v) const { return m_fem.layout().new_to_old_node[static_cast<std::size_t>(v)]; }
    /// Per-node values (#3V, internal order, e.g. positions()) as #V×3 rows in input order.
    Positions to_input_order(const VecX& node_values) const;
    /// The inverse of to_input_order: #V×3 rows in input order to #3V values in internal order.
    VecX from_input_order(CRef<Positions> rows) const;
    /// The tets in input order, numbered by input node, #T×4.
    Tets input_tets() const;
    /// Input (file) index of internal tet t.
    Index input_tet(Index t) const { return m_fem.layout().new_to_old_tet[static_cast<std::size_t>(t)]; }
    /// METIS part of internal tet t.
    Index part_of_tet(Index t) const { return m_fem.layout().tet_part[static_cast<std::size_t>(t)]; }
    /// Faces shared by tets of different parts.
    Index edge_cut() const { return m_edge_cut; }
    CorotationalFem& fem() { return m_fem; }
    const CorotationalFem& fem() const { return m_fem; }
    Index num_vertices() const { return m_mesh.num_vertices(); }

    /// Current positions x, #3V [m].
    VecX& positions() { return m_positions; }
    const VecX& positions() const { return m_positions; }
    /// Current velocities v, #3V [m/s].
    VecX& velocities() { return m_velocities; }
    const VecX& velocities() const { return m_velocities; }
    /// Displacements x − X, #3V [m].
    VecX displacements() const { return m_positions - m_fem.rest_dofs(); }

    /// #V flags, non-zero for a node held in place.
    const std::vector<char>& fixed() const { return m_fixed; }
    /// Number of fixed nodes.
    Index num_fixed() const { return m_num_fixed; }
    /// Marks node `v` fixed (it keeps its current position).
    void fix_vertex(Index v);
    /// Replaces every node's flag: nodes fixed from now on keep their current position and get
    /// velocity 0 (as at construction); released nodes move freely from the next step.
    /// @param[in] fixed  #V flags in internal order, non-zero for a node held in place
    /// @throws InputError if fixed.size() is not #V
    void set_fixed(const std::vector<char>& fixed);
    /// Constant external nodal forces from the box loads, #3V [N] (gravity is added by solvers).
    const VecX& load_forces() const { return m_load_forces; }
    VecX& load_forces() { return m_load_forces; }

    double rayleigh_mass() const { return m_rayleigh_mass; }
    double rayleigh_stiffness() const { return m_rayleigh_stiffness; }

    /// System matrix storage (pattern built once, values refilled by the solvers).
    BsrMatrix& system_matrix() { return m_system; }
    const BsrMatrix& system_matrix() const { return m_system; }
    /// The body's PCG solver (keeps its work vectors between steps).
    PcgSolver& pcg() { return m_pcg; }

    /// Embeds a fine contact surface (positions after the body transform) in the tets: each
    /// vertex follows the tet containing it (paper §4, coupled meshes).
    void embed_surface(SurfaceMesh surface);
    /// The embedded surface at rest (empty when the body has none) and its binding.
    const SurfaceMesh& embedded_surface() const { return m_embedded_surface; }
    const Embedding& embedding() const { return m_embedding; }

    /// Zeroes the entries of fixed nodes in a #3V vector (projection).
    void project_fixed(Eigen::Ref<VecX> dofs) const;

private:
    struct Partitioned {
        TetMesh mesh;
        PartLayout layout;
        Index edge_cut = 0;
    };
    static Partitioned partition_mesh(const TetMesh& mesh, Index num_parts);
    Body(Partitioned&& partitioned, const BodySpec& spec, MatrixPrecision precision);

    std::string m_name;
    Index m_edge_cut = 0;
    TetMesh m_mesh;
    CorotationalFem m_fem;
    VecX m_positions;
    VecX m_velocities;
    std::vector<char> m_fixed;
    Index m_num_fixed = 0;
    VecX m_load_forces;
    double m_rayleigh_mass = 0.0;
    double m_rayleigh_stiffness = 0.0;
    BsrMatrix m_system;
    PcgSolver m_pcg;
    SurfaceMesh m_embedded_surface;
    Embedding m_embedding;
};

/// Kinetic energy ½ vᵀMv of a body [J].
double kinetic_energy(const Body& body);

} // namespace coro
