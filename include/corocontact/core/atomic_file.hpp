#pragma once
/// @file atomic_file.hpp
/// @brief Files that are written whole or not at all: the bytes go to a temporary name in the
/// same folder, are flushed to the disk (fsync), and the temporary is renamed over the target.
/// A reader (ParaView, a restart) sees the old file or the new one, never a part of one, also
/// after a crash; a failed write leaves no temporary behind.
///
/// Cost: an fsync is a journal commit (milliseconds on a disk, for every file synced),
/// so files written many times a run (a frame's blocks) skip it, and the file listing them
/// (the .pvd) takes it.

#include <filesystem>
#include <string_view>

namespace coro {

/// Where write_file_atomically and commit_file stage `path`: `path` + ".tmp".
std::filesystem::path temporary_path(const std::filesystem::path& path);

/// Whether a write waits until its bytes are on the disk before the rename.
enum class Sync {
    FILE, ///< fsync before the rename: after a crash `path` holds the old or the new bytes, whole
    NONE, ///< no fsync (a new file that nothing lists yet, where an fsync per file costs too much)
};

/// Writes `bytes` to temporary_path(path) and renames it to `path`. The rename reaches the
/// disk with the file system's next commit; a crash before it leaves the previous `path`.
/// @throws OutputError naming the file and the system's reason (strerror, e.g. "No space left
///         on device"); the temporary is removed and `path` is left as it was
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes, Sync sync = Sync::FILE);

/// Moves a temporary file that another writer (VTK) has filled into place (rename, no fsync).
/// @param[in] temporary  the finished file, in the same folder as `path`
/// @throws OutputError naming the file and the system's reason; the temporary is removed
void commit_file(const std::filesystem::path& temporary, const std::filesystem::path& path);

/// Removes `temporary` after a failed write, if it is a regular file; never throws.
void remove_temporary(const std::filesystem::path& temporary) noexcept;

} // namespace coro
