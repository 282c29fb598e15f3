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
#include <corocontact/sim/divergence_check.hpp>
#include <corocontact/sim/phase_times.hpp>
#include <corocontact/solver/pcg.hpp>

#include <atomic>
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
    Index first_step = 0;            ///< the step the loop started from (> 0 after a restart)
    int stop_signal = 0;             ///< the signal that stopped the loop early, or 0
};

/// Called for every frame to write: (step, simulated time or load factor).
using FrameCallback = std::function<void(Index step, double time)>;
/// Called after every step: (steps done, steps in total).
using ProgressCallback = std::function<void(Index done, Index total)>;
/// Called to save the state after step `step` (the scene holds it). In `so_far` the *_mean
/// fields still hold sums and contacts_mean the sum over detections (what a restart needs to
/// continue them); wall_s is the loop time up to now.
using CheckpointCallback = std::function<void(Index step, const RunSummary& so_far)>;

/// Optional controls of a run: stopping on request, checkpoints, continuing a saved run.
struct RunControl {
    /// Polled before the first step and after every step; non-zero stops the loop after the
    /// step in progress (its frame is written) and is reported in RunSummary::stop_signal.
    const std::atomic<int>* stop = nullptr;
    /// > 0: on_checkpoint after every checkpoint_every-th step, after the last step and when
    /// stopped early.
    Index checkpoint_every = 0;
    CheckpointCallback on_checkpoint;
    /// > 0: the scene already holds the state after this step (a restart). The loop continues
    /// with the next step; frame 0 is not written; the initial detection rebuilds the contact
    /// response without counting, and `resume_summary` (as a CheckpointCallback received it)
    /// supplies the counters so far.
    Index resume_step = 0;
    RunSummary resume_summary;
};

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
    /// After every step the bodies are checked for divergence (sim/divergence_check.hpp).
    /// @param[in] control  stop flag, checkpoints, restart (see RunControl)
    /// @throws NumericalError prefixed with "step N (t = ...): " when the simulation diverges
    /// @throws InputError if control.resume_step is not below the last step
    RunSummary run(Index steps, const FrameCallback& on_frame, const ProgressCallback& on_progress,
                   const RunControl& control = {});

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
    DetectionScratch m_detection;          // detect_contacts' working memory, kept from step to step
    DivergenceCheck m_divergence;          // run after every step
};

/// PCG settings from the case's [solver] table.
PcgSettings pcg_settings(const SolverSettings& solver);

} // namespace coro
