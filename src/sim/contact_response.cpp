#include <corocontact/sim/contact_response.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace coro {

namespace {
constexpr std::size_t CONTACT_GRAIN = 64; // contacts per task

std::size_t at(Index i) { return static_cast<std::size_t>(i); }

// Shares of one surface vertex: a body node, or (embedded surface) 4 weighted nodes.
Index vertex_shares(const ContactSurface& surface) { return surface.embed_nodes.empty() ? 1 : 4; }
} // namespace

void ContactResponse::compute(const std::vector<Body>& bodies, const std::vector<ContactSurface>& surfaces,
                              const std::vector<ContactPoint>& contacts, const ContactSettings& settings, double dt,
                              SceneMatrix& matrix)
{
    const auto n_bodies = static_cast<Index>(bodies.size());
    const auto carries_nodes = [&](Index surface) { return surface >= 0 && surface < n_bodies; };
    m_forces.resize(bodies.size());
    for (std::size_t b = 0; b < bodies.size(); ++b)
        m_forces[b].setZero(3 * bodies[b].num_vertices());

    // Who carries the two points of each contact: the penetrating vertex (−1) and the other
    // face's vertices (barycentric weights). Obstacles (surfaces after the bodies, or planes)
    // carry no nodes.
    m_share_offsets.resize(contacts.size() + 1);
    m_share_offsets[0] = 0;
    for (std::size_t i = 0; i < contacts.size(); ++i) {
        const ContactPoint& contact = contacts[i];
        Index count = 0;
        if (carries_nodes(contact.body))
            count += vertex_shares(surfaces[at(contact.body)]);
        if (contact.other.is_surface() && carries_nodes(contact.other.index) && contact.face >= 0)
            count += 3 * vertex_shares(surfaces[at(contact.other.index)]);
        m_share_offsets[i + 1] = m_share_offsets[i] + count;
    }
    m_shares.resize(at(m_share_offsets.back()));
    m_share_forces.resize(m_shares.size());
    // Blocks: every pair of shares of a contact, contact after contact.
    m_block_offsets.resize(contacts.size() + 1);
    m_block_offsets[0] = 0;
    for (std::size_t i = 0; i < contacts.size(); ++i) {
        const Index count = m_share_offsets[i + 1] - m_share_offsets[i];
        m_block_offsets[i + 1] = m_block_offsets[i] + count * count;
    }
    CouplingBlocks& coupling = matrix.coupling();
    coupling.reset(m_block_offsets.back());

    const double k = settings.stiffness;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, contacts.size(), CONTACT_GRAIN),
                      [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const ContactPoint& contact = contacts[i];
            Share* shares = m_shares.data() + m_share_offsets[i];
            const Index count = m_share_offsets[i + 1] - m_share_offsets[i];
            Index filled = 0;
            Index block = m_block_offsets[i];
            const auto add_vertex = [&](Index body, Index vertex, double coefficient) {
                const ContactSurface& surface = surfaces[at(body)];
                const auto v = at(vertex);
                if (surface.embed_nodes.empty()) {
                    shares[filled++] = {body, surface.body_node[v], coefficient};
                    return;
                }
                for (std::size_t a = 0; a < 4; ++a)
                    shares[filled++] = {body, surface.embed_nodes[v][a],
                                        coefficient * surface.embed_weights[v][static_cast<Eigen::Index>(a)]};
            };
            if (carries_nodes(contact.body))
                add_vertex(contact.body, contact.vertex, -1.0);
            if (contact.other.is_surface() && carries_nodes(contact.other.index) && contact.face >= 0) {
                const ContactSurface& other = surfaces[at(contact.other.index)];
                for (int c = 0; c < 3; ++c)
                    add_vertex(contact.other.index, other.faces(contact.face, c), contact.barycentric[c]);
            }
            if (count == 0)
                continue; // two obstacles
            const Vec3& n = contact.normal;
            Vec3 u = Vec3::Zero(); // velocity of the other side relative to the penetrating vertex
            for (Index s = 0; s < count; ++s)
                u += shares[s].coefficient * bodies[at(shares[s].body)].velocities().segment<3>(3 * shares[s].node);
            const double normal_force = k * contact.depth;
            const Vec3 force = normal_force * n; // on the penetrating side
            Mat3 stiffness = (dt * dt * k + dt * settings.damping) * n * n.transpose();
            if (settings.friction > 0.0) {
                // Implicit, lagged friction: F_t = η u_t⁺ with η = μ f_n / max(|u_t|, ε) taken at
                // the step start. A slipping contact keeps |F_t| ≈ μ f_n, a stuck one is held by a
                // stiff tangential damper, and neither can reverse the slip within a step (an
                // explicit μ f_n on a light vertex can, and then chatters).
                const Mat3 tangential = Mat3::Identity() - n * n.transpose();
                const double speed = (tangential * u).norm();
                stiffness += dt * settings.friction * normal_force / std::max(speed, FRICTION_STICK_SPEED) * tangential;
            }
            const auto fixed = [&](const Share& share) {
                return bodies[at(share.body)].fixed()[at(share.node)] != 0;
            };
            for (Index r = 0; r < count; ++r) {
                const Share& row = shares[r];
                m_share_forces[at(m_share_offsets[i] + r)] = -row.coefficient * force;
                for (Index c = 0; c < count; ++c) {
                    const Share& col = shares[c];
                    CouplingBlocks::Entry& entry = coupling.entry(block++);
                    entry.row = matrix.offset(row.body) + row.node;
                    entry.column = matrix.offset(col.body) + col.node;
                    // Terms in a row or column of a fixed node are left out: those are identity.
                    if (fixed(row) || fixed(col))
                        entry.value.setZero();
                    else
                        entry.value = row.coefficient * col.coefficient * stiffness;
                }
            }
        }
    });
    // Forces in contact order, whatever the schedule.
    for (std::size_t s = 0; s < m_shares.size(); ++s)
        m_forces[at(m_shares[s].body)].segment<3>(3 * m_shares[s].node) += m_share_forces[s];
    coupling.finish(matrix.chunks());
}

} // namespace coro
