#pragma once
/// @file checkpoint.hpp
/// @brief The whole state of a run after a step, saved to a file and restored into a freshly
/// loaded scene, so the continued run writes frames bitwise equal to an uninterrupted one.
///
/// What the next step depends on: every body's positions and velocities (the PCG warm start is
/// v) and its element rotations R_e (update_rotations warm-starts from them, and the von Mises
/// stress of a frame uses them as well). Everything else a step reads is either constant (mesh,
/// material, fixed nodes, loads) or recomputed from the positions and velocities before it is
/// used: the contact surfaces and their trees (refit from the positions), the detection, the
/// penalty response with its lagged friction coefficient, the PCG preconditioner. The file also
/// carries the step, the run's counters (RunSummary, sums not yet averaged) and the frames
/// written so far, so the summary and the .pvd of the continued run cover the whole run.
///
/// Format (native little-endian, version 1): "COROCKPT", u32 version, u64 case fingerprint,
/// the body table (name, #V, #T, METIS parts), step, counters, frames, then per body positions
/// and velocities in mesh file node order (#V×3 doubles each) and rotations in mesh file tet
/// order (#T×9 doubles, column-major), then "END!" and a u64 FNV-1a checksum of all bytes
/// before it. Written through core/atomic_file.hpp (temporary name, fsync, rename).

#include <corocontact/sim/simulation.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace coro {

/// A frame already written: its step and simulated time (or load factor).
struct FrameRecord {
    Index step = 0;
    double time = 0.0;
};

/// What a checkpoint holds besides the bodies' state.
struct CheckpointState {
    Index step = 0;                  ///< steps done
    RunSummary summary;              ///< counters as CheckpointCallback received them
    std::vector<FrameRecord> frames; ///< frames written up to `step`, in order
};

/// A 64-bit fingerprint of a case: FNV-1a of the case file's bytes (spec.file). A checkpoint
/// only restarts the case it was written by.
/// @throws InputError if the case file cannot be read
std::uint64_t case_fingerprint(const CaseSpec& spec);

/// Saves the scene's state and `state` to `path` (temporary file + rename).
/// @throws OutputError naming the file and the system's reason if it cannot be written (no
///         temporary is left)
void write_checkpoint(const std::filesystem::path& path, const Scene& scene, const CheckpointState& state,
                      std::uint64_t fingerprint);

/// One body's part of a checkpoint, in the file's format: its entry of the body table and its
/// state. A distributed run gathers these on rank 0, which writes the one-process file.
struct CheckpointBody {
    std::string entry;
    std::string state;
};
CheckpointBody checkpoint_body(const Body& body);

/// write_checkpoint() from the parts of every body of the case, in case order.
void write_checkpoint(const std::filesystem::path& path, const std::vector<CheckpointBody>& bodies,
                      const CheckpointState& state, std::uint64_t fingerprint);

/// Restores the bodies' positions, velocities and rotations from `path` into `scene`, which
/// must be the freshly loaded scene of the same case.
/// @param[out] warnings  appended to, e.g. when a body is split into a different number of
///                       METIS parts than when saved (the run continues, but not bitwise)
/// @return the step, counters and frames saved with it
/// @throws InputError naming the file if it is not a checkpoint, is truncated or corrupt, or
///         belongs to another case (fingerprint, body names or counts differ)
CheckpointState read_checkpoint(const std::filesystem::path& path, Scene& scene, std::uint64_t fingerprint,
                                std::vector<std::string>& warnings);

/// A warning about one body of the case: its case index, the text.
using BodyWarning = std::pair<Index, std::string>;

/// read_checkpoint() into the scene of one process of a distributed run: its bodies are the
/// case's bodies `body_ids` (ascending) of `case_bodies`; the file is the one-process file.
/// @param[out] warnings  appended to, for this process's bodies, each with its case index (to
///                       be merged with the other processes' in case order)
CheckpointState read_checkpoint(const std::filesystem::path& path, Scene& scene, const std::vector<Index>& body_ids,
                                Index case_bodies, std::uint64_t fingerprint, std::vector<BodyWarning>& warnings);

} // namespace coro
