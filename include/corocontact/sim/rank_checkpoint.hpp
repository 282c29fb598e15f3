#pragma once
/// @file rank_checkpoint.hpp
/// @brief Checkpoints of a distributed run: rank 0 gathers every body's part and writes the
/// file one process writes (sim/checkpoint.hpp), so a run saved on K processes continues on any
/// number of them, one included. Every process restores its own bodies from that one file, which
/// all must see (a shared file system).

#include <corocontact/sim/body_ownership.hpp>
#include <corocontact/sim/checkpoint.hpp>

namespace coro {

/// write_checkpoint() of the whole case from its processes. Collective; a failure to write
/// throws on every process.
void write_checkpoint(const std::filesystem::path& path, const Scene& scene, const SceneDistribution& distribution,
                      const CheckpointState& state, std::uint64_t fingerprint);

} // namespace coro
