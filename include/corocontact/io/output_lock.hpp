#pragma once
/// @file output_lock.hpp
/// @brief One run per output folder: the lock file `DIR/corocontact.lock`, held with flock(2)
/// while a run writes there, so a second run into the same folder refuses at once instead of
/// mixing its frames into the first one's series.
///
/// The kernel lets go of the lock when its process ends, however it ends: a lock file left by
/// a run killed with SIGKILL is recognised as stale and taken over.

#include <filesystem>
#include <string>
#include <vector>

namespace coro {

class OutputLock {
public:
    /// Creates `dir` if needed and takes its lock; the lock file then names this process
    /// (pid, host, start time in UTC, `command`).
    /// @param[in] dir      the output folder
    /// @param[in] command  what runs, for the message another run gets ("corocontact run x.toml")
    /// @throws OutputError if the folder cannot be created or the lock file written (the path
    ///         and the system's reason), or if another run holds the lock: the message names
    ///         that run as its lock file describes it
    OutputLock(std::filesystem::path dir, const std::string& command);

    /// Removes the lock file and lets go of the lock; removes the folders this lock made too,
    /// as far as they are empty (a run refused for bad input leaves nothing behind).
    ~OutputLock();

    OutputLock(const OutputLock&) = delete;
    OutputLock& operator=(const OutputLock&) = delete;

    /// `DIR/corocontact.lock`.
    std::filesystem::path path() const;

    /// What the lock file of a run that ended without removing it said ("pid 4242 on host h,
    /// started 2026-11-26 10:00:00 UTC: corocontact run x.toml"), when this lock took it over;
    /// empty otherwise. The caller may warn about it.
    const std::string& stale_owner() const { return m_stale_owner; }

private:
    void remove_created_folders() const;

    std::filesystem::path m_dir;
    int m_fd = -1;
    std::vector<std::filesystem::path> m_created; ///< folders this lock made, deepest first
    std::string m_stale_owner;
};

} // namespace coro
