#include <corocontact/sim/integrator.hpp>

#include <corocontact/core/error.hpp>

#include <chrono>

namespace coro {

namespace {
// Adds m_i·g to every node's entry of `f`.
void add_gravity(const VecX& masses, const Vec3& gravity, Eigen::Ref<VecX> f)
{
    for (Eigen::Index v = 0; v < masses.size(); ++v)
        f.segment<3>(3 * v) += masses[v] * gravity;
}

void check_finite(const Body& body, const VecX& values, const char* what)
{
    if (values.allFinite())
        return;
    Eigen::Index first = 0;
    while (std::isfinite(values[first]))
        ++first;
    CORO_THROW(NumericalError, "body '" << body.name() << "': " << what << " of node "
                                        << body.input_node(static_cast<Index>(first / 3)) << " (mesh file order) is "
                                        << values[first]);
}
} // namespace

VecX assemble_implicit_euler(Body& body, double dt, const Vec3& gravity, const VecX& extra_forces, PhaseTimes& times)
{
    CorotationalFem& fem = body.fem();
    const VecX& x = body.positions();
    const VecX& v = body.velocities();
    const VecX& masses = fem.lumped_masses();
    const double alpha = body.rayleigh_mass(), beta = body.rayleigh_stiffness();
    VecX rhs(x.size());
    {
        // Rotations, rotated stiffness and internal forces in one pass over the tets; its time
        // is split between the two phases as the pass measured it.
        const auto start = std::chrono::steady_clock::now();
        const double rotation = fem.rotate_and_assemble_with_forces(x, dt * dt + dt * beta, 1.0 + dt * alpha,
                                                                    body.fixed(), body.system_matrix(), rhs);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        times.rotation += rotation;
        times.assembly += seconds - rotation;
    }
    ScopedTimer timer(times.assembly);
    rhs += body.load_forces();
    if (extra_forces.size() > 0)
        rhs += extra_forces;
    add_gravity(masses, gravity, rhs);
    rhs *= dt;
    for (Eigen::Index i = 0; i < masses.size(); ++i)
        rhs.segment<3>(3 * i) += masses[i] * v.segment<3>(3 * i);
    body.project_fixed(rhs);
    return rhs;
}

PcgResult implicit_euler_step(Body& body, double dt, const Vec3& gravity, const PcgSettings& settings,
                              PhaseTimes& times)
{
    VecX& x = body.positions();
    VecX& v = body.velocities();
    const VecX rhs = assemble_implicit_euler(body, dt, gravity, VecX(), times);
    PcgResult result;
    {
        ScopedTimer timer(times.solve);
        body.project_fixed(v);
        result = body.pcg().solve(body.system_matrix(), rhs, v, settings);
    }
    check_finite(body, v, "velocity");
    x += dt * v;
    return result;
}

double kinetic_energy(const Body& body)
{
    const VecX& masses = body.fem().lumped_masses();
    double energy = 0.0;
    for (Eigen::Index i = 0; i < masses.size(); ++i)
        energy += 0.5 * masses[i] * body.velocities().segment<3>(3 * i).squaredNorm();
    return energy;
}

} // namespace coro
