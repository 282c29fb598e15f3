#include <corocontact/sim/scene_system.hpp>

#include <corocontact/core/error.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <sstream>

namespace coro {

namespace {
std::size_t at(Index i) { return static_cast<std::size_t>(i); }
} // namespace

std::vector<const BsrMatrix*> SceneSystem::body_matrices(std::vector<Body>& bodies)
{
    std::vector<const BsrMatrix*> matrices;
    matrices.reserve(bodies.size());
    for (Body& body : bodies)
        matrices.push_back(&body.system_matrix());
    return matrices;
}

SceneSystem::SceneSystem(std::vector<Body>& bodies) : m_bodies(bodies), m_matrix(body_matrices(bodies))
{
    std::vector<const VecX*> positions;
    for (const Body& body : bodies)
        positions.push_back(&body.positions());
    m_matrix.set_node_positions(std::move(positions));
    // Work items: the bodies' parts in order, cut into runs of at least ELEMENT_TASK_TETS tets.
    Index tets = 0;
    for (Index b = 0; b < static_cast<Index>(bodies.size()); ++b) {
        const PartLayout& layout = bodies[at(b)].fem().layout();
        for (Index p = 0; p < layout.num_parts; ++p) {
            if (tets == 0)
                m_items.push_back({static_cast<Index>(m_units.size()), 0});
            m_units.push_back({b, p});
            tets += layout.tet_offsets[at(p) + 1] - layout.tet_offsets[at(p)];
            if (tets >= ELEMENT_TASK_TETS) {
                m_items.back().end_unit = static_cast<Index>(m_units.size());
                tets = 0;
            }
        }
    }
    if (!m_items.empty() && m_items.back().end_unit == 0)
        m_items.back().end_unit = static_cast<Index>(m_units.size());
    m_rhs = VecX::Zero(m_matrix.num_dofs());
    m_velocity = VecX::Zero(m_matrix.num_dofs());
    m_chunk_not_finite.assign(at(m_matrix.chunks().num_chunks()), 0);
}

CorotationalFem::ElementPass SceneSystem::element_pass(Index b, double dt)
{
    Body& body = m_bodies[at(b)];
    CorotationalFem::ElementPass pass;
    pass.x = body.positions().data();
    pass.rotate = true;
    pass.forces = m_rhs.data() + 3 * static_cast<std::ptrdiff_t>(offset(b));
    pass.matrix = &body.system_matrix();
    pass.stiffness_scale = dt * dt + dt * body.rayleigh_stiffness();
    pass.mass_scale = 1.0 + dt * body.rayleigh_mass();
    pass.fixed = body.num_fixed() > 0 ? body.fixed().data() : nullptr;
    return pass;
}

void SceneSystem::element_loop(double dt)
{
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m_items.size(), 1), [&](const tbb::blocked_range<std::size_t>& items) {
        for (std::size_t i = items.begin(); i != items.end(); ++i)
            for (Index u = m_items[i].first_unit; u < m_items[i].end_unit; ++u) {
                const Unit& unit = m_units[at(u)];
                try {
                    m_bodies[at(unit.body)].fem().element_part(unit.part, element_pass(unit.body, dt));
                } catch (const NumericalError& error) {
                    CORO_THROW(NumericalError, "body '" << m_bodies[at(unit.body)].name() << "': " << error.what());
                }
            }
    });
}

void SceneSystem::assemble(double dt, const Vec3& gravity, const std::vector<VecX>& contact_forces)
{
    for_each_chunk(m_matrix.chunks(), [&](Index c, Index begin, Index end) {
        const Index b = m_matrix.chunk_body(c);
        const Body& body = m_bodies[at(b)];
        const Index offset = this->offset(b);
        m_bodies[at(b)].fem().finish_rows(begin - offset, end - offset, element_pass(b, dt));
        const VecX& masses = body.fem().lumped_masses();
        const VecX& loads = body.load_forces();
        const VecX& v = body.velocities();
        const VecX* contact = contact_forces.empty() ? nullptr : &contact_forces[at(b)];
        const std::vector<char>& fixed = body.fixed();
        for (Index r = begin; r < end; ++r) {
            const Index node = r - offset;
            auto rhs = m_rhs.segment<3>(3 * r);
            auto v_new = m_velocity.segment<3>(3 * r);
            if (fixed[at(node)]) {
                rhs.setZero();
                v_new.setZero();
                continue;
            }
            Vec3 f = rhs + loads.segment<3>(3 * node);
            if (contact)
                f += contact->segment<3>(3 * node);
            f += masses[node] * gravity;
            rhs = dt * f + masses[node] * v.segment<3>(3 * node);
            v_new = v.segment<3>(3 * node);
        }
        m_chunk_not_finite[at(c)] = m_rhs.segment(3 * begin, 3 * (end - begin)).allFinite() ? 0 : 1;
    });
    report_non_finite(m_rhs, "right-hand side M v + h f");
}

void SceneSystem::report_non_finite(const VecX& values, const char* what) const
{
    for (Index c = 0; c < m_matrix.chunks().num_chunks(); ++c) {
        if (!m_chunk_not_finite[at(c)])
            continue;
        const Index b = m_matrix.chunk_body(c);
        const Body& body = m_bodies[at(b)];
        Index first = 3 * m_matrix.chunks().offsets[at(c)];
        while (std::isfinite(values[first]))
            ++first;
        std::ostringstream message;
        message << "body '" << body.name() << "': " << what << " at node " << body.input_node(first / 3 - offset(b))
                << " (mesh file order) is " << values[first];
        throw NumericalError(detail::with_source_location(message.str(), __FILE__, __LINE__), b);
    }
}

PcgResult SceneSystem::solve(const PcgSettings& settings, SceneExchange* exchange)
{
    return m_pcg.solve(m_matrix, m_rhs, m_velocity, settings, exchange);
}

void SceneSystem::advance(double dt)
{
    for_each_chunk(m_matrix.chunks(), [&](Index c, Index begin, Index end) {
        const Index b = m_matrix.chunk_body(c);
        Body& body = m_bodies[at(b)];
        const Index offset = this->offset(b);
        const auto segment = m_velocity.segment(3 * begin, 3 * (end - begin));
        m_chunk_not_finite[at(c)] = segment.allFinite() ? 0 : 1;
        body.velocities().segment(3 * (begin - offset), 3 * (end - begin)) = segment;
        body.positions().segment(3 * (begin - offset), 3 * (end - begin)) += dt * segment;
    });
    report_non_finite(m_velocity, "velocity");
}

PcgResult SceneSystem::step(double dt, const Vec3& gravity, const std::vector<VecX>& contact_forces,
                            const PcgSettings& settings)
{
    element_loop(dt);
    assemble(dt, gravity, contact_forces);
    const PcgResult result = solve(settings);
    advance(dt);
    return result;
}

} // namespace coro
