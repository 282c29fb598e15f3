#pragma once
/// @file beams.hpp
/// @brief Cantilever beams for the solver tests: [0,L]×[0,1]×[0,1], clamped at x = 0.

#include <corocontact/core/primitives.hpp>
#include <corocontact/sim/body.hpp>
#include <corocontact/sim/case_spec.hpp>

namespace coro::test {

struct Cantilever {
    double length = 5.0;
    Index cells_along = 10;   ///< cells along x
    Index cells_across = 2;   ///< cells along y and z
    double young = 1e5;
    double poisson = 0.3;
    double density = 1000.0;
    Vec3 tip_force = Vec3::Zero(); ///< total force on the face x = L [N]

    BodySpec spec() const
    {
        BodySpec spec;
        spec.name = "beam";
        spec.location = "test";
        spec.shape = BodyShape::BOX;
        spec.box_min = Vec3::Zero();
        spec.box_max = Vec3(length, 1.0, 1.0);
        spec.cells = {cells_along, cells_across, cells_across};
        spec.material.young = young;
        spec.material.poisson = poisson;
        spec.material.density = density;
        FixedRegion clamp;
        clamp.max = Vec3(1e-9, 10.0, 10.0);
        spec.fixed.push_back(clamp);
        if (tip_force.norm() > 0.0) {
            BoxLoad load;
            load.min = Vec3(length - 1e-9, -10.0, -10.0);
            load.force = tip_force;
            spec.loads.push_back(load);
        }
        return spec;
    }

    Body body() const
    {
        const BodySpec s = spec();
        return Body(make_box(s.box_min, s.box_max, s.cells), s);
    }

    /// Second moment of area of the 1×1 section, I = 1/12.
    static double second_moment() { return 1.0 / 12.0; }
};

/// Mean displacement of the nodes on the face x = L, #3.
inline Vec3 tip_displacement(const Body& body, double length)
{
    Vec3 sum = Vec3::Zero();
    int count = 0;
    const VecX u = body.displacements();
    for (Index v = 0; v < body.num_vertices(); ++v)
        if (body.mesh().rest_positions(v, 0) > length - 1e-9) {
            sum += u.segment<3>(3 * v);
            ++count;
        }
    return sum / count;
}

} // namespace coro::test
