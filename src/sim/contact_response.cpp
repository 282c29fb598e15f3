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

void evaluate_contacts(const std::vector<ContactSurface>& surfaces, const std::vector<ContactPoint>& contacts,
                       const ContactNodes& nodes, const ContactSettings& settings, double dt,
                       ContactRecords& records)
{
    // Who carries the two points of each contact: the penetrating vertex (−1) and the other
    // face's vertices (barycentric weights). Obstacles (surfaces after the bodies, or planes)
    // carry no nodes.
    records.terms.resize(contacts.size());
    records.share_offsets.resize(contacts.size() + 1);
    records.share_offsets[0] = 0;
    for (std::size_t i = 0; i < contacts.size(); ++i) {
        const ContactPoint& contact = contacts[i];
        Index count = 0;
        if (nodes.carries_nodes(contact.body))
            count += vertex_shares(surfaces[at(contact.body)]);
        if (contact.other.is_surface() && nodes.carries_nodes(contact.other.index) && contact.face >= 0)
            count += 3 * vertex_shares(surfaces[at(contact.other.index)]);
        records.share_offsets[i + 1] = records.share_offsets[i] + count;
    }
    records.shares.resize(at(records.share_offsets.back()));

    const double k = settings.stiffness;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, contacts.size(), CONTACT_GRAIN),
                      [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const ContactPoint& contact = contacts[i];
            ContactShare* shares = records.shares.data() + records.share_offsets[i];
            const Index count = records.share_offsets[i + 1] - records.share_offsets[i];
            Index filled = 0;
            const auto add_node = [&](Index surface, Index node, double coefficient) {
                shares[filled++] = {surface, node, coefficient, nodes.fixed(surface, node)};
            };
            const auto add_vertex = [&](Index body, Index vertex, double coefficient) {
                const ContactSurface& surface = surfaces[at(body)];
                const auto v = at(vertex);
                if (surface.embed_nodes.empty()) {
                    add_node(body, surface.body_node[v], coefficient);
                    return;
                }
                for (std::size_t a = 0; a < 4; ++a)
                    add_node(body, surface.embed_nodes[v][a],
                             coefficient * surface.embed_weights[v][static_cast<Eigen::Index>(a)]);
            };
            if (nodes.carries_nodes(contact.body))
                add_vertex(contact.body, contact.vertex, -1.0);
            if (contact.other.is_surface() && nodes.carries_nodes(contact.other.index) && contact.face >= 0) {
                const ContactSurface& other = surfaces[at(contact.other.index)];
                for (int c = 0; c < 3; ++c)
                    add_vertex(contact.other.index, other.faces(contact.face, c), contact.barycentric[c]);
            }
            if (count == 0)
                continue; // two obstacles
            const Vec3& n = contact.normal;
            Vec3 u = Vec3::Zero(); // velocity of the other side relative to the penetrating vertex
            for (Index s = 0; s < count; ++s)
                u += shares[s].coefficient * nodes.velocity(shares[s].surface, shares[s].node);
            const double normal_force = k * contact.depth;
            ContactTerms& terms = records.terms[i];
            terms.force = normal_force * n; // on the penetrating side
            terms.stiffness = (dt * dt * k + dt * settings.damping) * n * n.transpose();
            if (settings.friction > 0.0) {
                // Implicit, lagged friction: F_t = η u_t⁺ with η = μ f_n / max(|u_t|, ε) taken at
                // the step start. A slipping contact keeps |F_t| ≈ μ f_n, a stuck one is held by a
                // stiff tangential damper, and neither can reverse the slip within a step (an
                // explicit μ f_n on a light vertex can, and then chatters).
                const Mat3 tangential = Mat3::Identity() - n * n.transpose();
                const double speed = (tangential * u).norm();
                terms.stiffness +=
                    dt * settings.friction * normal_force / std::max(speed, FRICTION_STICK_SPEED) * tangential;
            }
        }
    });
}

void ContactResponse::compute(const std::vector<Body>& bodies, const std::vector<ContactSurface>& surfaces,
                              const std::vector<ContactPoint>& contacts, const ContactSettings& settings, double dt,
                              SceneMatrix& matrix, std::vector<VecX>& forces)
{
    evaluate_contacts(surfaces, contacts, BodyNodes(bodies), settings, dt, m_records);
    apply(
        m_records, bodies, [](Index surface) { return surface; },
        [&](Index surface, Index node) { return matrix.offset(surface) + node; }, matrix, forces);
}

void ContactResponse::apply(const ContactRecords& records, const std::vector<Body>& bodies,
                            FunctionRef<Index(Index surface)> local_body,
                            FunctionRef<Index(Index surface, Index node)> column, SceneMatrix& matrix,
                            std::vector<VecX>& forces)
{
    forces.resize(bodies.size());
    for (std::size_t b = 0; b < bodies.size(); ++b)
        forces[b].setZero(3 * bodies[b].num_vertices());

    // One coupling term per contact: its K, and its shares' rows here and columns.
    ContactCoupling& coupling = matrix.coupling();
    coupling.reset(records.share_offsets);
    m_share_forces.resize(records.shares.size());
    const tbb::blocked_range<Index> all_contacts(0, records.size(), CONTACT_GRAIN);
    tbb::parallel_for(all_contacts, [&](const tbb::blocked_range<Index>& range) {
        for (Index i = range.begin(); i != range.end(); ++i) {
            const ContactTerms& terms = records.terms[at(i)];
            const Index first = records.share_offsets[at(i)], end = records.share_offsets[at(i) + 1];
            coupling.stiffness(i) = terms.stiffness;
            bool rows_here = false;
            for (Index s = first; s < end; ++s)
                rows_here = rows_here || local_body(records.shares[at(s)].surface) >= 0;
            for (Index s = first; s < end; ++s) {
                const ContactShare& share = records.shares[at(s)];
                const Index body = local_body(share.surface);
                if (body >= 0)
                    m_share_forces[at(s)] = terms.force_on(share);
                ContactCoupling::Share& out = coupling.share(i, s - first);
                out.row = body >= 0 && !share.fixed ? matrix.offset(body) + share.node : -1;
                out.column = rows_here ? column(share.surface, share.node) : 0; // read only for rows here
                out.coefficient = share.fixed ? 0.0 : share.coefficient;
            }
        }
    });
    // Forces in contact order, whatever the schedule.
    for (std::size_t s = 0; s < records.shares.size(); ++s) {
        const ContactShare& share = records.shares[s];
        const Index body = local_body(share.surface);
        if (body >= 0)
            forces[at(body)].segment<3>(3 * share.node) += m_share_forces[s];
    }
    coupling.finish();
}

} // namespace coro
