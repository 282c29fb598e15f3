#pragma once
/// @file rank_contact.hpp
/// @brief Contact detection and response of a scene whose bodies are spread over processes
/// (DESIGN.md, "Beyond one machine: OpenMPI").
///
/// Each detection, on every process: the boxes of all bodies are gathered and the same
/// sort-and-sweep finds the same pairs everywhere. A pair belongs to the owner of its lower
/// body (obstacle pairs to rank 0), which receives the other body's surface — its topology and
/// the start positions of its nodes the first time, its nodes' positions and velocities every
/// time — and detects both directions. The copy is built and moved by the code that builds and
/// moves the owner's surface (ContactSurface::from_body or from_embedding, then update), so it
/// answers bit for bit as the owner's would. The terms of every contact go, with the contact, to the owners of the nodes it
/// touches, and each process adds those of its rows in the order of the contacts' keys (body,
/// vertex, other) in the case's numbering: the order in which one process holding every body
/// adds them. Forces, coupling terms and the halo of the PCG are therefore those of one
/// process, bit for bit.
///
/// The scene's surfaces are this process's: its bodies' (scene order), the obstacle meshes',
/// then the copies of remote bodies received so far (kept, so topology is sent once).

#include <corocontact/contact/contact_surface.hpp>
#include <corocontact/contact/detector.hpp>
#include <corocontact/core/communicator.hpp>
#include <corocontact/sim/body_ownership.hpp>
#include <corocontact/sim/case_spec.hpp>
#include <corocontact/sim/contact_response.hpp>
#include <corocontact/solver/rank_exchange.hpp>

#include <cstdint>
#include <vector>

namespace coro {

struct Scene;

class RankContact {
public:
    /// What one detection found, counted where it was detected (sums over processes are the
    /// one-process numbers).
    struct Counts {
        Index contacts = 0;     ///< contact points detected here
        Index cross_rank = 0;   ///< of those, touching nodes of another process
        double max_depth = 0.0; ///< deepest of them [m]
    };

    /// Collective. Takes the scene's surfaces as they are now (built from the start positions)
    /// for the topology it sends.
    /// @param[in] communicator  must outlive this object
    /// @param[in] ownership     the owner of every case body
    /// @param[in] body_ids      case index of each body of `scene`, ascending
    /// @param[in] scene         this process's bodies with their surfaces (make_scene_surfaces)
    RankContact(Communicator& communicator, const BodyOwnership& ownership, std::vector<Index> body_ids,
                const Scene& scene);

    /// One detection on the current positions and its response on this process's rows (see the
    /// file comment). Collective.
    /// @param[in,out] scene  surfaces updated (remote copies added); contacts := the contact
    ///                       points of this process's bodies' vertices (`body` in scene order,
    ///                       `other` in the case's numbering: bodies, then obstacle meshes, or
    ///                       a plane); contact_forces := the forces on its nodes
    /// @param[in,out] response  applied to this process's rows
    /// @param[in,out] matrix    the scene matrix: its coupling terms refilled, its components
    ///                          those of the whole scene (contact_components of every box)
    /// @param[in,out] exchange  its halo set to the coupling's ghost rows, its components set
    Counts detect(Scene& scene, const ContactSettings& settings, double dt, ContactResponse& response,
                  SceneMatrix& matrix, RankExchange& exchange);

private:
    /// A remote body's surface held here, and the nodes under it.
    struct Copy {
        Index body = -1;              // case index
        Index surface = -1;           // index in the scene's surfaces
        std::vector<Index> nodes;     // ascending: the body nodes the surface moves with
        Positions positions;          // #V×3: the body's node positions, rows of `nodes` known [m]
        std::vector<Vec3> velocities; // of `nodes` [m/s]
        std::vector<char> fixed;      // of `nodes`
        std::size_t slot(Index node) const;
    };
    class Nodes;

    /// Rank of the process that detects pair (a, b), a < b, case surface numbering.
    Index pair_owner(Index a) const;
    /// Sends the surfaces of this process's bodies to the owners of their pairs, and takes in
    /// those it needs itself (copies created or refreshed). Collective.
    void exchange_surfaces(const std::vector<std::pair<Index, Index>>& pairs, Scene& scene);
    /// Scene surface of a case surface (bodies, then obstacle meshes), or −1 if not held here.
    Index local_surface(Index global) const;
    /// Case surface of a scene surface.
    Index global_surface(Index surface) const;

    Communicator& m_communicator;
    BodyOwnership m_ownership;
    std::vector<Index> m_ids;          // scene body → case body
    std::vector<Index> m_local;        // case body → scene body, or −1
    Index m_num_bodies = 0;            // N: bodies of the case
    Index m_num_obstacles = 0;         // obstacle meshes
    std::vector<std::vector<Index>> m_rank_bodies; // per rank, its case bodies ascending
    std::vector<Index> m_components;       // case body → component of the whole scene
    std::vector<Index> m_local_components; // scene body → component of the whole scene
    // Owner side, per scene body: the nodes its surface moves with, their start positions (the
    // surface and its tree were built from them), and whether each rank has its topology.
    std::vector<std::vector<Index>> m_surface_nodes;
    std::vector<std::vector<Vec3>> m_start_positions;
    std::vector<std::vector<char>> m_topology_sent;
    // Receiver side.
    std::vector<Copy> m_copies;
    std::vector<Index> m_copy_of;      // case body → index in m_copies, or −1
    // Buffers kept between detections.
    std::vector<std::vector<char>> m_send, m_receive;
    ContactRecords m_records;
    DetectionScratch m_detection;
};

} // namespace coro
