#pragma once
/// @file output_file.hpp
/// @brief A file the user names on the command line (`detect --csv PATH`): replaced whole when
/// it is a file, written through when it is something else (a named pipe, a device, a symlink).

#include <filesystem>
#include <string_view>

namespace coro {

/// Writes `bytes` to `path`. When `path` does not exist or is a regular file, through
/// write_file_atomically (a temporary beside it, fsync, rename), so a reader never sees half a
/// file. Anything else that exists there (lstat, so a symlink is not followed for this test) —
/// a named pipe, a device, a symlink — is opened and written to directly: a rename would
/// replace the pipe, the device node or the link itself with a regular file. A symlink's
/// target is then truncated and written in place.
/// @throws OutputError naming `path` and the system's reason (strerror)
void write_output_file(const std::filesystem::path& path, std::string_view bytes);

} // namespace coro
