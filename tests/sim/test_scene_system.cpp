#include "beams.hpp"
#include "near.hpp"

#include <corocontact/core/error.hpp>
#include <corocontact/sim/scene_system.hpp>
#include <corocontact/sim/static_solver.hpp>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace coro;

namespace {
PcgSettings tight_pcg()
{
    PcgSettings settings;
    settings.max_iterations = 5000;
    settings.tolerance = 1e-12;
    return settings;
}

// A scene of one body, stepped by SceneSystem.
struct OneBody {
    std::vector<Body> bodies;
    SceneSystem system;
    explicit OneBody(Body body) : bodies(one(std::move(body))), system(bodies) {}
    Body& body() { return bodies.front(); }
    void step(double dt, const Vec3& gravity) { system.step(dt, gravity, {}, tight_pcg()); }
    static std::vector<Body> one(Body body)
    {
        std::vector<Body> bodies;
        bodies.push_back(std::move(body));
        return bodies;
    }
};

// Free DOFs of a body (nodes not fixed), in DOF order.
std::vector<Eigen::Index> free_dofs(const Body& body)
{
    std::vector<Eigen::Index> dofs;
    for (Index v = 0; v < body.num_vertices(); ++v)
        if (!body.fixed()[static_cast<std::size_t>(v)])
            for (int d = 0; d < 3; ++d)
                dofs.push_back(3 * v + d);
    return dofs;
}
} // namespace

TEST(ImplicitEuler, EnergyDecaysExactlyAsImplicitEulerPredictsPerMode)
{
    // Small-amplitude free vibration of a cantilever, no physical damping. Implicit Euler
    // multiplies the energy of a mode of frequency ω by 1/(1 + h²ω²) per step; the predicted
    // energy is that decay applied to the modal decomposition of the initial state.
    test::Cantilever beam;
    beam.tip_force = Vec3(0.0, -0.1, 0.0);
    Body body = beam.body();
    PhaseTimes times;
    ASSERT_TRUE(solve_static(body, 1.0, Vec3::Zero(), tight_pcg(), 1e-8, 20, times).converged);
    body.load_forces().setZero(); // release

    // Modes of the linear system on the free DOFs: K φ = ω² M φ.
    const std::vector<Eigen::Index> dofs = free_dofs(body);
    const auto n = static_cast<Eigen::Index>(dofs.size());
    CorotationalFem reference(body.mesh(), beam.spec().material); // rotations: identity
    BsrMatrix k_bsr = reference.make_matrix();
    reference.assemble(1.0, 0.0, {}, k_bsr);
    const Eigen::MatrixXd k_full = Eigen::MatrixXd(k_bsr.to_sparse());
    Eigen::MatrixXd k(n, n);
    Eigen::VectorXd m(n), u0(n);
    const VecX displacement = body.displacements();
    for (Eigen::Index i = 0; i < n; ++i) {
        for (Eigen::Index j = 0; j < n; ++j)
            k(i, j) = k_full(dofs[static_cast<std::size_t>(i)], dofs[static_cast<std::size_t>(j)]);
        m[i] = reference.lumped_masses()[dofs[static_cast<std::size_t>(i)] / 3];
        u0[i] = displacement[dofs[static_cast<std::size_t>(i)]];
    }
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> modes(k, Eigen::MatrixXd(m.asDiagonal()));
    const Eigen::VectorXd omega2 = modes.eigenvalues();
    const Eigen::VectorXd amplitude = modes.eigenvectors().transpose() * (m.asDiagonal() * u0); // M-orthonormal
    const double h = 0.5 / std::sqrt(omega2[0]); // ω₁h = 0.5: strong numerical damping

    const auto energy = [&](const Body& b) {
        return kinetic_energy(b) + b.fem().strain_energy(b.positions());
    };
    OneBody scene(std::move(body));
    const double e0 = energy(scene.body());
    const double e0_modal = 0.5 * (omega2.array() * amplitude.array().square()).sum();
    ASSERT_NEAR(e0, e0_modal, 1e-6 * e0);

    for (int step = 1; step <= 40; ++step) {
        scene.step(h, Vec3::Zero());
        const double predicted =
            0.5 * (omega2.array() * amplitude.array().square() * (1.0 + h * h * omega2.array()).pow(-step)).sum();
        const double measured = energy(scene.body());
        ASSERT_NEAR(measured / predicted, 1.0, 2e-3) << "step " << step;
        if (step % 10 == 0)
            std::printf("step %d: E/E0 measured %.6f, implicit Euler predicts %.6f\n", step, measured / e0,
                        predicted / e0);
    }
}

TEST(ImplicitEuler, DampedBeamSettlesToStaticSolution)
{
    test::Cantilever beam;
    beam.young = 2e7;
    const Vec3 gravity(0.0, -9.81, 0.0);

    OneBody scene([&] {
        BodySpec spec = beam.spec();
        spec.rayleigh_mass = 2.0;
        spec.rayleigh_stiffness = 0.01;
        return Body(make_box(spec.box_min, spec.box_max, spec.cells), spec);
    }());
    for (int step = 0; step < 400; ++step)
        scene.step(0.1, gravity);
    const Body& settled = scene.body();
    PhaseTimes times;

    Body reference = beam.body();
    double factor = 0.0;
    for (int k = 1; k <= 4; ++k) {
        factor = k / 4.0;
        ASSERT_TRUE(solve_static(reference, factor, gravity, tight_pcg(), 1e-10, 50, times).converged);
    }
    const Vec3 tip_dynamic = test::tip_displacement(settled, beam.length);
    const Vec3 tip_static = test::tip_displacement(reference, beam.length);
    std::printf("tip after settling %.6g %.6g, static %.6g %.6g\n", tip_dynamic.x(), tip_dynamic.y(),
                tip_static.x(), tip_static.y());
    EXPECT_LT(tip_static.y(), -0.04 * beam.length); // a visible sag, and the tip moves inward:
    EXPECT_LT(tip_static.x(), -1e-3);
    EXPECT_NEAR_REL(tip_dynamic, tip_static, 1e-6, 1e-4);
    EXPECT_LT(settled.velocities().cwiseAbs().maxCoeff(), 1e-5);
}

TEST(ImplicitEuler, FreeFallUnderGravityIsExact)
{
    // An unconstrained body falls rigidly: v⁺ = v + h g each step, no internal force.
    test::Cantilever beam;
    BodySpec spec = beam.spec();
    spec.fixed.clear();
    OneBody scene(Body(make_box(spec.box_min, spec.box_max, spec.cells), spec));
    const Vec3 g(0.0, 0.0, -9.81);
    for (int step = 0; step < 10; ++step)
        scene.step(0.01, g);
    const Body& body = scene.body();
    for (Index v = 0; v < body.num_vertices(); ++v)
        ASSERT_NEAR_REL(body.velocities().segment<3>(3 * v), Vec3(10 * 0.01 * g), 1e-10, 0.0);
}

TEST(ImplicitEuler, NonFiniteStateIsNamedAsNumericalError)
{
    test::Cantilever beam;
    OneBody scene(beam.body());
    scene.body().positions()[3 * 17 + 1] = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(scene.step(0.01, Vec3::Zero()), NumericalError);
}
