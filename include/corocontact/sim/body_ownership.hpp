#pragma once
/// @file body_ownership.hpp
/// @brief Which process of a distributed run owns which bodies (DESIGN.md, "Beyond one machine:
/// OpenMPI"): whole bodies, balanced by tets, near bodies together.

#include <corocontact/core/communicator.hpp>
#include <corocontact/sim/body.hpp>

#include <vector>

namespace coro {

struct Scene;

/// The owner of every body of a case.
struct BodyOwnership {
    Index num_ranks = 1;
    std::vector<Index> owner; ///< #bodies (case order): the rank owning body b, in [0, num_ranks)

    /// The bodies of `rank`, ascending.
    std::vector<Index> bodies_of(Index rank) const;
};

/// Splits the bodies over `num_ranks` processes: METIS (partition_graph) on the bodies'
/// proximity graph — an edge where the bodies' boxes, each grown on every side by half the
/// mean largest box edge, overlap at the start — with each body weighing its tets. Near bodies share an owner,
/// so few contacts cross processes, and the tets per process differ by METIS' 3 % tolerance
/// where the bodies allow it. The same bodies and rank count always give the same owners.
/// @param[in] bodies     every body of the case, in case order (their current positions are used)
/// @param[in] num_ranks  ≥ 1
BodyOwnership assign_bodies(const std::vector<Body>& bodies, Index num_ranks);

/// A process's part of a distributed run.
struct SceneDistribution {
    Communicator* communicator = nullptr; ///< the run's processes; must outlive whoever uses this
    BodyOwnership ownership;              ///< the owner of every case body
    std::vector<Index> body_ids;          ///< the case index of each body this process holds, ascending
};

/// Keeps only the bodies of `rank` in `scene` (case order kept); the others are destroyed.
/// @return the case index of every body kept
std::vector<Index> keep_bodies_of(Scene& scene, const BodyOwnership& ownership, Index rank);

/// Splits a scene holding every body of the case over the processes and keeps this process's
/// bodies in it: assign_bodies() on rank 0, its owners sent to all, so every process holds the
/// same assignment. Collective.
/// @throws InputError on every process if they did not all load the same bodies
SceneDistribution distribute_scene(Scene& scene, Communicator& communicator);

} // namespace coro
