#pragma once
/// @file simulation.hpp
/// @brief The scene and its time loop (dynamic) or load-step loop (static).

#include <corocontact/sim/body.hpp>
#include <corocontact/sim/body_ownership.hpp>
#include <corocontact/sim/case_spec.hpp>
#include <corocontact/contact/contact_surface.hpp>
#include <corocontact/contact/detector.hpp>
#include <corocontact/contact/plane_obstacle.hpp>
#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/sim/contact_response.hpp>
#include <corocontact/sim/divergence_check.hpp>
#include <corocontact/sim/phase_times.hpp>
#include <corocontact/sim/scene_contact.hpp>
#include <corocontact/sim/scene_system.hpp>
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
    std::vector<ContactPoint> contacts;   ///< the last detection, sorted by (body, vertex, other);
                                          ///< distributed: those of this process's bodies' vertices,
                                          ///< `other` in the case's numbering (see rank_contact.hpp)
    std::vector<PlaneObstacle> planes;    ///< rigid half-space obstacles (plane obstacles)
    std::vector<VecX> contact_forces;     ///< per body #3V: contact forces of the last detection [N]

    Index num_tets() const;
    Index num_vertices() const;
};

/// What a run measured (DESIGN.md, OUT/NAME.summary.json).
struct RunSummary {
    Index steps = 0;               ///< time steps (dynamic) or load steps (static) done
    double wall_s = 0.0;           ///< wall time of the steps, frames and checkpoints, loading
                                   ///< excluded [s]
    double steps_per_s = 0.0;      ///< steps / wall_s
    PhaseTimes phases;             ///< seconds per phase
    double cg_iterations_mean = 0.0; ///< PCG iterations per solve
    double cg_residual_mean = 0.0;   ///< relative residual after each solve, averaged
    Index solves = 0;              ///< PCG solves done
    Index solves_not_converged = 0; ///< solves that stopped at the iteration cap
    PreconditionerTimes preconditioner; ///< AMG: hierarchy set-ups and V-cycles (their time is
                                        ///< part of phases.solve); zero for the other kinds
    Index static_not_converged = 0; ///< static load steps that missed static_tolerance
    double static_iterations_mean = 0.0; ///< static: Newton iterations per load step and body
    Index static_iterations_max = 0;     ///< static: the most Newton iterations of a load step
    double max_contact_depth = 0.0;  ///< deepest penetration seen by any detection [m]
    double contacts_mean = 0.0;      ///< inside vertices per detection
    Index detections = 0;            ///< detection passes (initial state and every step)
    Index embree_disagreements = 0;  ///< with cross_check = "embree": vertices where Embree and
                                     ///< the axis-ray test disagreed, summed over all detections
    Index first_step = 0;            ///< the step the loop started from (> 0 after a restart)
    int stop_signal = 0;             ///< the signal that stopped the loop early, or 0
};

/// What a distributed run measured (zero in one process).
struct RankStats {
    Index ranks = 1;                       ///< processes of the run
    double mpi_bytes_per_step = 0.0;       ///< payload this process received from the others per
                                           ///< step of this run (solve and contact, not output) [B]
    double solve_bytes_per_step = 0.0;     ///< of those, in the PCG: halo and dot products [B]
    double cross_rank_contacts_mean = 0.0; ///< contact points per detection of this run whose
                                           ///< nodes lie on two or more processes (all processes)
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

/// Runs a scene as its case says, all at once (run()) or step by step (start(), then step()).
class Simulation {
public:
    /// @param[in,out] scene  bodies, advanced in place; must outlive the Simulation, and its
    ///                       bodies must not be added or removed. With contact enabled, its
    ///                       contact surfaces are built here.
    /// @param[in] spec       settings (simulation, solver, contact); bodies are already in `scene`;
    ///                       must outlive the Simulation
    /// @param[in] distribution  null (one process holds every body), or this process's part of a
    ///                       distributed run: `scene` holds its bodies (keep_bodies_of); then
    ///                       construction and every call below are collective, and a failure on
    ///                       any process throws on all (run_collectively)
    /// @throws InputError if cross_check = "embree" and the build has no Embree, or the run is
    ///         distributed (the cross-check runs in one process)
    Simulation(Scene& scene, const CaseSpec& spec, const SceneDistribution* distribution = nullptr);

    /// Runs up to step `steps` (dynamic) or all load steps (static): start(), then step()
    /// until done or stopped. Frame 0 is the initial state; then every output_every-th step and
    /// the last (every load step when static).
    /// @param[in] control  stop flag, checkpoints, restart (see RunControl)
    /// @throws NumericalError as step()
    /// @throws InputError if control.resume_step is not below the last step
    RunSummary run(Index steps, const FrameCallback& on_frame, const ProgressCallback& on_progress,
                   const RunControl& control = {});

    /// Detection on the current state, before the first step(): the contact response the first
    /// step uses. After a restart (resume_step > 0) its counters are not added: `resume` holds
    /// the counters so far, as a CheckpointCallback received them.
    void start(Index resume_step = 0, const RunSummary& resume = {});

    /// One time step (dynamic) or the next load step (static), the divergence check, and the
    /// detection on the new state.
    /// @throws NumericalError prefixed with "step N (t = ...): " when the simulation diverges
    void step();

    /// Recomputes the contact response of the current state (the forces and coupling terms the
    /// next step uses) from the current velocities, fixed nodes and contact settings: for a
    /// caller that changed them between steps. Detection is not repeated (positions have not
    /// moved); counters are not changed. Does nothing where contact does not apply
    /// (run_notes.hpp contact_applies).
    void update_contact_response();

    /// Steps done, those before a restart included.
    Index steps_done() const { return m_step; }
    /// Simulated time after steps_done() [s], or the load factor (static).
    double time() const { return time_of(m_step); }
    /// Simulated time (dynamic) or load factor (static) after step `step`.
    double time_of(Index step) const;
    /// The counters so far, means taken (see RunSummary); distributed: of all processes
    /// (collective), timings this process's.
    RunSummary summary() const;
    /// The distributed run's measures (collective when distributed).
    RankStats rank_stats() const;

    ~Simulation();
    Simulation(const Simulation&) = delete;
    Simulation& operator=(const Simulation&) = delete;

private:
    void detect(RunSummary& summary);
    void dynamic_step();
    void static_step(Index load_step);
    /// Runs `work` (no communication in it) so that a failure on any process throws on all; of
    /// NumericalErrors about a body, the one about the first body in case order.
    void collectively(FunctionRef<void()> work);
    /// The counters of all processes (collective when distributed); *_mean fields still sums.
    RunSummary totals() const;
    /// Of the `text`s about a body of each process (`body`: index into this process's bodies,
    /// −1 for none), the one about the first body in case order, as one process finds it first
    /// (collective when distributed), or "".
    std::string first_over_processes(Index body, std::string text) const;
    /// locate_non_finite() of the first body with a non-finite value, in case order, or "".
    std::string first_non_finite() const;


    Scene& m_scene;
    const CaseSpec& m_spec;
    struct EmbreeCheck;
    std::unique_ptr<EmbreeCheck> m_embree; // cross-check scenes, when asked for
    struct Ranks;
    std::unique_ptr<Ranks> m_ranks;        // distributed: the exchanges with the other processes
    SceneSystem m_system;                  // the scene-wide implicit Euler step
    ContactResponse m_response;            // of the last detection, used by the next step
    std::vector<Index> m_components;       // contact_components() of the last detection
    DetectionScratch m_detection;          // detect_contacts' working memory, kept from step to step
    std::vector<ContactPoint> m_surface_contacts, m_plane_contacts; // a detection's, before their merge
    PlaneContactScratch m_plane_scratch;                           // detect_plane_contacts' working memory
    DivergenceCheck m_divergence;          // run after every step
    Index m_step = 0;                      // steps done
    RunSummary m_totals;                   // counters so far; *_mean fields hold sums
};

/// PCG settings from the case's [solver] table.
PcgSettings pcg_settings(const SolverSettings& solver);

} // namespace coro
