#pragma once
// One body's linearly implicit Euler system without contact, for the solver benchmarks:
// (M + hC + h²K') v⁺ = M v + h (f0 − K'x + f_ext + m g), C = αM + βK', fixed nodes projected —
// the body's part of what SceneSystem assembles, into the body's own matrix.

#include <corocontact/sim/body.hpp>

namespace coro::bench {

/// Fills body.system_matrix() at the current positions and returns the right-hand side, #3V.
inline VecX implicit_euler_system(Body& body, double dt, const Vec3& gravity)
{
    CorotationalFem& fem = body.fem();
    fem.update_rotations(body.positions());
    fem.assemble(dt * dt + dt * body.rayleigh_stiffness(), 1.0 + dt * body.rayleigh_mass(), body.fixed(),
                 body.system_matrix());
    VecX rhs(body.positions().size());
    fem.internal_forces(body.positions(), rhs);
    rhs += body.load_forces();
    const VecX& masses = fem.lumped_masses();
    for (Eigen::Index v = 0; v < masses.size(); ++v)
        rhs.segment<3>(3 * v) += masses[v] * gravity;
    rhs *= dt;
    for (Eigen::Index v = 0; v < masses.size(); ++v)
        rhs.segment<3>(3 * v) += masses[v] * body.velocities().segment<3>(3 * v);
    body.project_fixed(rhs);
    return rhs;
}

} // namespace coro::bench
