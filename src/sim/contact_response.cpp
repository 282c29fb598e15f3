#include <corocontact/sim/contact_response.hpp>

#include <algorithm>
#include <array>

namespace coro {

namespace {
struct Share {
    Index body;
    Index node;
    double coefficient;
};
} // namespace

ContactResponse contact_response(const std::vector<Body>& bodies, const std::vector<ContactSurface>& surfaces,
                                 const std::vector<ContactPoint>& contacts, const ContactSettings& settings,
                                 double dt)
{
    const auto n_bodies = static_cast<Index>(bodies.size());
    ContactResponse response;
    response.forces.reserve(bodies.size());
    for (const Body& body : bodies)
        response.forces.push_back(VecX::Zero(3 * body.num_vertices()));

    const double k = settings.stiffness;
    std::array<Share, 16> shares{};
    for (const ContactPoint& contact : contacts) {
        // Who carries the two points of this contact.
        // Obstacles (surfaces after the bodies, or planes) carry no nodes.
        int count = 0;
        // A surface vertex is a body node, or (embedded surface) a weighted set of 4 nodes.
        const auto add_vertex = [&](Index body, Index vertex, double coefficient) {
            const ContactSurface& surface = surfaces[static_cast<std::size_t>(body)];
            const auto v = static_cast<std::size_t>(vertex);
            if (surface.embed_nodes.empty()) {
                shares[static_cast<std::size_t>(count++)] = {body, surface.body_node[v], coefficient};
                return;
            }
            for (std::size_t a = 0; a < 4; ++a)
                shares[static_cast<std::size_t>(count++)] = {
                    body, surface.embed_nodes[v][a], coefficient * surface.embed_weights[v][static_cast<Eigen::Index>(a)]};
        };
        if (contact.body < n_bodies)
            add_vertex(contact.body, contact.vertex, -1.0);
        if (contact.other.is_surface() && contact.other.index < n_bodies && contact.face >= 0) {
            const ContactSurface& other = surfaces[static_cast<std::size_t>(contact.other.index)];
            for (int i = 0; i < 3; ++i)
                add_vertex(contact.other.index, other.faces(contact.face, i), contact.barycentric[i]);
        }
        if (count == 0)
            continue; // two obstacles
        const Vec3& n = contact.normal;
        Vec3 u = Vec3::Zero(); // velocity of the other side relative to the penetrating vertex
        for (int s = 0; s < count; ++s) {
            const Share& share = shares[static_cast<std::size_t>(s)];
            u += share.coefficient * bodies[static_cast<std::size_t>(share.body)].velocities().segment<3>(3 * share.node);
        }
        const double normal_force = k * contact.depth;
        Vec3 force = normal_force * n; // on the penetrating side
        Mat3 matrix = (dt * dt * k + dt * settings.damping) * n * n.transpose();
        if (settings.friction > 0.0) {
            // Implicit, lagged friction: F_t = η u_t⁺ with η = μ f_n / max(|u_t|, ε) taken at the
            // step start. A slipping contact keeps |F_t| ≈ μ f_n, a stuck one is held by a stiff
            // tangential damper, and neither can reverse the slip within a step (an explicit
            // μ f_n on a light vertex can, and then chatters).
            const Mat3 tangential = Mat3::Identity() - n * n.transpose();
            const double speed = (tangential * u).norm();
            matrix += dt * settings.friction * normal_force / std::max(speed, FRICTION_STICK_SPEED) * tangential;
        }
        for (int r = 0; r < count; ++r) {
            const Share& row = shares[static_cast<std::size_t>(r)];
            response.forces[static_cast<std::size_t>(row.body)].segment<3>(3 * row.node) -= row.coefficient * force;
            for (int c = 0; c < count; ++c) {
                const Share& col = shares[static_cast<std::size_t>(c)];
                response.blocks.push_back({row.body, row.node, col.body, col.node,
                                           row.coefficient * col.coefficient * matrix});
            }
        }
    }
    return response;
}

} // namespace coro
