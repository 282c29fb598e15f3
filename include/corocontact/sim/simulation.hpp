#pragma once
/// @file simulation.hpp
/// @brief The scene and its time loop (dynamic) or load-step loop (static).

#include <corocontact/sim/body.hpp>
#include <corocontact/sim/case_spec.hpp>
#include <corocontact/contact/contact_surface.hpp>
#include <corocontact/contact/detector.hpp>
#include <corocontact/contact/plane_obstacle.hpp>
#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/sim/contact_response.hpp>
#include <corocontact/sim/phase_times.hpp>
#include <corocontact/solver/pcg.hpp>

#include <functional>
#include <memory>
#include <vector>

namespace coro {

/// All bodies of a case, and what contact detection last found.
struct Scene {
    std::vector<Body> bodies;
    std::vector<ContactSurface> surfaces; ///< with contact: one per body (body order), then one per
                                          ///< mesh obstacle; else empty
    std::vector<SurfaceMesh> obstacle_meshes; ///< rigid, static closed surfaces (mesh obstacles)
    std::vector<ContactPoint> contacts;   ///< the last detection, sorted by (body, vertex, other)
    std::vector<PlaneObstacle> planes;    ///< rigid half-space obstacles (plane obstacles)
    std::vector<VecX> contact_forces;     ///< per body #3V: contact forces of the last detection [N]

    Index num_tets() const;
    Index num_vertices() const;
};

/// What a run measured (DESIGN.md, OUT/NAME.summary.json).
struct RunSummary {
    Index steps = 0;               ///< time steps (dynamic) or load steps (static) done
    double wall_s = 0.0;           ///< wall time of the loop, loading excluded [s]
    double steps_per_s = 0.0;      ///< steps / wall_s
    PhaseTimes phases;             ///< seconds per phase
    double cg_iterations_mean = 0.0; ///< PCG iterations per solve
    double cg_residual_mean = 0.0;   ///< relative residual after each solve, averaged
    Index solves = 0;              ///< PCG solves done
    Index solves_not_converged = 0; ///< solves that stopped at the iteration cap
    Index static_not_converged = 0; ///< static load steps that missed static_tolerance
    double max_contact_depth = 0.0;  ///< deepest penetration seen by any detection [m]
    double contacts_mean = 0.0;      ///< inside vertices per detection
    Index detections = 0;            ///< detection passes (initial state and every step)
    Index embree_disagreements = 0;  ///< with cross_check = "embree": vertices where Embree and
                                     ///< the axis-ray test disagreed, summed over all detections
};

/// Called for every frame to write: (step, simulated time or load factor).
using FrameCallback = std::function<void(Index step, double time)>;
/// Called after every step: (steps done, steps in total).
using ProgressCallback = std::function<void(Index done, Index total)>;

/// Runs a scene as its case says.
class Simulation {
public:
    /// @param[in,out] scene  bodies, advanced in place; must outlive the Simulation. With contact
    ///                       enabled, its contact surfaces are built here.
    /// @param[in] spec       settings (simulation, solver, contact); bodies are already in `scene`
    /// @throws InputError if cross_check = "embree" and the build has no Embree
    Simulation(Scene& scene, const CaseSpec& spec);

    /// Runs `steps` time steps (dynamic) or all load steps (static). Frame 0 is the initial
    /// state; then every output_every-th step and the last (every load step when static).
    /// With contact enabled, detection runs on the initial state and after every step.
    /// @throws NumericalError prefixed with "step N: " when the simulation diverges
    RunSummary run(Index steps, const FrameCallback& on_frame, const ProgressCallback& on_progress);

    ~Simulation();
    Simulation(const Simulation&) = delete;
    Simulation& operator=(const Simulation&) = delete;

private:
    void detect(RunSummary& summary);
    void dynamic_step(RunSummary& summary);
    void static_step(Index load_step, RunSummary& summary);

    Scene& m_scene;
    const CaseSpec& m_spec;
    struct EmbreeCheck;
    std::unique_ptr<EmbreeCheck> m_embree; // cross-check scenes, when asked for
    ContactResponse m_response;            // of the last detection, used by the next step
};

/// PCG settings from the case's [solver] table.
PcgSettings pcg_settings(const SolverSettings& solver);

} // namespace coro
