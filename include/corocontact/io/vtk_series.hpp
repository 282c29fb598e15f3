#pragma once
/// @file vtk_series.hpp
/// @brief A time series for ParaView: NAME.pvd listing NAME_<step>.vtm, one .vtu per block.

#include <corocontact/core/types.hpp>

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace coro {

/// A named data array: #rows × components (1 for scalars, 3 for vectors).
struct DataArray {
    std::string name;
    Eigen::MatrixXd values;
};

/// One block of a frame: a body's tet mesh, or a triangle surface (set exactly one of tets
/// and tris).
struct FrameBlock {
    std::string name;                   ///< block name shown in ParaView (the body's name)
    Positions points;                   ///< #V×3 current positions, in the input node order
    Tets tets;                          ///< #T×4, or empty
    Tris tris;                          ///< #F×3, or empty
    std::vector<DataArray> point_data;  ///< each #V×k
    std::vector<DataArray> cell_data;   ///< each #T×k (or #F×k)
};

/// Writes frames with VTK's XML writers into `dir`:
/// `dir/NAME_<step>/<block>.vtu`, `dir/NAME_<step>.vtm` referencing them, and `dir/NAME.pvd`
/// listing every complete frame with its time. Every file is written under a temporary name
/// and renamed, and the .pvd is rewritten after each frame, so a run stopped at any moment
/// leaves a series whose every listed file loads.
class VtkSeriesWriter {
public:
    /// Creates `dir` if needed; removes nothing.
    /// @throws InputError if the directory cannot be created
    VtkSeriesWriter(std::filesystem::path dir, std::string name);

    /// Writes one frame and appends it to the .pvd.
    /// @param[in] step    step number used in the file names (zero-padded to 6 digits)
    /// @param[in] time    simulated time [s] written to the .pvd
    /// @param[in] blocks  the frame's blocks, written in this order
    /// @throws InputError if a file cannot be written (names the file)
    void write_frame(Index step, double time, const std::vector<FrameBlock>& blocks);

    /// One process's share of a frame that several write (a distributed run): the blocks it
    /// holds, each under the file name of its place among `names` (what write_frame() gives
    /// the same block). The frame is listed by list_frame() once every share is written.
    /// @param[in] names   every block of the frame, in frame order: the same on every process
    /// @param[in] blocks  this process's blocks, each named in `names`
    /// @throws InputError if a file cannot be written (names the file)
    void write_blocks(Index step, const std::vector<std::string>& names, const std::vector<FrameBlock>& blocks);

    /// Writes the .vtm of a frame whose blocks (`names`, in frame order) are written, and
    /// appends the frame to the .pvd. write_frame() is write_blocks() of all blocks and this.
    /// @throws InputError if a file cannot be written (names the file)
    void list_frame(Index step, double time, const std::vector<std::string>& names);

    /// Lists a frame that an earlier run wrote into the same directory (a restart continues
    /// its series) without writing anything: the next .pvd lists it before the new frames.
    /// @param[in] step  step number of the frame on disk
    /// @param[in] time  its simulated time [s]
    /// @throws InputError if `dir/NAME_<step>.vtm` does not exist
    void adopt_frame(Index step, double time);

    /// Path of the .pvd collection.
    std::filesystem::path pvd_path() const;
    /// Number of frames written so far.
    std::size_t num_frames() const { return m_frames.size(); }

private:
    struct FrameEntry {
        double time;
        std::string vtm; // relative to m_dir
    };
    void write_pvd() const;

    std::filesystem::path m_dir;
    std::string m_name;
    std::vector<FrameEntry> m_frames;
};

} // namespace coro
