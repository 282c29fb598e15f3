#pragma once
/// @file scene_system.hpp
/// @brief One linearly implicit Euler step of every body of a scene as one system (DESIGN.md,
/// "Many bodies: the scene is the unit of work").
///
///   (M + hC + h²K' + contact terms) v⁺ = M v + h (f_ext + m g + f0 − K'x + f_contact),
///   x⁺ = x + h v⁺,   C = αM + βK' per body, R frozen at the start of the step,
///
/// solved by one PCG over all bodies' unknowns, warm-started from v; fixed nodes are projected
/// out (v⁺ = 0 there). The step runs as scene-wide parallel loops: the element loop over work
/// items (a large body's METIS parts, small bodies batched), then the rows of every body in the
/// chunks of the scene matrix. Buffers are sized once: a step allocates nothing.

#include <corocontact/sim/body.hpp>
#include <corocontact/solver/pcg.hpp>
#include <corocontact/solver/scene_matrix.hpp>

#include <vector>

namespace coro {

/// Tets per work item of the element loop: small bodies are batched until an item holds this many.
constexpr Index ELEMENT_TASK_TETS = 2048;

class SceneSystem {
public:
    /// @param[in,out] bodies  the scene's bodies; referenced (their matrices, positions and
    ///                        velocities are used in place), so they must outlive this object
    ///                        and keep their addresses and sizes
    explicit SceneSystem(std::vector<Body>& bodies);

    SceneSystem(const SceneSystem&) = delete;
    SceneSystem& operator=(const SceneSystem&) = delete;

    /// The scene matrix: the bodies' matrices and the contact coupling, whose rows are
    /// the scene rows of offset().
    SceneMatrix& matrix() { return m_matrix; }
    const SceneMatrix& matrix() const { return m_matrix; }
    /// First scene row (node) of body b.
    Index offset(Index body) const { return m_matrix.offset(body); }

    /// Step part 1, the element loop over all work items: rotations R_e from the current
    /// positions, then every body's M + hC + h²K' (interior rows) and internal forces.
    /// @param[in] dt  time step h [s], > 0
    /// @throws NumericalError naming the body and tet whose deformation gradient is not finite
    void element_loop(double dt);

    /// Step part 2, over the scene's row chunks: interface rows summed, fixed nodes projected,
    /// right-hand side M v + h (f + f_ext + m g + contact_forces) and the warm start v.
    /// @throws NumericalError naming the body and node (mesh file order) of the first
    ///         non-finite right-hand side entry
    /// @param[in] gravity         acceleration [m/s²]
    /// @param[in] contact_forces  per body #3V explicit contact forces [N], or empty for none;
    ///                            the coupling terms are expected in matrix().coupling()
    void assemble(double dt, const Vec3& gravity, const std::vector<VecX>& contact_forces);

    /// Set-ups and applications of the PCG's preconditioner so far (AMG; zero for the others).
    PreconditionerTimes preconditioner_times() const { return m_pcg.preconditioner_times(); }

    /// Step part 3: one PCG over the scene.
    /// @param[in] exchange  null, or the halo and chunk sums of a scene spread over processes
    ///                      (see PcgSolver::solve; collective then)
    PcgResult solve(const PcgSettings& settings, SceneExchange* exchange = nullptr);

    /// Step part 4: v⁺ to the bodies and x⁺ = x + h v⁺.
    /// @throws NumericalError naming the body and node (mesh file order) of the first
    ///         non-finite velocity
    void advance(double dt);

    /// All four parts.
    PcgResult step(double dt, const Vec3& gravity, const std::vector<VecX>& contact_forces,
                   const PcgSettings& settings);

private:
    CorotationalFem::ElementPass element_pass(Index body, double dt);
    static std::vector<const BsrMatrix*> body_matrices(std::vector<Body>& bodies);
    // Throws for the first chunk flagged in m_chunk_not_finite, naming the body and node of its
    // first non-finite entry of `values` (scene DOFs).
    void report_non_finite(const VecX& values, const char* what) const;

    // A run of consecutive (body, part) units of the element loop.
    struct WorkItem {
        Index first_unit, end_unit;
    };
    struct Unit {
        Index body, part;
    };

    std::vector<Body>& m_bodies;
    SceneMatrix m_matrix;
    std::vector<Unit> m_units;
    std::vector<WorkItem> m_items;
    VecX m_rhs;       // #3N scene right-hand side (the element loop writes f into it)
    VecX m_velocity;  // #3N scene unknowns v⁺
    std::vector<char> m_chunk_not_finite;
    PcgSolver m_pcg;
};

} // namespace coro
