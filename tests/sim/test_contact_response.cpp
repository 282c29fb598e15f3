#include "near.hpp"

#include <corocontact/core/primitives.hpp>
#include <corocontact/core/surface_mesh.hpp>
#include <corocontact/io/case_reader.hpp>
#include <corocontact/io/surface_readers.hpp>
#include <corocontact/io/scene_loader.hpp>
#include <corocontact/sim/simulation.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

using namespace coro;

namespace {

struct LoadedCase {
    CaseSpec spec;
    LoadedScene loaded;
};

LoadedCase load(const std::string& text)
{
    LoadedCase run{parse_case(text, "test.toml"), {}};
    run.loaded = load_scene(run.spec);
    return run;
}

Vec3 momentum(const Scene& scene)
{
    Vec3 p = Vec3::Zero();
    for (const Body& body : scene.bodies)
        for (Index v = 0; v < body.num_vertices(); ++v)
            p += body.fem().lumped_masses()[v] * body.velocities().segment<3>(3 * v);
    return p;
}

double energy(const Scene& scene)
{
    double e = 0.0;
    for (const Body& body : scene.bodies)
        e += kinetic_energy(body) + body.fem().strain_energy(body.positions());
    return e;
}

std::string two_spheres(double stiffness, double speed = 2.0, double gap = 0.4, int steps = 120)
{
    return R"toml([simulation]
dt = 0.005
steps = )toml" + std::to_string(steps) + R"toml(
[solver]
max_iterations = 400
tolerance = 1e-10
[contact]
enabled = true
stiffness = )toml" + std::to_string(stiffness) + R"toml(
[[body]]
name = "left"
shape = "sphere"
radius = 0.5
resolution = 8
translate = [)toml" + std::to_string(-0.5 - gap / 2) + R"toml(, 0.05, 0.0]
velocity = [)toml" + std::to_string(speed) + R"toml(, 0.0, 0.0]
young = 2e5
density = 1000.0
[[body]]
name = "right"
shape = "sphere"
radius = 0.5
resolution = 8
translate = [)toml" + std::to_string(0.5 + gap / 2) + R"toml(, -0.05, 0.0]
velocity = [)toml" + std::to_string(-speed) + R"toml(, 0.0, 0.0]
young = 2e5
density = 1000.0
)toml";
}

} // namespace

TEST(ContactResponse, HeadOnSpheresConserveMomentumAndGainNoEnergy)
{
    LoadedCase run = load(two_spheres(1e6));
    Scene& scene = run.loaded.scene;
    Simulation simulation(scene, run.spec);
    const Vec3 p0 = momentum(scene);
    const double reference = 2.0 * scene.bodies[0].fem().lumped_masses().sum() * 2.0; // Σ m|v|
    const double e0 = energy(scene);
    double largest_momentum_error = 0.0, largest_energy = 0.0;
    bool touched = false;
    simulation.run(run.spec.simulation.steps, nullptr, [&](Index, Index) {
        largest_momentum_error = std::max(largest_momentum_error, (momentum(scene) - p0).norm() / reference);
        largest_energy = std::max(largest_energy, energy(scene));
        touched = touched || !scene.contacts.empty();
    });
    ASSERT_TRUE(touched);
    // The spheres separated again: they move apart.
    double vx_left = 0.0;
    const Body& left = scene.bodies[0];
    for (Index v = 0; v < left.num_vertices(); ++v)
        vx_left += left.fem().lumped_masses()[v] * left.velocities()[3 * v] / left.fem().lumped_masses().sum();
    EXPECT_LT(vx_left, -0.5) << "the left sphere bounced back";
    std::printf("momentum error %.2e of sum m|v|; energy max/initial %.6f\n", largest_momentum_error, largest_energy / e0);
    EXPECT_LT(largest_momentum_error, 0.01);
    EXPECT_LE(largest_energy, e0 * (1.0 + 1e-6));
}

TEST(ContactResponse, PenetrationShrinksAsStiffnessGrows)
{
    // Slow spheres (0.5 m/s each, 5 mm of relative travel per step) so that the penetration
    // is set by the penalty, not by how far a vertex moves in one step.
    double previous = 1e300;
    for (const double k : {2e3, 2e4, 2e5}) {
        LoadedCase run = load(two_spheres(k, 0.5, 0.1, 90));
        Simulation simulation(run.loaded.scene, run.spec);
        const RunSummary summary = simulation.run(run.spec.simulation.steps, nullptr, nullptr);
        std::printf("stiffness %.0e: max depth %.4g m\n", k, summary.max_contact_depth);
        EXPECT_GT(summary.max_contact_depth, 0.0);
        EXPECT_LT(summary.max_contact_depth, 0.8 * previous) << "stiffness " << k;
        previous = summary.max_contact_depth;
    }
}

namespace {
std::string box_on_plane(double degrees, double friction, double stiffness, double mass_damping)
{
    const double t = degrees * M_PI / 180.0;
    char normal[96];
    std::snprintf(normal, sizeof normal, "[%.17g, %.17g, 0.0]", -std::sin(t), std::cos(t));
    return R"toml([simulation]
dt = 0.002
steps = 500
gravity = [0.0, -9.81, 0.0]
[solver]
max_iterations = 300
tolerance = 1e-10
[contact]
enabled = true
stiffness = )toml" + std::to_string(stiffness) + R"toml(
damping = 20.0
friction = )toml" + std::to_string(friction) + R"toml(
[[body]]
name = "box"
shape = "box"
min = [-0.1, 0.0, -0.1]
max = [0.1, 0.1, 0.1]
cells = [2, 1, 2]
rotate_axis = [0.0, 0.0, 1.0]
rotate_degrees = )toml" + std::to_string(degrees) + R"toml(
young = 1e7
density = 1000.0
rayleigh_mass = )toml" + std::to_string(mass_damping) + R"toml(
[[obstacle]]
type = "plane"
point = [0.0, 0.0, 0.0]
normal = )toml" + normal + "\n";
}
} // namespace

TEST(ContactResponse, BoxRestsOnPlaneWithStaticEquilibriumPenetration)
{
    // At rest the bottom nodes carry the weight: Σ k δ_i = m g. The box is stiff, so the
    // bottom stays flat and every bottom node sinks by δ = m g / (k n_bottom).
    const double k = 1e5;
    LoadedCase run = load(box_on_plane(0.0, 0.0, k, 5.0)); // damped so that it settles
    Scene& scene = run.loaded.scene;
    Simulation simulation(scene, run.spec);
    simulation.run(run.spec.simulation.steps, nullptr, nullptr);
    const Body& box = scene.bodies[0];
    const double weight = box.fem().lumped_masses().sum() * 9.81;
    Index bottom = 0;
    double depth_sum = 0.0;
    for (const ContactPoint& c : scene.contacts) {
        ++bottom;
        depth_sum += c.depth;
    }
    ASSERT_EQ(bottom, 9); // the 3×3 nodes of the bottom face
    const double predicted = weight / (k * bottom);
    std::printf("resting box: mean depth %.6g m, static equilibrium %.6g m\n", depth_sum / bottom, predicted);
    EXPECT_NEAR(depth_sum / bottom, predicted, 0.01 * predicted);
    EXPECT_LT(box.velocities().cwiseAbs().maxCoeff(), 1e-3);
}

TEST(ContactResponse, BoxRestsOnAMeshObstacleAsOnAPlane)
{
    // The floor as a closed triangle surface (an OBJ slab) instead of a plane: same contacts,
    // same static equilibrium depth.
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "coro_test_mesh_obstacle";
    std::filesystem::create_directories(dir);
    const TetMesh slab = make_box(Vec3(-1.0, -0.3, -1.0), Vec3(1.0, 0.0, 1.0), {1, 1, 1});
    SurfaceMesh floor;
    floor.faces = boundary_faces(slab);
    floor.vertices = slab.rest_positions; // every node of a 1-cell box is on its surface
    write_obj(dir / "floor.obj", floor);

    std::string text = box_on_plane(0.0, 0.0, 1e5, 5.0);
    text = text.substr(0, text.find("[[obstacle]]")) + "[[obstacle]]\ntype = \"mesh\"\nmesh = \"" +
           (dir / "floor.obj").string() + "\"\n";
    LoadedCase run = load(text);
    ASSERT_EQ(run.loaded.scene.obstacle_meshes.size(), 1u);
    Scene& scene = run.loaded.scene;
    Simulation simulation(scene, run.spec);
    simulation.run(run.spec.simulation.steps, nullptr, nullptr);
    double depth_sum = 0.0;
    Index count = 0;
    for (const ContactPoint& c : scene.contacts)
        if (c.body == 0) {
            depth_sum += c.depth;
            ++count;
            EXPECT_NEAR_REL(c.normal, Vec3::UnitY(), 1e-12, 0.0);
        }
    ASSERT_EQ(count, 9);
    const double predicted = scene.bodies[0].fem().lumped_masses().sum() * 9.81 / (1e5 * count);
    std::printf("box on a mesh obstacle: mean depth %.6g m, static equilibrium %.6g m\n", depth_sum / count, predicted);
    EXPECT_NEAR(depth_sum / count, predicted, 0.01 * predicted);
}

TEST(ContactResponse, EmbeddedSurfaceForcesKeepTotalForceAndMoment)
{
    // A fine sphere surface embedded in a coarse tet sphere, pressed into a plane: the contact
    // forces reach the tet nodes through barycentric weights; their total force and moment
    // about the origin equal those of the forces on the surface vertices.
    LoadedCase run = load(R"toml([contact]
enabled = true
stiffness = 1000.0
[[body]]
name = "ball"
shape = "sphere"
radius = 0.5
resolution = 4
[[obstacle]]
type = "plane"
point = [0.0, -0.45, 0.0]
normal = [0.3, 1.0, 0.1]
)toml");
    Body& body = run.loaded.scene.bodies[0];
    const TetMesh fine = make_sphere(Vec3::Zero(), 0.49, 10);
    SurfaceMesh surface;
    surface.faces = boundary_faces(fine);
    surface.vertices = fine.rest_positions; // interior nodes are unused vertices: harmless
    body.embed_surface(surface);
    Scene& scene = run.loaded.scene;
    Simulation simulation(scene, run.spec);
    simulation.run(0, nullptr, nullptr); // detection and response on the initial state only
    ASSERT_FALSE(scene.contacts.empty());

    Vec3 force = Vec3::Zero(), moment = Vec3::Zero();
    const Positions at_surface = embedded_positions(body.embedding(), as_positions(body.positions()));
    for (const ContactPoint& c : scene.contacts) {
        const Vec3 f = run.spec.contact.stiffness * c.depth * c.normal; // on the surface vertex
        force += f;
        moment += at_surface.row(c.vertex).transpose().cross(f);
    }
    Vec3 node_force = Vec3::Zero(), node_moment = Vec3::Zero();
    const VecX& f_nodes = scene.contact_forces[0];
    for (Index v = 0; v < body.num_vertices(); ++v) {
        node_force += f_nodes.segment<3>(3 * v);
        node_moment += body.positions().segment<3>(3 * v).cross(Vec3(f_nodes.segment<3>(3 * v)));
    }
    EXPECT_GT(force.norm(), 0.0);
    EXPECT_NEAR_REL(node_force, force, 1e-12 * force.norm(), 0.0);
    EXPECT_NEAR_REL(node_moment, moment, 1e-12 * force.norm(), 0.0);
}

TEST(ContactResponse, FrictionSticksBelowAndSlidesAboveTheFrictionAngle)
{
    // μ = 0.5: tan 20° = 0.36 < μ sticks, tan 35° = 0.70 > μ slides.
    double travel[2] = {0.0, 0.0};
    const double angles[2] = {20.0, 35.0};
    for (int i = 0; i < 2; ++i) {
        LoadedCase run = load(box_on_plane(angles[i], 0.5, 1e5, 0.0));
        Scene& scene = run.loaded.scene;
        Simulation simulation(scene, run.spec);
        const Vec3 start = as_positions(scene.bodies[0].positions()).colwise().mean().transpose();
        simulation.run(run.spec.simulation.steps, nullptr, nullptr);
        travel[i] = (as_positions(scene.bodies[0].positions()).colwise().mean().transpose() - start).norm();
        std::printf("tilt %.0f deg: the box moved %.4g m in 1 s\n", angles[i], travel[i]);
    }
    EXPECT_LT(travel[0], 0.01);
    // Sliding: a = g (sin θ − μ cos θ) = 1.609 m/s², s = a t²/2 = 0.804 m after 1 s.
    const double t35 = 35.0 * M_PI / 180.0;
    const double slide = 0.5 * 9.81 * (std::sin(t35) - 0.5 * std::cos(t35));
    EXPECT_NEAR(travel[1], slide, 0.05 * slide);
}
