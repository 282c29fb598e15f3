#pragma once
/// @file scene_output.hpp
/// @brief What a frame shows of a scene, and the run summary file.

#include <corocontact/io/vtk_series.hpp>
#include <corocontact/sim/simulation.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace coro {

/// One block per body: current positions in input node order, point data `displacement` and
/// `velocity` (#V×3), cell data `von_mises` (#T, Pa); `<body>_surface` for an embedded
/// surface; `obstacle<k>` for the k-th mesh obstacle; `plane<k>` for the k-th plane obstacle,
/// a rectangle of the plane covering the scene's bounds at rest (two triangles).
std::vector<FrameBlock> scene_frame(const Scene& scene);

/// What OUT/NAME.summary.json holds besides the RunSummary.
struct SummaryContext {
    std::string name;
    Index threads = 1;
    Index bodies = 0;
    Index tets = 0;
    double peak_rss_mb = 0.0;
    double setup_s = 0.0; ///< wall time before the first step: reading, meshing, loading [s]
};

/// The summary as JSON text (keys of DESIGN.md: steps, wall_s (the time loop only),
/// steps_per_s, setup_s (before the loop), threads, bodies, tets,
/// phases{rotation,assembly,solve,contact,output}, cg_iterations_mean, cg_residual_mean,
/// peak_rss_mb, plus solves, solves_not_converged and static_not_converged).
std::string summary_json(const RunSummary& summary, const SummaryContext& context);

} // namespace coro
