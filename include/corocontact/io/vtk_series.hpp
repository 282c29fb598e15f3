#pragma once
/// @file vtk_series.hpp
/// @brief A time series for ParaView: NAME.pvd listing NAME_<step>.vtm, one .vtu per block.

#include <corocontact/core/function_ref.hpp>
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
    /// @throws InputError for a name that is not a plain file name
    /// @throws OutputError if the folder cannot be created (the path and the system's reason)
    VtkSeriesWriter(std::filesystem::path dir, std::string name);

    /// Writes one frame and appends it to the .pvd.
    /// @param[in] step    step number used in the file names (zero-padded to 6 digits)
    /// @param[in] time    simulated time [s] written to the .pvd
    /// @param[in] blocks  the frame's blocks, written in this order
    /// @throws OutputError if a file cannot be written (the path and the system's reason); the
    ///         files of a new frame written before the failure are removed again, the .pvd
    ///         still lists the earlier frames
    void write_frame(Index step, double time, const std::vector<FrameBlock>& blocks);

    /// One process's share of a frame that several write (a distributed run): the blocks it
    /// holds, each under the file name of its place among `names` (what write_frame() gives
    /// the same block). The frame is listed by list_frame() once every share is written.
    /// @param[in] names   every block of the frame, in frame order: the same on every process
    /// @param[in] blocks  this process's blocks, each named in `names`
    /// @return the files written, for their writer to remove if another share fails
    /// @throws OutputError if a file cannot be written (the files written before are removed)
    std::vector<std::filesystem::path> write_blocks(Index step, const std::vector<std::string>& names,
                                                    const std::vector<FrameBlock>& blocks) const;

    /// Writes the .vtm of a frame whose blocks (`names`, in frame order) are written, and
    /// appends the frame to the .pvd: write_frame() is write_blocks() of every block and this.
    /// @throws OutputError if a file cannot be written (a new frame's .vtm is removed again)
    void list_frame(Index step, double time, const std::vector<std::string>& names);

    /// Lists a frame that an earlier run wrote into the same directory (a restart continues
    /// its series) without writing anything: the next .pvd lists it before the new frames.
    /// @param[in] step  step number of the frame on disk
    /// @param[in] time  its simulated time [s]
    /// @throws InputError if `dir/NAME_<step>.vtm` does not exist
    void adopt_frame(Index step, double time);

    /// Writes the .pvd listing the frames so far: write_frame does it after every frame; after
    /// adopt_frame it lists an earlier run's frames before the first new one is written.
    /// @throws OutputError if the file cannot be written
    void write_pvd() const;

    /// Path of the .pvd collection.
    std::filesystem::path pvd_path() const;
    /// Number of frames written so far.
    std::size_t num_frames() const { return m_frames.size(); }

private:
    struct FrameEntry {
        double time;
        std::string vtm; // relative to m_dir
    };
    /// Writes `blocks` of the frame whose blocks are `names`; appends each finished file to
    /// `written`.
    void write_block_files(const std::string& stem, const std::vector<std::string>& names,
                           const std::vector<FrameBlock>& blocks, std::vector<std::filesystem::path>& written) const;
    /// Writes the .vtm naming `names`; appends it to `written`.
    void write_vtm(const std::string& stem, const std::vector<std::string>& names,
                   std::vector<std::filesystem::path>& written) const;
    /// write_blocks(written) (the frame's .vtu files), then its .vtm and the .pvd; a new
    /// frame's files are all removed again if one cannot be written.
    void list_written_frame(Index step, double time, const std::vector<std::string>& names,
                            FunctionRef<void(std::vector<std::filesystem::path>& written)> write_blocks);

    std::filesystem::path m_dir;
    std::string m_name;
    std::vector<FrameEntry> m_frames;
};

} // namespace coro
