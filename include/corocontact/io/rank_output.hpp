#pragma once
/// @file rank_output.hpp
/// @brief What a distributed run writes (DESIGN.md, Output): each process the .vtu of its
/// bodies, rank 0 those of the obstacles, the .vtm naming every block, the .pvd and the summary
/// with a line per process. The frames are the files one process writes for the same state.

#include <corocontact/core/communicator.hpp>
#include <corocontact/io/scene_output.hpp>
#include <corocontact/io/vtk_series.hpp>
#include <corocontact/sim/simulation.hpp>

#include <string>
#include <utility>
#include <vector>

namespace coro {

class RankFrames {
public:
    /// Collective: learns the blocks of every process (their names, in case body order).
    /// @param[in] communicator  must outlive this object
    /// @param[in] writer        the series (every process's, on one shared folder); must outlive this
    /// @param[in] scene         this process's bodies and the obstacles
    /// @param[in] body_ids      the case index of each body of `scene`, ascending
    RankFrames(Communicator& communicator, VtkSeriesWriter& writer, const Scene& scene,
               const std::vector<Index>& body_ids);

    /// Writes one frame of the scene's current state. Collective; a file that cannot be written
    /// on any process throws OutputError on all (run_collectively), and the frame's files go.
    void write(Index step, double time, const Scene& scene);

private:
    Communicator& m_communicator;
    VtkSeriesWriter& m_writer;
    std::vector<std::string> m_names;  // every block of a frame, in frame order
    std::pair<Vec3, Vec3> m_bounds;    // of the whole scene at rest, for the plane obstacles
};

/// Every process's bodies, tets and bytes per step, on rank 0 (rank order; empty elsewhere).
/// Collective.
std::vector<RankLoad> gather_rank_loads(Communicator& communicator, const Scene& scene, const RankStats& stats);

} // namespace coro
