#include <corocontact/sim/rank_contact.hpp>

#include "detail/bytes.hpp"

#include <corocontact/contact/broad_phase.hpp>
#include <corocontact/contact/plane_obstacle.hpp>
#include <corocontact/core/error.hpp>
#include <corocontact/sim/scene_contact.hpp>
#include <corocontact/sim/simulation.hpp>

#include <algorithm>
#include <numeric>
#include <tuple>

namespace coro {

namespace {

using detail::ByteReader;
using detail::ByteWriter;

std::size_t at(Index i) { return static_cast<std::size_t>(i); }

using Key = std::tuple<Index, Index, ContactTarget>; // (body, vertex, other), case numbering

Key key_of(const ContactPoint& point) { return {point.body, point.vertex, point.other}; }

/// The nodes a surface moves with, ascending.
std::vector<Index> surface_nodes(const ContactSurface& surface)
{
    std::vector<Index> nodes = surface.body_node;
    for (const std::array<Index, 4>& embed : surface.embed_nodes)
        nodes.insert(nodes.end(), embed.begin(), embed.end());
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    return nodes;
}

void put_contact(ByteWriter& out, const ContactPoint& p)
{
    out.put(p.body);
    out.put(p.vertex);
    out.put(p.other.kind);
    out.put(p.other.index);
    out.put(p.face);
    out.put(p.depth);
    out.put(p.normal.data(), 3);
    out.put(p.barycentric.data(), 3);
}

ContactPoint get_contact(ByteReader& in)
{
    ContactPoint p;
    p.body = in.get<Index>();
    p.vertex = in.get<Index>();
    p.other.kind = in.get<ContactTarget::Kind>();
    p.other.index = in.get<Index>();
    p.face = in.get<Index>();
    p.depth = in.get<double>();
    in.get(p.normal.data(), 3);
    in.get(p.barycentric.data(), 3);
    return p;
}

} // namespace

std::size_t RankContact::Copy::slot(Index node) const
{
    return static_cast<std::size_t>(std::lower_bound(nodes.begin(), nodes.end(), node) - nodes.begin());
}

/// The nodes under this process's surfaces: its bodies' and the remote copies'.
class RankContact::Nodes final : public ContactNodes {
public:
    Nodes(const RankContact& contact, const Scene& scene) : m_contact(contact), m_scene(scene) {}

    bool carries_nodes(Index surface) const override
    {
        const auto bodies = static_cast<Index>(m_scene.bodies.size());
        return surface >= 0 && (surface < bodies || surface >= bodies + m_contact.m_num_obstacles);
    }
    Vec3 velocity(Index surface, Index node) const override
    {
        if (surface < static_cast<Index>(m_scene.bodies.size()))
            return m_scene.bodies[at(surface)].velocities().segment<3>(3 * node);
        const Copy& copy = copy_of(surface);
        return copy.velocities[copy.slot(node)];
    }
    bool fixed(Index surface, Index node) const override
    {
        if (surface < static_cast<Index>(m_scene.bodies.size()))
            return m_scene.bodies[at(surface)].fixed()[at(node)] != 0;
        const Copy& copy = copy_of(surface);
        return copy.fixed[copy.slot(node)] != 0;
    }

private:
    const Copy& copy_of(Index surface) const
    {
        return m_contact.m_copies[at(surface - static_cast<Index>(m_scene.bodies.size()) - m_contact.m_num_obstacles)];
    }
    const RankContact& m_contact;
    const Scene& m_scene;
};

RankContact::RankContact(Communicator& communicator, const BodyOwnership& ownership, std::vector<Index> body_ids,
                         const Scene& scene)
    : m_communicator(communicator), m_ownership(ownership), m_ids(std::move(body_ids))
{
    m_num_bodies = static_cast<Index>(ownership.owner.size());
    m_num_obstacles = static_cast<Index>(scene.surfaces.size() - m_ids.size());
    m_local.assign(at(m_num_bodies), -1);
    for (std::size_t l = 0; l < m_ids.size(); ++l)
        m_local[at(m_ids[l])] = static_cast<Index>(l);
    for (Index r = 0; r < ownership.num_ranks; ++r)
        m_rank_bodies.push_back(ownership.bodies_of(r));

    for (std::size_t l = 0; l < m_ids.size(); ++l) {
        m_surface_nodes.push_back(surface_nodes(scene.surfaces[l]));
        std::vector<Vec3>& start = m_start_positions.emplace_back();
        for (const Index node : m_surface_nodes.back())
            start.push_back(scene.bodies[l].positions().segment<3>(3 * node));
        m_topology_sent.emplace_back(at(ownership.num_ranks), 0);
    }
    m_copy_of.assign(at(m_num_bodies), -1);
}

Index RankContact::pair_owner(Index a) const { return a < m_num_bodies ? m_ownership.owner[at(a)] : 0; }

Index RankContact::local_surface(Index global) const
{
    const auto bodies = static_cast<Index>(m_ids.size());
    if (global >= m_num_bodies)
        return bodies + (global - m_num_bodies);
    if (m_local[at(global)] >= 0)
        return m_local[at(global)];
    const Index copy = m_copy_of[at(global)];
    return copy < 0 ? -1 : m_copies[at(copy)].surface;
}

Index RankContact::global_surface(Index surface) const
{
    const auto bodies = static_cast<Index>(m_ids.size());
    if (surface < bodies)
        return m_ids[at(surface)];
    if (surface < bodies + m_num_obstacles)
        return m_num_bodies + (surface - bodies);
    return m_copies[at(surface - bodies - m_num_obstacles)].body;
}

void RankContact::exchange_surfaces(const std::vector<std::pair<Index, Index>>& pairs, Scene& scene)
{
    const int ranks = m_communicator.size(), me = m_communicator.rank();
    // Which of this process's bodies each rank needs: the other body of a pair it owns.
    std::vector<std::vector<Index>> wanted(at(ranks));
    for (const auto& [a, b] : pairs) {
        const Index owner = pair_owner(a);
        if (b < m_num_bodies && m_ownership.owner[at(b)] == me && owner != me)
            wanted[at(owner)].push_back(m_local[at(b)]);
    }
    m_send.assign(at(ranks), {});
    for (int r = 0; r < ranks; ++r) {
        std::vector<Index>& bodies = wanted[at(r)];
        std::sort(bodies.begin(), bodies.end());
        bodies.erase(std::unique(bodies.begin(), bodies.end()), bodies.end());
        ByteWriter out(m_send[at(r)]);
        for (const Index l : bodies) {
            const ContactSurface& surface = scene.surfaces[at(l)];
            const std::vector<Index>& nodes = m_surface_nodes[at(l)];
            const Body& body = scene.bodies[at(l)];
            char& sent = m_topology_sent[at(l)][at(r)];
            out.put(m_ids[at(l)]);
            out.put(sent);
            if (!sent) { // topology, and the start positions the owner's surface was built from
                out.put_string(surface.name);
                out.put(body.num_vertices());
                const char embedded = surface.embed_nodes.empty() ? 0 : 1;
                out.put(embedded);
                out.put(static_cast<Index>(surface.faces.rows()));
                if (embedded) {
                    out.put(surface.faces.data(), at(static_cast<Index>(surface.faces.size())));
                    out.put(static_cast<Index>(surface.embed_nodes.size()));
                    out.put(surface.embed_nodes.data(), surface.embed_nodes.size());
                    for (const Eigen::Vector4d& w : surface.embed_weights)
                        out.put(w.data(), 4);
                } else { // the faces in the body's node numbering, as from_body takes them
                    for (Index f = 0; f < surface.faces.rows(); ++f)
                        for (int c = 0; c < 3; ++c)
                            out.put(surface.body_node[at(surface.faces(f, c))]);
                }
                out.put(static_cast<Index>(nodes.size()));
                out.put(nodes.data(), nodes.size());
                for (const Index node : nodes)
                    out.put(body.fixed()[at(node)]);
                for (const Vec3& x : m_start_positions[at(l)])
                    out.put(x.data(), 3);
                sent = 1;
            }
            for (const Index node : nodes)
                out.put(body.positions().data() + 3 * node, 3);
            for (const Index node : nodes)
                out.put(body.velocities().data() + 3 * node, 3);
        }
    }
    m_communicator.exchange(m_send, m_receive);

    for (int r = 0; r < ranks; ++r) {
        if (r == me)
            continue;
        ByteReader in(m_receive[at(r)]);
        while (!in.done()) {
            const auto body = in.get<Index>();
            const auto known = in.get<char>();
            if (!known) {
                Copy copy;
                copy.body = body;
                copy.surface = static_cast<Index>(scene.surfaces.size());
                const std::string name = in.get_string();
                copy.positions = Positions::Zero(in.get<Index>(), 3);
                const char embedded = in.get<char>();
                Tris faces(in.get<Index>(), 3);
                in.get(faces.data(), at(static_cast<Index>(faces.size())));
                std::vector<std::array<Index, 4>> embed_nodes;
                std::vector<Eigen::Vector4d> embed_weights;
                if (embedded) {
                    embed_nodes.resize(at(in.get<Index>()));
                    in.get(embed_nodes.data(), embed_nodes.size());
                    embed_weights.resize(embed_nodes.size());
                    for (Eigen::Vector4d& w : embed_weights)
                        in.get(w.data(), 4);
                }
                copy.nodes.resize(at(in.get<Index>()));
                in.get(copy.nodes.data(), copy.nodes.size());
                copy.fixed.resize(copy.nodes.size());
                in.get(copy.fixed.data(), copy.fixed.size());
                for (const Index node : copy.nodes)
                    in.get(copy.positions.row(node).data(), 3);
                copy.velocities.resize(copy.nodes.size());
                scene.surfaces.push_back(
                    embedded ? ContactSurface::from_embedding(name, copy.positions, faces, std::move(embed_nodes),
                                                              std::move(embed_weights))
                             : ContactSurface::from_body(name, copy.positions, faces));
                m_copy_of[at(body)] = static_cast<Index>(m_copies.size());
                m_copies.push_back(std::move(copy));
            }
            Copy& copy = m_copies[at(m_copy_of[at(body)])];
            for (const Index node : copy.nodes)
                in.get(copy.positions.row(node).data(), 3);
            scene.surfaces[at(copy.surface)].update(copy.positions);
            for (Vec3& v : copy.velocities)
                in.get(v.data(), 3);
        }
    }
}

RankContact::Counts RankContact::detect(Scene& scene, const ContactSettings& settings, double dt,
                                        ContactResponse& response, SceneMatrix& matrix, RankExchange& exchange)
{
    const int ranks = m_communicator.size(), me = m_communicator.rank();
    const auto n_local = static_cast<Index>(m_ids.size());
    Counts counts;
    update_contact_surfaces(scene.bodies, scene.surfaces);

    // The broad phase of one process: every body's box, then the obstacle meshes'.
    std::vector<double> mine;
    for (Index l = 0; l < n_local; ++l) {
        const Aabb box = scene.surfaces[at(l)].tree.bounds();
        mine.insert(mine.end(), box.min.data(), box.min.data() + 3);
        mine.insert(mine.end(), box.max.data(), box.max.data() + 3);
    }
    std::vector<int> sizes(at(ranks)), offsets(at(ranks));
    int total = 0;
    for (int r = 0; r < ranks; ++r) {
        sizes[at(r)] = 6 * static_cast<int>(m_rank_bodies[at(r)].size());
        offsets[at(r)] = total;
        total += sizes[at(r)];
    }
    std::vector<double> gathered(at(total));
    m_communicator.all_gather(mine.data(), sizes[at(me)], gathered.data(), sizes.data(), offsets.data());
    std::vector<Aabb> boxes(at(m_num_bodies + m_num_obstacles));
    for (int r = 0; r < ranks; ++r)
        for (std::size_t i = 0; i < m_rank_bodies[at(r)].size(); ++i) {
            const double* box = gathered.data() + offsets[at(r)] + 6 * i;
            Aabb& b = boxes[at(m_rank_bodies[at(r)][i])];
            b.min = Vec3(box[0], box[1], box[2]);
            b.max = Vec3(box[3], box[4], box[5]);
        }
    for (Index k = 0; k < m_num_obstacles; ++k)
        boxes[at(m_num_bodies + k)] = scene.surfaces[at(n_local + k)].tree.bounds();
    const std::vector<std::pair<Index, Index>> pairs = overlapping_pairs(boxes);

    // The components of the whole scene, from the same boxes on every process.
    contact_components(std::vector<Aabb>(boxes.begin(), boxes.begin() + m_num_bodies), m_components);
    m_local_components.resize(m_ids.size());
    for (std::size_t l = 0; l < m_ids.size(); ++l)
        m_local_components[l] = m_components[at(m_ids[l])];
    exchange.set_components(m_components);
    matrix.set_components(m_local_components, exchange.num_components());

    exchange_surfaces(pairs, scene);

    // This process's pairs, in its surface numbering, and their contacts in the case's order.
    std::vector<std::pair<Index, Index>> own_pairs;
    for (const auto& [a, b] : pairs)
        if (pair_owner(a) == me) {
            const Index x = local_surface(a), y = local_surface(b);
            own_pairs.emplace_back(std::min(x, y), std::max(x, y));
        }
    std::sort(own_pairs.begin(), own_pairs.end());
    std::vector<ContactPoint> found =
        detect_contacts(scene.surfaces, own_pairs, detection_settings(settings), m_detection);
    if (!scene.planes.empty()) {
        const std::vector<ContactPoint> planes = detect_plane_contacts(scene.surfaces, n_local, scene.planes);
        found.insert(found.end(), planes.begin(), planes.end());
    }
    const auto global_key = [&](const ContactPoint& p) {
        return Key{global_surface(p.body), p.vertex,
                   p.other.is_surface() ? ContactTarget::surface(global_surface(p.other.index)) : p.other};
    };
    std::vector<std::size_t> order(found.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(),
              [&](std::size_t x, std::size_t y) { return global_key(found[x]) < global_key(found[y]); });
    std::vector<ContactPoint> contacts;
    contacts.reserve(found.size());
    for (const std::size_t i : order)
        contacts.push_back(found[i]);
    evaluate_contacts(scene.surfaces, contacts, Nodes(*this, scene), settings, dt, m_records);

    // Each contact, with its terms, to the owners of the nodes it touches (this one included).
    m_send.assign(at(ranks), {});
    std::vector<Index> destinations;
    for (std::size_t i = 0; i < contacts.size(); ++i) {
        ContactPoint point = contacts[i];
        counts.max_depth = std::max(counts.max_depth, point.depth);
        std::tie(point.body, point.vertex, point.other) = global_key(point);
        destinations.clear();
        for (Index s = m_records.share_offsets[i]; s < m_records.share_offsets[i + 1]; ++s)
            destinations.push_back(m_ownership.owner[at(global_surface(m_records.shares[at(s)].surface))]);
        std::sort(destinations.begin(), destinations.end());
        destinations.erase(std::unique(destinations.begin(), destinations.end()), destinations.end());
        counts.cross_rank += destinations.size() > 1 || (destinations.size() == 1 && destinations[0] != me) ? 1 : 0;
        for (const Index rank : destinations) {
            ByteWriter out(m_send[at(rank)]);
            put_contact(out, point);
            const ContactTerms& terms = m_records.terms[i];
            out.put(terms.stiffness.data(), 9);
            out.put(terms.force.data(), 3);
            out.put(m_records.share_offsets[i + 1] - m_records.share_offsets[i]);
            for (Index s = m_records.share_offsets[i]; s < m_records.share_offsets[i + 1]; ++s) {
                const ContactShare& share = m_records.shares[at(s)];
                out.put(global_surface(share.surface));
                out.put(share.node);
                out.put(share.coefficient);
                out.put(static_cast<char>(share.fixed ? 1 : 0));
            }
        }
    }
    counts.contacts = static_cast<Index>(contacts.size());
    m_communicator.exchange(m_send, m_receive);

    // Every contact touching a node here, in the case's order.
    std::vector<ContactPoint> points;
    ContactRecords received;
    for (int r = 0; r < ranks; ++r) {
        ByteReader in(m_receive[at(r)]);
        while (!in.done()) {
            points.push_back(get_contact(in));
            ContactTerms terms;
            in.get(terms.stiffness.data(), 9);
            in.get(terms.force.data(), 3);
            received.terms.push_back(terms);
            const auto n = in.get<Index>();
            for (Index s = 0; s < n; ++s) {
                ContactShare share;
                share.surface = in.get<Index>();
                share.node = in.get<Index>();
                share.coefficient = in.get<double>();
                share.fixed = in.get<char>() != 0;
                received.shares.push_back(share);
            }
            received.share_offsets.push_back(received.share_offsets.back() + n);
        }
    }
    order.resize(points.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(),
              [&](std::size_t x, std::size_t y) { return key_of(points[x]) < key_of(points[y]); });
    m_records.terms.clear();
    m_records.shares.clear();
    m_records.share_offsets.assign(1, 0);
    scene.contacts.clear();
    for (const std::size_t i : order) {
        m_records.terms.push_back(received.terms[i]);
        m_records.shares.insert(m_records.shares.end(), received.shares.begin() + received.share_offsets[i],
                                received.shares.begin() + received.share_offsets[i + 1]);
        m_records.share_offsets.push_back(static_cast<Index>(m_records.shares.size()));
        ContactPoint point = points[i];
        if (point.body < m_num_bodies && m_local[at(point.body)] >= 0) {
            point.body = m_local[at(point.body)];
            scene.contacts.push_back(point);
        }
    }

    // Ghost rows: the nodes of other processes that share a contact with a node here, in the
    // case's order; the halo sends a node here to every process holding a ghost of it.
    const auto is_here = [&](const ContactShare& share) { return m_local[at(share.surface)] >= 0; };
    std::vector<std::pair<Index, Index>> ghosts;         // (case body, node)
    std::vector<std::tuple<Index, Index, Index>> sends;  // (rank, case body, node)
    for (Index i = 0; i < m_records.size(); ++i) {
        const auto first = m_records.shares.begin() + m_records.share_offsets[at(i)];
        const auto end = m_records.shares.begin() + m_records.share_offsets[at(i) + 1];
        if (std::none_of(first, end, is_here))
            continue;
        for (auto remote = first; remote != end; ++remote) {
            if (is_here(*remote))
                continue;
            ghosts.emplace_back(remote->surface, remote->node);
            for (auto local = first; local != end; ++local)
                if (is_here(*local))
                    sends.emplace_back(m_ownership.owner[at(remote->surface)], local->surface, local->node);
        }
    }
    std::sort(ghosts.begin(), ghosts.end());
    ghosts.erase(std::unique(ghosts.begin(), ghosts.end()), ghosts.end());
    std::sort(sends.begin(), sends.end());
    sends.erase(std::unique(sends.begin(), sends.end()), sends.end());

    const Index rows = matrix.num_block_rows();
    RankExchange::Halo halo;
    halo.num_ghosts = static_cast<Index>(ghosts.size());
    const auto neighbour = [&](Index rank) -> std::size_t {
        if (halo.ranks.empty() || halo.ranks.back() != rank) {
            halo.ranks.push_back(static_cast<int>(rank));
            halo.send_rows.emplace_back();
            halo.ghost_rows.emplace_back();
        }
        return halo.ranks.size() - 1;
    };
    // Both lists come grouped by rank, ascending: merge them rank by rank.
    std::vector<std::pair<Index, Index>> by_rank; // (rank, ghost)
    for (std::size_t g = 0; g < ghosts.size(); ++g)
        by_rank.emplace_back(m_ownership.owner[at(ghosts[g].first)], static_cast<Index>(g));
    std::stable_sort(by_rank.begin(), by_rank.end(),
                     [](const auto& x, const auto& y) { return x.first < y.first; });
    std::size_t s = 0, g = 0;
    while (s < sends.size() || g < by_rank.size()) {
        const Index rank = std::min(s < sends.size() ? std::get<0>(sends[s]) : ranks,
                                    g < by_rank.size() ? by_rank[g].first : ranks);
        const std::size_t k = neighbour(rank);
        for (; s < sends.size() && std::get<0>(sends[s]) == rank; ++s) {
            const Index body = m_local[at(std::get<1>(sends[s]))];
            halo.send_rows[k].push_back(matrix.offset(body) + std::get<2>(sends[s]));
        }
        for (; g < by_rank.size() && by_rank[g].first == rank; ++g)
            halo.ghost_rows[k].push_back(by_rank[g].second);
    }

    response.apply(
        m_records, scene.bodies, [&](Index body) { return m_local[at(body)]; },
        [&](Index body, Index node) {
            const Index l = m_local[at(body)];
            if (l >= 0)
                return matrix.offset(l) + node;
            const auto ghost = std::lower_bound(ghosts.begin(), ghosts.end(), std::make_pair(body, node));
            return rows + static_cast<Index>(ghost - ghosts.begin());
        },
        matrix, scene.contact_forces);
    exchange.set_halo(std::move(halo));
    return counts;
}

} // namespace coro
