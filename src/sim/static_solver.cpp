#include <corocontact/sim/static_solver.hpp>

#include <corocontact/core/error.hpp>
#include <corocontact/solver/vector_ops.hpp>

#include <algorithm>
#include <cmath>

namespace coro {

StaticResult solve_static(Body& body, double load_factor, const Vec3& gravity,
                          const PcgSettings& settings, double tolerance, Index max_iterations,
                          PhaseTimes& times)
{
    CorotationalFem& fem = body.fem();
    VecX& x = body.positions();
    const VecX& masses = fem.lumped_masses();

    VecX load = body.load_forces();
    for (Eigen::Index v = 0; v < masses.size(); ++v)
        load.segment<3>(3 * v) += masses[v] * gravity;
    load *= load_factor;
    body.project_fixed(load);

    StaticResult result;
    VecX residual(x.size()), step(x.size());
    double reference = norm(load);
    for (Index iteration = 0;; ++iteration) {
        {
            ScopedTimer timer(times.rotation);
            fem.update_rotations(x);
        }
        {
            ScopedTimer timer(times.assembly);
            fem.internal_forces(x, residual);
            if (iteration == 0 && reference == 0.0)
                reference = norm(residual);
            residual += load;
            body.project_fixed(residual);
        }
        result.residual = reference > 0.0 ? norm(residual) / reference : 0.0;
        CORO_CHECK(std::isfinite(result.residual), NumericalError,
                   "body '" << body.name() << "': static residual is not finite at iteration " << iteration);
        result.iterations = iteration;
        if (result.residual <= tolerance) {
            result.converged = true;
            break;
        }
        if (iteration >= max_iterations)
            break;
        {
            ScopedTimer timer(times.assembly);
            fem.assemble(1.0, 0.0, body.fixed(), body.system_matrix());
        }
        {
            ScopedTimer timer(times.solve);
            step.setZero();
            const PcgResult solve = body.pcg().solve(body.system_matrix(), residual, step, settings);
            result.cg_iterations += solve.iterations;
        }
        x += step;
    }
    return result;
}

} // namespace coro
