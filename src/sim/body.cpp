#include <corocontact/sim/body.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/partition/part_layout.hpp>
#include <corocontact/partition/partition.hpp>

namespace coro {

namespace {
bool inside(const Vec3& p, const Vec3& min, const Vec3& max)
{
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
}
} // namespace

Body::Partitioned Body::partition_mesh(const TetMesh& mesh, Index num_parts)
{
    const TetPartition partition = partition_tets(mesh.tets, mesh.num_vertices(), num_parts);
    Partitioned result;
    result.layout = make_part_layout(mesh.tets, mesh.num_vertices(), partition);
    result.mesh = reorder_mesh(mesh, result.layout);
    result.edge_cut = partition.edge_cut;
    return result;
}

Body::Body(const TetMesh& mesh, const BodySpec& spec, Index num_parts, MatrixPrecision precision)
    : Body(partition_mesh(mesh, num_parts), spec, precision)
{
}

Body::Body(Partitioned&& partitioned, const BodySpec& spec, MatrixPrecision precision)
    : m_name(spec.name), m_edge_cut(partitioned.edge_cut), m_mesh(std::move(partitioned.mesh)),
      m_fem(m_mesh, spec.material, std::move(partitioned.layout)), m_rayleigh_mass(spec.rayleigh_mass),
      m_rayleigh_stiffness(spec.rayleigh_stiffness)
{
    const Index n = m_mesh.num_vertices();
    m_positions = m_fem.rest_dofs();
    m_velocities.resize(3 * n);
    for (Index v = 0; v < n; ++v)
        m_velocities.segment<3>(3 * v) = spec.velocity;
    m_fixed.assign(static_cast<std::size_t>(n), 0);
    m_load_forces = VecX::Zero(3 * n);

    for (std::size_t k = 0; k < spec.fixed.size(); ++k) {
        Index count = 0;
        for (Index v = 0; v < n; ++v)
            if (inside(m_mesh.rest_positions.row(v).transpose(), spec.fixed[k].min, spec.fixed[k].max)) {
                m_fixed[static_cast<std::size_t>(v)] = 1;
                ++count;
            }
        CORO_CHECK(count > 0, InputError,
                   spec.location << ": body '" << m_name << "', [[body.fixed]] " << k
                                 << ": the box holds no node of the body (expected at least one)");
    }
    for (std::size_t k = 0; k < spec.loads.size(); ++k) {
        std::vector<Index> nodes;
        for (Index v = 0; v < n; ++v)
            if (inside(m_mesh.rest_positions.row(v).transpose(), spec.loads[k].min, spec.loads[k].max))
                nodes.push_back(v);
        CORO_CHECK(!nodes.empty(), InputError,
                   spec.location << ": body '" << m_name << "', [[body.load]] " << k
                                 << ": the box holds no node of the body (expected at least one)");
        const Vec3 share = spec.loads[k].force / static_cast<double>(nodes.size());
        for (const Index v : nodes)
            m_load_forces.segment<3>(3 * v) += share;
    }
    for (Index v = 0; v < n; ++v)
        if (m_fixed[static_cast<std::size_t>(v)]) {
            m_velocities.segment<3>(3 * v).setZero();
            ++m_num_fixed;
        }
    m_system = m_fem.make_matrix(precision);
}

void Body::fix_vertex(Index v)
{
    char& fixed = m_fixed[static_cast<std::size_t>(v)];
    m_num_fixed += fixed ? 0 : 1;
    fixed = 1;
}

void Body::set_fixed(const std::vector<char>& fixed)
{
    CORO_CHECK(fixed.size() == m_fixed.size(), InputError,
               "body '" << m_name << "': " << fixed.size() << " fixed flags given, expected one per node ("
                        << m_fixed.size() << ")");
    m_num_fixed = 0;
    for (std::size_t v = 0; v < fixed.size(); ++v) {
        m_fixed[v] = fixed[v] ? 1 : 0;
        if (m_fixed[v]) {
            m_velocities.segment<3>(3 * static_cast<Eigen::Index>(v)).setZero();
            ++m_num_fixed;
        }
    }
}

Positions Body::to_input_order(const VecX& node_values) const
{
    Positions rows(num_vertices(), 3);
    for (Index v = 0; v < num_vertices(); ++v)
        rows.row(input_node(v)) = node_values.segment<3>(3 * v).transpose();
    return rows;
}

VecX Body::from_input_order(CRef<Positions> rows) const
{
    VecX node_values(3 * num_vertices());
    for (Index v = 0; v < num_vertices(); ++v)
        node_values.segment<3>(3 * v) = rows.row(input_node(v)).transpose();
    return node_values;
}

Tets Body::input_tets() const
{
    Tets tets(m_mesh.num_tets(), 4);
    for (Index t = 0; t < m_mesh.num_tets(); ++t)
        for (int a = 0; a < 4; ++a)
            tets(input_tet(t), a) = input_node(m_mesh.tets(t, a));
    return tets;
}

void Body::embed_surface(SurfaceMesh surface)
{
    m_embedding = embed_points(m_mesh, surface.vertices);
    m_embedded_surface = std::move(surface);
}

void Body::project_fixed(Eigen::Ref<VecX> dofs) const
{
    for (std::size_t v = 0; v < m_fixed.size(); ++v)
        if (m_fixed[v])
            dofs.segment<3>(3 * static_cast<Eigen::Index>(v)).setZero();
}

double kinetic_energy(const Body& body)
{
    const VecX& masses = body.fem().lumped_masses();
    double energy = 0.0;
    for (Index i = 0; i < masses.size(); ++i)
        energy += 0.5 * masses[i] * body.velocities().segment<3>(3 * i).squaredNorm();
    return energy;
}

} // namespace coro
