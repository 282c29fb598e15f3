#pragma once
/// @file scene_exchange.hpp
/// @brief What a scene system spread over several processes needs from the others during a
/// solve: the values of the coupled rows they own (the halo), and sums over all chunks of all
/// processes in the global chunk order, per component of the scene (DESIGN.md, "Beyond one
/// machine: OpenMPI").
///
/// A process holds the rows of its own bodies (the scene matrix's rows) followed by G ghost
/// rows: rows of other processes' bodies that its contact coupling terms read. Chunks are
/// defined by bodies, so the global chunk order (body order, then each body's chunks) is the
/// same for any number of processes, and a sum formed in it gives the bits of one process.
/// A one-process solve has no exchange and pays nothing for this interface.

#include <corocontact/core/types.hpp>

namespace coro {

class SceneExchange {
public:
    virtual ~SceneExchange() = default;

    /// G: the ghost rows that follow the matrix's own rows in the vectors given to
    /// update_ghosts() (coupling columns ≥ #rows name them).
    virtual Index num_ghost_rows() const = 0;

    /// Writes the owners' current values into the ghost rows of x. Collective.
    /// @param[in,out] x  #3(N + G): rows [0, N) this process's (read), [N, N + G) ghosts (written)
    virtual void update_ghosts(double* x) = 0;

    /// totals[k·width + j] = Σ partials[c·width + j] over every chunk c of component k, of
    /// every process, added one after another in the global chunk order starting from 0.0:
    /// the per-component sums of one process holding every body. Collective.
    /// @param[in] partials  #chunks × width, this process's chunks in its own (ascending) order
    /// @param[in] width     values per chunk, ≥ 1
    /// @param[out] totals   #K × width, K the components of the whole scene
    ///                      (SceneMatrix::num_components of every process's matrix)
    virtual void sum_by_component(const double* partials, int width, double* totals) = 0;
};

} // namespace coro
