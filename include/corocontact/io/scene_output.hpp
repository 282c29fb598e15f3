#pragma once
/// @file scene_output.hpp
/// @brief What a frame shows of a scene, and the run summary file.

#include <corocontact/io/vtk_series.hpp>
#include <corocontact/sim/simulation.hpp>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace coro {

/// One block per body: current positions in input node order, point data `displacement` and
/// `velocity` (#V×3), cell data `von_mises` (#T, Pa); `<body>_surface` for an embedded
/// surface; `obstacle<k>` for the k-th mesh obstacle; `plane<k>` for the k-th plane obstacle,
/// a rectangle of the plane covering the scene's bounds at rest (two triangles).
std::vector<FrameBlock> scene_frame(const Scene& scene);

/// The blocks of scene_frame() that show the bodies (each body's, and `<body>_surface` after
/// it for an embedded surface), in body order.
std::vector<FrameBlock> body_blocks(const Scene& scene);

/// The names of the blocks body_blocks() makes of `body`.
std::vector<std::string> body_block_names(const Body& body);

/// The blocks of scene_frame() that show the obstacles: `obstacle<k>`, then `plane<k>` drawn
/// over `bounds` (lowest, highest corner).
std::vector<FrameBlock> obstacle_blocks(const Scene& scene, const std::pair<Vec3, Vec3>& bounds);

/// The box planes are drawn over: the bodies' rest positions, the obstacle meshes and the
/// planes' points (lowest, highest corner). A distributed run takes it over all processes.
std::pair<Vec3, Vec3> rest_bounds(const Scene& scene);

/// One process of a distributed run, in the summary.
struct RankLoad {
    Index bodies = 0;
    Index tets = 0;
    double mpi_bytes_per_step = 0.0; ///< received from the other processes per step [B]
    double solve_bytes_per_step = 0.0; ///< of those, in the PCG (halo and dot products) [B]
};

/// What OUT/NAME.summary.json holds besides the RunSummary.
struct SummaryContext {
    std::string name;
    Index threads = 1;
    Index bodies = 0;
    Index tets = 0;
    double peak_rss_mb = 0.0;
    double setup_s = 0.0; ///< wall time before the first step: reading, meshing, loading [s]
    Index ranks = 1;                ///< processes of the run
    std::vector<RankLoad> per_rank; ///< distributed: one per process, rank order; else empty
    double cross_rank_contacts_mean = 0.0; ///< distributed: contact points per detection whose
                                           ///< nodes lie on two or more processes
};

/// The summary as JSON text (keys of DESIGN.md: steps, wall_s (the time loop only),
/// steps_per_s, setup_s (before the loop), threads, bodies, tets, ranks, mpi_bytes_per_step
/// (the mean over the processes, 0 in one process; distributed also cross_rank_contacts_mean
/// and per_rank: rank, bodies, tets, mpi_bytes_per_step, solve_bytes_per_step),
/// phases{rotation,assembly,solve,contact,output}, cg_iterations_mean, cg_residual_mean,
/// peak_rss_mb, plus solves, solves_not_converged and static_not_converged).
std::string summary_json(const RunSummary& summary, const SummaryContext& context);

} // namespace coro
