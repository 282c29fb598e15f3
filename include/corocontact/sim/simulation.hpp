#pragma once
/// @file simulation.hpp
/// @brief The scene and its time loop (dynamic) or load-step loop (static).

#include <corocontact/sim/body.hpp>
#include <corocontact/sim/case_spec.hpp>
#include <corocontact/sim/phase_times.hpp>
#include <corocontact/solver/pcg.hpp>

#include <functional>
#include <vector>

namespace coro {

/// All bodies of a case.
struct Scene {
    std::vector<Body> bodies;

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
};

/// Called for every frame to write: (step, simulated time or load factor).
using FrameCallback = std::function<void(Index step, double time)>;
/// Called after every step: (steps done, steps in total).
using ProgressCallback = std::function<void(Index done, Index total)>;

/// Runs a scene as its case says.
class Simulation {
public:
    /// @param[in,out] scene  bodies, advanced in place; must outlive the Simulation
    /// @param[in] spec       settings (simulation, solver); bodies are already in `scene`
    Simulation(Scene& scene, const CaseSpec& spec);

    /// Runs `steps` time steps (dynamic) or all load steps (static). Frame 0 is the initial
    /// state; then every output_every-th step and the last (every load step when static).
    /// @throws NumericalError prefixed with "step N: " when the simulation diverges
    RunSummary run(Index steps, const FrameCallback& on_frame, const ProgressCallback& on_progress);

private:
    void dynamic_step(RunSummary& summary);
    void static_step(Index load_step, RunSummary& summary);

    Scene& m_scene;
    const CaseSpec& m_spec;
};

/// PCG settings from the case's [solver] table.
PcgSettings pcg_settings(const SolverSettings& solver);

} // namespace coro
