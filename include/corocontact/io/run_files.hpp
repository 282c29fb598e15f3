#pragma once
/// @file run_files.hpp
/// @brief The files a run of series NAME writes into its output folder, besides the VTK series
/// itself (NAME.pvd, NAME_<step>.vtm, NAME_<step>/<block>.vtu: vtk_series.hpp): the summary
/// and the checkpoint; and the removal of what an earlier run of the same series left there.

#include <corocontact/core/types.hpp>

#include <filesystem>
#include <string>

namespace coro {

/// `DIR/NAME.summary.json`.
std::filesystem::path summary_path(const std::filesystem::path& dir, const std::string& name);

/// `DIR/NAME.checkpoint`.
std::filesystem::path checkpoint_path(const std::filesystem::path& dir, const std::string& name);

/// What remove_earlier_run removed.
struct RemovedFiles {
    Index frames = 0; ///< frames (a .vtm with its folder of .vtu files)
    Index files = 0;  ///< files of any kind, the frames' included
    bool checkpoint = false; ///< the earlier run's checkpoint was one of them
};

/// Removes what an earlier run of series `name` left in `dir`, so that nothing of it stands
/// beside the series this run writes: its .pvd (first, so that it never lists a removed frame),
/// its frames after step `keep_through_step` (all of them when it is negative), its summary,
/// every temporary file of the series, and its checkpoint unless `keep_checkpoint`. Other
/// series and anything else in `dir` stay, and so does a frame folder holding files other
/// than .vtu. Call it while holding the folder's OutputLock.
/// @param[in] keep_through_step  a restart keeps the frames up to its checkpoint's step; a
///                               fresh run passes -1
/// @throws OutputError if a file cannot be removed (the path and the system's reason)
RemovedFiles remove_earlier_run(const std::filesystem::path& dir, const std::string& name, Index keep_through_step,
                                bool keep_checkpoint);

} // namespace coro
