#pragma once
/// @file rank_exchange.hpp
/// @brief The SceneExchange of a scene whose bodies are spread over the processes of a
/// Communicator: chunk sums gathered and added per component in the global chunk order, and
/// the halo of the coupling terms.

#include <corocontact/core/communicator.hpp>
#include <corocontact/solver/scene_exchange.hpp>

#include <vector>

namespace coro {

class RankExchange final : public SceneExchange {
public:
    /// Which rows a process sends to its neighbours and which ghost rows it receives from them.
    struct Halo {
        std::vector<int> ranks;                     ///< the neighbours, no repeats, not this process
        std::vector<std::vector<Index>> send_rows;  ///< per neighbour: own rows it reads, in the order
                                                    ///< it stores them
        std::vector<std::vector<Index>> ghost_rows; ///< per neighbour: ghost rows (0 = the first after
                                                    ///< the own rows) it fills, in the order it sends
        Index num_ghosts = 0;                       ///< G
    };

    /// Collective: learns every process's chunks to fix the global chunk order (by case body,
    /// then each body's chunks in order). Every case body is its own component until
    /// set_components().
    /// @param[in] communicator  must outlive this object
    /// @param[in] chunk_bodies  for each chunk of this process's scene matrix, the case index of
    ///                          its body (ascending, as the matrix's chunks are)
    /// @param[in] num_rows      N: the rows of this process's bodies
    RankExchange(Communicator& communicator, const std::vector<Index>& chunk_bodies, Index num_rows);

    /// Sets the components of the whole scene (the same on every process).
    /// @param[in] component_of_body  for every case body, its component: 0, 1, … in the order
    ///                               of each component's first body (contact_components)
    void set_components(std::vector<Index> component_of_body);
    /// K: components of the whole scene.
    Index num_components() const { return m_num_components; }

    /// Sets the halo of the coupling terms now in the matrix (until the next call).
    void set_halo(Halo halo);
    const Halo& halo() const { return m_halo; }

    Index num_ghost_rows() const override { return m_halo.num_ghosts; }
    void update_ghosts(double* x) override;
    void sum_by_component(const double* partials, int width, double* totals) override;

private:
    Communicator& m_communicator;
    Index m_rows;
    std::vector<int> m_chunk_counts;  // #ranks: chunks of each process
    std::vector<int> m_chunk_offsets; // #ranks: the first of each process's chunks in the gathered list
    std::vector<Index> m_order;       // #all chunks: gathered position of each chunk, in global order
    std::vector<Index> m_order_body;  // #all chunks: case body of each chunk, in global order
    std::vector<Index> m_component_of_body; // #case bodies
    Index m_num_components = 0;
    std::vector<int> m_counts, m_displacements; // of one gather (chunk counts × width)
    std::vector<double> m_gathered;
    Halo m_halo;
    std::vector<std::vector<double>> m_send, m_receive;
};

} // namespace coro
