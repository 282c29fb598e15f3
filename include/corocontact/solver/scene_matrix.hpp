#pragma once
/// @file scene_matrix.hpp
/// @brief The system matrix of a whole scene: every body's own matrix on the block diagonal
/// (pattern built once, values refilled in place) plus the contact coupling.
///
/// The rows (nodes) of body b are the scene rows [offset(b), offset(b) + #V_b). The row chunks
/// are the product chunks of the body matrices in body order (a small body is one chunk, a
/// large body its METIS parts and interface pieces), so every reduction over the scene sums
/// per-body partials in a fixed order: results never depend on the thread count.
///
/// The bodies fall into components: sets of bodies that the coupling may join (bodies whose
/// boxes overlap). The matrix is block diagonal by component, so the scene PCG runs one
/// recurrence per component, each stopping when its own residual is small enough.

#include <corocontact/solver/bsr_matrix.hpp>
#include <corocontact/solver/contact_coupling.hpp>
#include <corocontact/solver/row_chunks.hpp>

#include <vector>

namespace coro {

/// Rows per task of the scene-wide loops: small bodies are grouped until a task holds this many.
constexpr Index SCENE_TASK_ROWS = 1024;

class SceneMatrix {
public:
    SceneMatrix() = default;

    /// @param[in] bodies  the block-diagonal matrices in body order, each symmetric in upper
    ///                    storage (BsrMatrix::symmetric_upper); they are referenced, not copied,
    ///                    and must outlive this object (their values may change between uses)
    /// @throws std::invalid_argument if a matrix is not in upper storage
    explicit SceneMatrix(std::vector<const BsrMatrix*> bodies);

    Index num_bodies() const { return static_cast<Index>(m_bodies.size()); }
    Index num_block_rows() const { return m_chunks.num_rows(); }
    Index num_dofs() const { return 3 * num_block_rows(); }
    /// First scene row of body b.
    Index offset(Index body) const { return m_offsets[static_cast<std::size_t>(body)]; }
    const BsrMatrix& body_matrix(Index body) const { return *m_bodies[static_cast<std::size_t>(body)]; }
    /// The row chunks (reduction leaves) and tasks of every scene-wide loop.
    const RowChunks& chunks() const { return m_chunks; }
    /// The body of chunk c.
    Index chunk_body(Index chunk) const { return m_chunk_body[static_cast<std::size_t>(chunk)]; }

    /// Attaches the node positions of every body: an elasticity matrix's near-null space is
    /// spanned by the rigid-body motions of its nodes, from which the AMG preconditioner builds
    /// its coarse spaces. Referenced like the matrices (the values may change between uses).
    /// @param[in] positions  per body, in body order, #3V_b node positions [m]
    /// @throws std::invalid_argument if the count or a size does not match the bodies
    void set_node_positions(std::vector<const VecX*> positions);
    /// The positions of body b, or null when none are attached.
    const VecX* node_positions(Index body) const
    {
        return m_positions.empty() ? nullptr : m_positions[static_cast<std::size_t>(body)];
    }
    /// Components: component_of_body[b] for every body, numbered 0, 1, … in the order of each
    /// component's first body. Every coupling term must join bodies of one component.
    /// @throws std::invalid_argument if the numbering is not of that form
    void set_components(const std::vector<Index>& component_of_body);
    /// Components of a distributed scene (scene_exchange.hpp): component_of_body[b] for every
    /// body of this process, in the numbering of the whole scene's `num_components`.
    /// @throws std::invalid_argument if a number is outside [0, num_components)
    void set_components(const std::vector<Index>& component_of_body, Index num_components);
    /// Number of components (initially one per body).
    Index num_components() const { return m_num_components; }
    /// The component of chunk c.
    Index chunk_component(Index chunk) const { return m_chunk_component[static_cast<std::size_t>(chunk)]; }

    /// The contact coupling (scene rows, indexed by chunks()); call coupling().finish() after
    /// filling.
    ContactCoupling& coupling() { return m_coupling; }
    const ContactCoupling& coupling() const { return m_coupling; }

    /// y = A x, and for every chunk c the partial dot product Σ_{i in c} x_i y_i in
    /// `chunk_dots[c]` (the caller adds them in chunk order).
    /// @param[in] x            #3N scene DOFs, followed by the ghost rows that coupling columns
    ///                         ≥ N name in a distributed scene (scene_exchange.hpp)
    /// @param[out] y           #3N (must not alias x)
    /// @param[out] chunk_dots  #chunks, or null when no dot product is wanted
    /// @param[in] active       #chunks flags, or null for all: the rows (and dots) of chunks
    ///                         whose flag is 0 are skipped (left as they were); chunks of one
    ///                         component must share their flag
    void multiply(const double* x, double* y, double* chunk_dots, const char* active = nullptr) const;

    /// The diagonal blocks A_rr of the rows of chunk c (body block plus coupling).
    /// @param[out] out  one Block3 per row of the chunk
    void diagonal_blocks(Index chunk, Block3* out) const;

private:
    std::vector<const BsrMatrix*> m_bodies;
    std::vector<const VecX*> m_positions; // per body, or empty
    std::vector<Index> m_offsets;       // #bodies+1
    RowChunks m_chunks;
    std::vector<Index> m_chunk_body;    // #chunks
    std::vector<Index> m_chunk_local;   // #chunks: the chunk's index within its body matrix
    bool m_any_gathers = false;         // some body has blocks reaching across its chunks
    Index m_num_components = 0;
    std::vector<Index> m_chunk_component; // #chunks
    ContactCoupling m_coupling;
};

} // namespace coro
