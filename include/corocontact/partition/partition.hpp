#pragma once
/// @file partition.hpp
/// @brief METIS partition of a body's tets into parts (subdomains) for the parallel element loop.

#include <corocontact/core/types.hpp>

#include <vector>

namespace coro {

/// Which part every tet belongs to.
struct TetPartition {
    Index num_parts = 1;
    std::vector<Index> tet_part; ///< #T, values in [0, num_parts)
    Index edge_cut = 0;          ///< faces shared by tets of different parts (METIS objective)

    /// Tets in each part, #parts.
    std::vector<Index> part_sizes() const;
    /// Largest part over the mean part size (1 = perfect balance).
    double imbalance() const;
};

/// Splits the tets into `num_parts` face-connected parts with METIS_PartMeshDual (ncommon = 3,
/// fixed seed, so the same mesh always gives the same partition). With one part, or more parts
/// requested than tets, every tet goes to part 0 … num_parts clamped to #T.
/// @param[in] tets          #T×4 node indices
/// @param[in] num_vertices  #V
/// @param[in] num_parts     ≥ 1
/// @throws InputError if num_parts < 1; NumericalError if METIS fails (its status is named)
TetPartition partition_tets(const Tets& tets, Index num_vertices, Index num_parts);

/// Fewest tets a part of a body should carry: a part is one task of the element loop, and a
/// task of fewer tets costs more to schedule than its work. Smaller bodies stay in one part; a
/// scene batches them into its work items (sim/scene_system.hpp).
constexpr Index MIN_TETS_PER_PART = 2048;

/// Default number of parts of a body: `parts_per_thread` × the machine's online cores (not
/// --threads, nor the CPU set a process is bound to, so 1 and 2 threads and every MPI binding
/// partition alike and give identical results), at most one part per MIN_TETS_PER_PART tets, at
/// least 1.
Index default_num_parts(Index num_tets, Index parts_per_thread);

} // namespace coro
