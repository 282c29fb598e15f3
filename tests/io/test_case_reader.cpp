#include <corocontact/core/error.hpp>
#include <corocontact/io/case_reader.hpp>

#include "../common/mesh_fixtures.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <ostream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;
using ::testing::ThrowsMessage;

namespace {

const std::string BOX = "[[body]]\nshape = \"box\"\n";

coro::CaseSpec parse(const std::string& text) { return coro::parse_case(text, "case.toml"); }

/// 1-based number of the `nth` (0-based) line of `text` that contains `needle`.
int line_of(const std::string& text, const std::string& needle, int nth = 0)
{
    std::istringstream in(text);
    std::string line;
    for (int number = 1; std::getline(in, line); ++number)
        if (line.find(needle) != std::string::npos && nth-- == 0)
            return number;
    return -1;
}

} // namespace

// ---------------------------------------------------------------------------------------------
// Valid cases

TEST(ReadCase, FullCaseParsesEveryKey)
{
    const fs::path dir = coro::test::scratch_dir("case_full");
    const fs::path ground = dir / "rigid" / "ground.obj";
    const std::string text = R"([simulation]
name = "two_spheres"
analysis = "static"
dt = 0.005
steps = 200
load_steps = 12
gravity = [0.0, -9.81, 0]
output_every = 5
output_dir = "results/run1"

[solver]
max_iterations = 40
tolerance = 1e-7
preconditioner = "jacobi"
matrix_precision = "single"
static_tolerance = 1e-9
static_max_iterations = 30
parts_per_thread = 2

[contact]
enabled = true
mode = "paper"
stiffness = 2e5
damping = 0.5
friction = 0.3
cross_check = "embree"

[[body]]
name = "left"
mesh = "meshes/left.msh"
surface = "../shared/left_fine.obj"
translate = [1.0, 2.0, 3.0]
rotate_axis = [1, 0, 0]
rotate_degrees = 90
scale = 2.5
velocity = [0.0, -1.0, 0.5]
young = 2e6
poisson = 0.45
density = 1100.0
rayleigh_mass = 0.1
rayleigh_stiffness = 0.001
[[body.fixed]]
min = [-1e9, -1e9, -1e9]
max = [0.0, 1e9, 1e9]
[[body.fixed]]
min = [5, 5, 5]
max = [6, 6, 6]
[[body.load]]
min = [9.999, -1e9, -1e9]
max = [1e9, 1e9, 1e9]
force = [0.0, -1.0, 0.0]

[[body]]
name = "block"
shape = "box"
min = [-1, -2, -3]
max = [1, 2, 3]
cells = [2, 4, 6]

[[body]]
name = "ball"
shape = "sphere"
center = [0, 5, 0]
radius = 0.5
resolution = 6

[[obstacle]]
type = "plane"
point = [0, -1, 0]
normal = [0, 2, 0]

[[obstacle]]
type = "mesh"
mesh = ")" + ground.string() + "\"\n";
    const fs::path file = coro::test::write_text(dir / "scene" / "full.toml", text);

    const coro::CaseSpec spec = coro::read_case(file);
    EXPECT_EQ(spec.file, file);

    const coro::SimulationSettings& sim = spec.simulation;
    EXPECT_EQ(sim.name, "two_spheres");
    EXPECT_EQ(sim.analysis, coro::Analysis::STATIC);
    EXPECT_EQ(sim.dt, 0.005);
    EXPECT_EQ(sim.steps, 200);
    EXPECT_EQ(sim.load_steps, 12);
    EXPECT_EQ(sim.gravity, coro::Vec3(0.0, -9.81, 0.0));
    EXPECT_EQ(sim.output_every, 5);
    EXPECT_EQ(sim.output_dir, fs::path("results/run1"));

    const coro::SolverSettings& solver = spec.solver;
    EXPECT_EQ(solver.max_iterations, 40);
    EXPECT_EQ(solver.tolerance, 1e-7);
    EXPECT_EQ(solver.preconditioner, coro::PcgPreconditioner::JACOBI);
    EXPECT_EQ(solver.matrix_precision, coro::MatrixPrecision::SINGLE);
    EXPECT_EQ(solver.static_tolerance, 1e-9);
    EXPECT_EQ(solver.static_max_iterations, 30);
    EXPECT_EQ(solver.parts_per_thread, 2);

    const coro::ContactSettings& contact = spec.contact;
    EXPECT_TRUE(contact.enabled);
    EXPECT_EQ(contact.mode, coro::ContactMode::PAPER);
    EXPECT_EQ(contact.stiffness, 2e5);
    EXPECT_EQ(contact.damping, 0.5);
    EXPECT_EQ(contact.friction, 0.3);
    EXPECT_EQ(contact.cross_check, coro::CrossCheck::EMBREE);

    ASSERT_EQ(spec.bodies.size(), 3u);
    const coro::BodySpec& left = spec.bodies[0];
    EXPECT_EQ(left.name, "left");
    EXPECT_EQ(left.location, file.string() + ":" + std::to_string(line_of(text, "[[body]]", 0)));
    EXPECT_EQ(left.shape, coro::BodyShape::MESH);
    EXPECT_EQ(left.mesh, dir / "scene" / "meshes" / "left.msh");
    EXPECT_EQ(left.surface, dir / "shared" / "left_fine.obj");
    EXPECT_EQ(left.transform.translate, coro::Vec3(1.0, 2.0, 3.0));
    EXPECT_EQ(left.transform.rotate_axis, coro::Vec3(1.0, 0.0, 0.0));
    EXPECT_EQ(left.transform.rotate_degrees, 90.0);
    EXPECT_EQ(left.transform.scale, 2.5);
    EXPECT_EQ(left.velocity, coro::Vec3(0.0, -1.0, 0.5));
    EXPECT_EQ(left.material.young, 2e6);
    EXPECT_EQ(left.material.poisson, 0.45);
    EXPECT_EQ(left.material.density, 1100.0);
    EXPECT_EQ(left.rayleigh_mass, 0.1);
    EXPECT_EQ(left.rayleigh_stiffness, 0.001);
    ASSERT_EQ(left.fixed.size(), 2u);
    EXPECT_EQ(left.fixed[0].min, coro::Vec3::Constant(-1e9));
    EXPECT_EQ(left.fixed[0].max, coro::Vec3(0.0, 1e9, 1e9));
    EXPECT_EQ(left.fixed[1].min, coro::Vec3::Constant(5.0));
    EXPECT_EQ(left.fixed[1].max, coro::Vec3::Constant(6.0));
    ASSERT_EQ(left.loads.size(), 1u);
    EXPECT_EQ(left.loads[0].min, coro::Vec3(9.999, -1e9, -1e9));
    EXPECT_EQ(left.loads[0].max, coro::Vec3::Constant(1e9));
    EXPECT_EQ(left.loads[0].force, coro::Vec3(0.0, -1.0, 0.0));

    const coro::BodySpec& block = spec.bodies[1];
    EXPECT_EQ(block.name, "block");
    EXPECT_EQ(block.location, file.string() + ":" + std::to_string(line_of(text, "[[body]]", 1)));
    EXPECT_EQ(block.shape, coro::BodyShape::BOX);
    EXPECT_TRUE(block.mesh.empty());
    EXPECT_TRUE(block.surface.empty());
    EXPECT_EQ(block.box_min, coro::Vec3(-1.0, -2.0, -3.0));
    EXPECT_EQ(block.box_max, coro::Vec3(1.0, 2.0, 3.0));
    EXPECT_EQ(block.cells, (std::array<coro::Index, 3>{2, 4, 6}));

    const coro::BodySpec& ball = spec.bodies[2];
    EXPECT_EQ(ball.name, "ball");
    EXPECT_EQ(ball.shape, coro::BodyShape::SPHERE);
    EXPECT_EQ(ball.center, coro::Vec3(0.0, 5.0, 0.0));
    EXPECT_EQ(ball.radius, 0.5);
    EXPECT_EQ(ball.resolution, 6);

    ASSERT_EQ(spec.obstacles.size(), 2u);
    EXPECT_EQ(spec.obstacles[0].type, coro::ObstacleType::PLANE);
    EXPECT_EQ(spec.obstacles[0].location,
              file.string() + ":" + std::to_string(line_of(text, "[[obstacle]]", 0)));
    EXPECT_EQ(spec.obstacles[0].point, coro::Vec3(0.0, -1.0, 0.0));
    EXPECT_EQ(spec.obstacles[0].normal, coro::Vec3(0.0, 1.0, 0.0)); // normalised
    EXPECT_EQ(spec.obstacles[1].type, coro::ObstacleType::MESH);
    EXPECT_EQ(spec.obstacles[1].location,
              file.string() + ":" + std::to_string(line_of(text, "[[obstacle]]", 1)));
    EXPECT_EQ(spec.obstacles[1].mesh, ground);
    fs::remove_all(dir);
}

TEST(ReadCase, OmittedKeysTakeTheDocumentedDefaults)
{
    const fs::path dir = coro::test::scratch_dir("case_defaults");
    const std::string text = BOX + "[[body]]\nshape = \"sphere\"\n[[body.fixed]]\n[[obstacle]]\n";
    const coro::CaseSpec spec = coro::parse_case(text, dir / "minimal.toml");

    const coro::SimulationSettings sim_default;
    EXPECT_EQ(spec.simulation.name, "minimal"); // the case file's stem
    EXPECT_EQ(spec.simulation.analysis, sim_default.analysis);
    EXPECT_EQ(spec.simulation.dt, sim_default.dt);
    EXPECT_EQ(spec.simulation.steps, sim_default.steps);
    EXPECT_EQ(spec.simulation.load_steps, sim_default.load_steps);
    EXPECT_EQ(spec.simulation.gravity, sim_default.gravity);
    EXPECT_EQ(spec.simulation.output_every, sim_default.output_every);
    EXPECT_EQ(spec.simulation.output_dir, fs::path("out") / "minimal");

    const coro::SolverSettings solver_default;
    EXPECT_EQ(spec.solver.max_iterations, solver_default.max_iterations);
    EXPECT_EQ(spec.solver.tolerance, solver_default.tolerance);
    EXPECT_EQ(spec.solver.preconditioner, solver_default.preconditioner);
    EXPECT_EQ(spec.solver.static_tolerance, solver_default.static_tolerance);
    EXPECT_EQ(spec.solver.static_max_iterations, solver_default.static_max_iterations);
    EXPECT_EQ(spec.solver.parts_per_thread, solver_default.parts_per_thread);

    const coro::ContactSettings contact_default;
    EXPECT_EQ(spec.contact.enabled, contact_default.enabled);
    EXPECT_EQ(spec.contact.mode, contact_default.mode);
    EXPECT_EQ(spec.contact.stiffness, contact_default.stiffness);
    EXPECT_EQ(spec.contact.damping, contact_default.damping);
    EXPECT_EQ(spec.contact.friction, contact_default.friction);
    EXPECT_EQ(spec.contact.cross_check, contact_default.cross_check);

    const coro::BodySpec body_default;
    ASSERT_EQ(spec.bodies.size(), 2u);
    const coro::BodySpec& box = spec.bodies[0];
    EXPECT_EQ(box.name, "body0");
    EXPECT_EQ(box.shape, coro::BodyShape::BOX);
    EXPECT_EQ(box.box_min, body_default.box_min);
    EXPECT_EQ(box.box_max, body_default.box_max);
    EXPECT_EQ(box.cells, body_default.cells);
    EXPECT_TRUE(box.surface.empty());
    EXPECT_EQ(box.transform.translate, body_default.transform.translate);
    EXPECT_EQ(box.transform.rotate_axis, body_default.transform.rotate_axis);
    EXPECT_EQ(box.transform.rotate_degrees, body_default.transform.rotate_degrees);
    EXPECT_EQ(box.transform.scale, body_default.transform.scale);
    EXPECT_EQ(box.velocity, body_default.velocity);
    EXPECT_EQ(box.material.young, body_default.material.young);
    EXPECT_EQ(box.material.poisson, body_default.material.poisson);
    EXPECT_EQ(box.material.density, body_default.material.density);
    EXPECT_EQ(box.rayleigh_mass, body_default.rayleigh_mass);
    EXPECT_EQ(box.rayleigh_stiffness, body_default.rayleigh_stiffness);
    EXPECT_TRUE(box.fixed.empty());
    EXPECT_TRUE(box.loads.empty());

    const coro::BodySpec& ball = spec.bodies[1];
    EXPECT_EQ(ball.name, "body1");
    EXPECT_EQ(ball.shape, coro::BodyShape::SPHERE);
    EXPECT_EQ(ball.center, body_default.center);
    EXPECT_EQ(ball.radius, body_default.radius);
    EXPECT_EQ(ball.resolution, body_default.resolution);
    ASSERT_EQ(ball.fixed.size(), 1u); // an empty [[body.fixed]] fixes every node
    EXPECT_EQ(ball.fixed[0].min, coro::FixedRegion().min);
    EXPECT_EQ(ball.fixed[0].max, coro::FixedRegion().max);

    const coro::ObstacleSpec obstacle_default;
    ASSERT_EQ(spec.obstacles.size(), 1u);
    EXPECT_EQ(spec.obstacles[0].type, obstacle_default.type);
    EXPECT_EQ(spec.obstacles[0].point, obstacle_default.point);
    EXPECT_EQ(spec.obstacles[0].normal, obstacle_default.normal);
    fs::remove_all(dir);
}

TEST(ReadCase, IntegersAreAcceptedWhereNumbersAreExpected)
{
    const coro::CaseSpec spec = parse("[simulation]\ndt = 1\ngravity = [0, -10, 0]\n" + BOX + "young = 200\n");
    EXPECT_EQ(spec.simulation.dt, 1.0);
    EXPECT_EQ(spec.simulation.gravity, coro::Vec3(0.0, -10.0, 0.0));
    EXPECT_EQ(spec.bodies[0].material.young, 200.0);
}

TEST(ReadCase, ToleranceZeroIsAcceptedAndMeansRunTheCap)
{
    const coro::CaseSpec spec = parse("[solver]\ntolerance = 0\nmax_iterations = 10\n" + BOX);
    EXPECT_EQ(spec.solver.tolerance, 0.0);
    EXPECT_EQ(spec.solver.max_iterations, 10);
}

TEST(ReadCase, InlineArrayOfTablesEqualsHeaderForm)
{
    const coro::CaseSpec spec = parse(
        "body = [{ name = \"a\", shape = \"box\", fixed = [{ max = [0, 1, 1] }] }]\n"
        "obstacle = [{ type = \"plane\", normal = [0, 0, 3] }]\n");
    ASSERT_EQ(spec.bodies.size(), 1u);
    EXPECT_EQ(spec.bodies[0].name, "a");
    ASSERT_EQ(spec.bodies[0].fixed.size(), 1u);
    EXPECT_EQ(spec.bodies[0].fixed[0].max, coro::Vec3(0.0, 1.0, 1.0));
    ASSERT_EQ(spec.obstacles.size(), 1u);
    EXPECT_EQ(spec.obstacles[0].normal, coro::Vec3(0.0, 0.0, 1.0));
}

// ---------------------------------------------------------------------------------------------
// Paths

TEST(ReadCase, RelativePathsResolveAgainstTheCaseFolder)
{
    const fs::path dir = coro::test::scratch_dir("case_relative");
    const std::string text =
        "[[body]]\nmesh = \"../meshes/./a.msh\"\nsurface = \"b.obj\"\n"
        "[[obstacle]]\ntype = \"mesh\"\nmesh = \"rigid/ground.stl\"\n";
    const coro::CaseSpec spec = coro::parse_case(text, dir / "cases" / "c.toml");
    EXPECT_EQ(spec.bodies[0].mesh, dir / "meshes" / "a.msh");
    EXPECT_EQ(spec.bodies[0].surface, dir / "cases" / "b.obj");
    EXPECT_EQ(spec.obstacles[0].mesh, dir / "cases" / "rigid" / "ground.stl");
    fs::remove_all(dir);
}

TEST(ReadCase, RelativeCaseFileResolvesAgainstTheWorkingDirectory)
{
    const coro::CaseSpec spec =
        coro::parse_case("[[body]]\nmesh = \"a.msh\"\n", fs::path("some") / "folder" / "c.toml");
    EXPECT_TRUE(spec.bodies[0].mesh.is_absolute());
    EXPECT_EQ(spec.bodies[0].mesh, fs::current_path() / "some" / "folder" / "a.msh");
}

TEST(ReadCase, AbsolutePathsAreKeptAndNormalised)
{
    const fs::path dir = coro::test::scratch_dir("case_absolute");
    const fs::path given = dir / "x" / ".." / "meshes" / "a.msh";
    const coro::CaseSpec spec =
        coro::parse_case("[[body]]\nmesh = \"" + given.string() + "\"\n", dir / "cases" / "c.toml");
    EXPECT_EQ(spec.bodies[0].mesh, dir / "meshes" / "a.msh");
    fs::remove_all(dir);
}

TEST(ReadCase, OutputDirIsRelativeToTheWorkingDirectory)
{
    const fs::path dir = coro::test::scratch_dir("case_output");
    const coro::CaseSpec spec = coro::parse_case(
        "[simulation]\noutput_dir = \"results/run1/\"\n" + BOX, dir / "cases" / "c.toml");
    EXPECT_EQ(spec.simulation.output_dir, fs::path("results") / "run1");

    const coro::CaseSpec named =
        coro::parse_case("[simulation]\nname = \"drop\"\n" + BOX, dir / "cases" / "c.toml");
    EXPECT_EQ(named.simulation.output_dir, fs::path("out") / "drop");
    fs::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// The file itself

TEST(ReadCase, MissingFileIsAnError)
{
    const fs::path dir = coro::test::scratch_dir("case_missing");
    const fs::path file = dir / "nope.toml";
    EXPECT_THAT([&] { coro::read_case(file); },
                ThrowsMessage<coro::InputError>(
                    AllOf(StartsWith(file.string() + ":"), HasSubstr("no such file"))));
    fs::remove_all(dir);
}

TEST(ReadCase, DeviceIsAnErrorNotReadWithoutEnd)
{
    const fs::path dir = coro::test::scratch_dir("case_device");
    const fs::path file = dir / "zero.toml";
    fs::create_symlink("/dev/zero", file);
    EXPECT_THAT([&] { coro::read_case(file); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith(file.string() + ":"),
                                                      HasSubstr("it is not a regular file, expected a .toml file"))));
    fs::remove_all(dir);
}

TEST(ReadCase, DirectoryIsAnError)
{
    const fs::path dir = coro::test::scratch_dir("case_directory");
    EXPECT_THAT([&] { coro::read_case(dir); },
                ThrowsMessage<coro::InputError>(
                    AllOf(StartsWith(dir.string() + ":"), HasSubstr("is a directory"))));
    fs::remove_all(dir);
}

TEST(ReadCase, SyntaxErrorGivesLineAndColumn)
{
    EXPECT_THAT([] { parse("[simulation]\ndt = 0.1\nsteps = = 3\n" + BOX); },
                ThrowsMessage<coro::InputError>(
                    AllOf(StartsWith("case.toml:3:9:"), HasSubstr("invalid TOML"))));
    EXPECT_THAT([] { parse(BOX + "young = 1\nyoung = 2\n"); },
                ThrowsMessage<coro::InputError>(
                    AllOf(StartsWith("case.toml:4:"), HasSubstr("young"))));
}

TEST(ReadCase, NoBodyIsAnError)
{
    EXPECT_THAT([] { parse("[simulation]\ndt = 0.1\n"); },
                ThrowsMessage<coro::InputError>(
                    AllOf(StartsWith("case.toml:1:1: body:"), HasSubstr("at least one [[body]]"))));
    EXPECT_THAT([] { parse("\nbody = []\n"); },
                ThrowsMessage<coro::InputError>(StartsWith("case.toml:2:8: body:")));
}

// ---------------------------------------------------------------------------------------------
// Unknown keys and tables

TEST(ReadCase, UnknownKeySuggestsTheClosestKnownKey)
{
    EXPECT_THAT([] { parse(BOX + "yuong = 1e5\n"); },
                ThrowsMessage<coro::InputError>(
                    AllOf(StartsWith("case.toml:3:1: body[0].yuong: unknown key in [[body]]"),
                          HasSubstr("did you mean 'young'?"))));
    EXPECT_THAT([] { parse("[simulation]\ndtt = 0.1\n" + BOX); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:2:1: simulation.dtt:"),
                                                      HasSubstr("did you mean 'dt'?"))));
}

TEST(ReadCase, UnknownKeyWithoutNeighbourListsTheKnownKeys)
{
    EXPECT_THAT([] { parse("[contact]\nfoo = 1\n" + BOX); },
                ThrowsMessage<coro::InputError>(
                    AllOf(StartsWith("case.toml:2:1: contact.foo: unknown key in [contact]"),
                          HasSubstr("known keys: enabled, mode, stiffness"),
                          Not(HasSubstr("did you mean")))));
}

TEST(ReadCase, UnknownTableSuggestsTheClosestTable)
{
    EXPECT_THAT([] { parse("[simulaton]\ndt = 0.1\n" + BOX); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:1:2: simulaton: unknown table"),
                                                      HasSubstr("did you mean 'simulation'?"))));
    EXPECT_THAT([] { parse(BOX + "[[bodies]]\n"); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:3:3: bodies: unknown table"),
                                                      HasSubstr("did you mean 'body'?"))));
}

TEST(ReadCase, KeyInTheWrongTableNamesItsTable)
{
    EXPECT_THAT([] { parse("[solver]\ngravity = [0, 0, 0]\n" + BOX); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:2:1: solver.gravity:"),
                                                      HasSubstr("'gravity' is a key of [simulation]"))));
    EXPECT_THAT([] { parse("dt = 0.1\n" + BOX); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:1:1: dt: unknown top-level key"),
                                                      HasSubstr("[simulation]"))));
}

TEST(ReadCase, BodyKeyBelowFixedHeaderExplainsTheNesting)
{
    EXPECT_THAT([] { parse(BOX + "[[body.fixed]]\nmax = [0, 1, 1]\nyoung = 1e5\n"); },
                ThrowsMessage<coro::InputError>(
                    AllOf(StartsWith("case.toml:5:1: body[0].fixed[0].young: unknown key in [[body.fixed]]"),
                          HasSubstr("move it above"))));
}

TEST(ReadCase, UnknownKeyInSecondBodyNamesThatBody)
{
    EXPECT_THAT([] { parse(BOX + BOX + "poison = 0.3\n"); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:5:1: body[1].poison:"),
                                                      HasSubstr("did you mean 'poisson'?"))));
}

// ---------------------------------------------------------------------------------------------
// Types

TEST(ReadCase, StringWhereNumberExpectedIsAnError)
{
    EXPECT_THAT([] { parse("[simulation]\ndt = \"fast\"\n" + BOX); },
                ThrowsMessage<coro::InputError>(StartsWith(
                    "case.toml:2:6: simulation.dt: expected a number > 0, found the string \"fast\"")));
}

TEST(ReadCase, FloatWhereIntegerExpectedIsAnError)
{
    EXPECT_THAT([] { parse("[simulation]\nsteps = 10.0\n" + BOX); },
                ThrowsMessage<coro::InputError>(StartsWith("case.toml:2:9: simulation.steps: expected an "
                                                           "integer >= 1, found the floating-point number 10.0")));
    EXPECT_THAT([] { parse(BOX + "cells = [2, 2.5, 2]\n"); },
                ThrowsMessage<coro::InputError>(StartsWith("case.toml:3:13: body[0].cells[1]: expected an integer")));
}

TEST(ReadCase, IntegerBeyondIndexRangeIsAnError)
{
    EXPECT_THAT([] { parse("[simulation]\nsteps = 3000000000\n" + BOX); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:2:9: simulation.steps:"),
                                                      HasSubstr("2147483647"))));
}

TEST(ReadCase, WrongTypeForBooleanStringAndTable)
{
    EXPECT_THAT([] { parse("[contact]\nenabled = 1\n" + BOX); },
                ThrowsMessage<coro::InputError>(StartsWith(
                    "case.toml:2:11: contact.enabled: expected a boolean (true or false), found the integer 1")));
    EXPECT_THAT([] { parse(BOX + "name = 3\n"); },
                ThrowsMessage<coro::InputError>(
                    StartsWith("case.toml:3:8: body[0].name: expected a string, found the integer 3")));
    EXPECT_THAT([] { parse("simulation = 3\n" + BOX); },
                ThrowsMessage<coro::InputError>(StartsWith("case.toml:1:14: simulation: expected a table")));
    EXPECT_THAT([] { parse("[body]\nshape = \"box\"\n"); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:1:1: body: expected an array of tables"),
                                                      HasSubstr("[[body]]"))));
    EXPECT_THAT([] { parse(BOX + "[body.fixed]\n"); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:3:1: body[0].fixed:"),
                                                      HasSubstr("[[body.fixed]]"))));
}

TEST(ReadCase, VectorOfWrongLengthIsAnError)
{
    EXPECT_THAT([] { parse("[simulation]\ngravity = [0, -9.81]\n" + BOX); },
                ThrowsMessage<coro::InputError>(StartsWith("case.toml:2:11: simulation.gravity: expected an "
                                                           "array of 3 numbers, found an array of 2 elements")));
    EXPECT_THAT([] { parse(BOX + "translate = 1.0\n"); },
                ThrowsMessage<coro::InputError>(StartsWith(
                    "case.toml:3:13: body[0].translate: expected an array of 3 numbers, found the floating")));
}

TEST(ReadCase, VectorElementOfWrongTypeNamesTheElement)
{
    EXPECT_THAT([] { parse("[simulation]\ngravity = [0, \"down\", 0]\n" + BOX); },
                ThrowsMessage<coro::InputError>(StartsWith(
                    "case.toml:2:15: simulation.gravity[1]: expected a number, found the string \"down\"")));
}

TEST(ReadCase, WrongEnumValueListsTheAllowedOnes)
{
    EXPECT_THAT([] { parse("[simulation]\nanalysis = \"dynamc\"\n" + BOX); },
                ThrowsMessage<coro::InputError>(
                    AllOf(StartsWith("case.toml:2:12: simulation.analysis: expected one of \"dynamic\" or "
                                     "\"static\", found the string \"dynamc\""),
                          HasSubstr("did you mean \"dynamic\"?"))));
    EXPECT_THAT([] { parse("[solver]\npreconditioner = \"ilu\"\n" + BOX); },
                ThrowsMessage<coro::InputError>(StartsWith(
                    "case.toml:2:18: solver.preconditioner: expected one of \"jacobi\", \"block_jacobi\" or \"amg\"")));
    EXPECT_THAT([] { parse("[solver]\nmatrix_precision = \"half\"\n" + BOX); },
                ThrowsMessage<coro::InputError>(StartsWith(
                    "case.toml:2:20: solver.matrix_precision: expected one of \"double\" or \"single\", "
                    "found the string \"half\"")));
    EXPECT_THAT([] { parse("[contact]\nmode = \"fast\"\n" + BOX); },
                ThrowsMessage<coro::InputError>(
                    StartsWith("case.toml:2:8: contact.mode: expected one of \"exact\" or \"paper\"")));
    EXPECT_THAT([] { parse("[contact]\ncross_check = true\n" + BOX); },
                ThrowsMessage<coro::InputError>(StartsWith(
                    "case.toml:2:15: contact.cross_check: expected one of \"none\" or \"embree\", found the boolean")));
    EXPECT_THAT([] { parse("[[body]]\nshape = \"cube\"\n"); },
                ThrowsMessage<coro::InputError>(
                    StartsWith("case.toml:2:9: body[0].shape: expected one of \"box\" or \"sphere\"")));
    EXPECT_THAT([] { parse(BOX + "[[obstacle]]\ntype = \"wall\"\n"); },
                ThrowsMessage<coro::InputError>(
                    StartsWith("case.toml:4:8: obstacle[0].type: expected one of \"plane\" or \"mesh\"")));
}

// ---------------------------------------------------------------------------------------------
// Values out of range: one row per rule

namespace {

struct BadValue {
    std::string name;   ///< test name
    std::string text;   ///< the case
    std::string start;  ///< the message starts with this: position and key
    std::string detail; ///< and contains this
};

void PrintTo(const BadValue& bad, std::ostream* os) { *os << bad.name; }

class ReadCaseRejects : public ::testing::TestWithParam<BadValue> {};

TEST_P(ReadCaseRejects, ValueOutOfRange)
{
    const BadValue& bad = GetParam();
    EXPECT_THAT([&] { parse(bad.text); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith(bad.start), HasSubstr(bad.detail))));
}

std::string sim(const std::string& line) { return "[simulation]\n" + line + "\n" + BOX; }
std::string solver(const std::string& line) { return "[solver]\n" + line + "\n" + BOX; }
std::string contact(const std::string& line) { return "[contact]\n" + line + "\n" + BOX; }
std::string body(const std::string& line) { return BOX + line + "\n"; }
std::string sphere(const std::string& line) { return "[[body]]\nshape = \"sphere\"\n" + line + "\n"; }

} // namespace

INSTANTIATE_TEST_SUITE_P(
    ReadCase, ReadCaseRejects,
    ::testing::Values(
        BadValue{"DtZero", sim("dt = 0.0"), "case.toml:2:6: simulation.dt:", "expected a number > 0, found the floating-point number 0.0"},
        BadValue{"DtNegative", sim("dt = -1e-3"), "case.toml:2:6: simulation.dt:", "found the floating-point number -0.001"},
        BadValue{"DtNan", sim("dt = nan"), "case.toml:2:6: simulation.dt:", "expected a finite number > 0, found the floating-point number nan"},
        BadValue{"DtInf", sim("dt = inf"), "case.toml:2:6: simulation.dt:", "finite"},
        BadValue{"StepsZero", sim("steps = 0"), "case.toml:2:9: simulation.steps:", "expected an integer >= 1, found the integer 0"},
        BadValue{"LoadStepsZero", sim("load_steps = 0"), "case.toml:2:14: simulation.load_steps:", "found the integer 0"},
        BadValue{"OutputEveryZero", sim("output_every = 0"), "case.toml:2:16: simulation.output_every:", "found the integer 0"},
        BadValue{"GravityNan", sim("gravity = [0, nan, 0]"), "case.toml:2:15: simulation.gravity[1]:", "finite"},
        BadValue{"NameWithSpace", sim("name = \"two spheres\""), "case.toml:2:8: simulation.name:", "letters, digits"},
        BadValue{"NameEmpty", sim("name = \"\""), "case.toml:2:8: simulation.name:", "1 to 128"},
        BadValue{"NameTooLong", sim("name = \"" + std::string(129, 'n') + "\""), "case.toml:2:8: simulation.name:", "(129 characters)"},
        BadValue{"OutputDirEmpty", sim("output_dir = \"\""), "case.toml:2:14: simulation.output_dir:", "empty"},
        BadValue{"MaxIterationsZero", solver("max_iterations = 0"), "case.toml:2:18: solver.max_iterations:", "found the integer 0"},
        BadValue{"ToleranceNegative", solver("tolerance = -1e-6"), "case.toml:2:13: solver.tolerance:", "expected a number in [0, 1), found the floating-point number -1e-06"},
        BadValue{"ToleranceOne", solver("tolerance = 1"), "case.toml:2:13: solver.tolerance:", "expected a number in [0, 1), found the integer 1"},
        BadValue{"StaticToleranceNegative", solver("static_tolerance = -1e-8"), "case.toml:2:20: solver.static_tolerance:", "in (0, 1)"},
        BadValue{"StaticToleranceAboveOne", solver("static_tolerance = 2.5"), "case.toml:2:20: solver.static_tolerance:", "in (0, 1)"},
        BadValue{"StaticMaxIterationsZero", solver("static_max_iterations = 0"), "case.toml:2:25: solver.static_max_iterations:", ">= 1"},
        BadValue{"PartsPerThreadZero", solver("parts_per_thread = 0"), "case.toml:2:20: solver.parts_per_thread:", "found the integer 0"},
        BadValue{"PartsPerThreadHuge", solver("parts_per_thread = 100001"), "case.toml:2:20: solver.parts_per_thread:", "expected an integer >= 1 and <= 100000, found the integer 100001"},
        BadValue{"StiffnessZero", contact("stiffness = 0.0"), "case.toml:2:13: contact.stiffness:", "> 0"},
        BadValue{"DampingNegative", contact("damping = -0.1"), "case.toml:2:11: contact.damping:", "expected a number >= 0, found the floating-point number -0.1"},
        BadValue{"FrictionNegative", contact("friction = -1"), "case.toml:2:12: contact.friction:", "in [0, 10]"},
        BadValue{"FrictionHuge", contact("friction = 1e12"), "case.toml:2:12: contact.friction:", "expected a number in [0, 10], found the floating-point number 1e+12"},
        BadValue{"YoungZero", body("young = 0"), "case.toml:3:9: body[0].young:", "expected a number > 0, found the integer 0"},
        BadValue{"YoungInf", body("young = +inf"), "case.toml:3:9: body[0].young:", "finite"},
        BadValue{"PoissonHalf", body("poisson = 0.5"), "case.toml:3:11: body[0].poisson:", "expected a number in (-1, 0.5), found the floating-point number 0.5"},
        BadValue{"PoissonMinusOne", body("poisson = -1"), "case.toml:3:11: body[0].poisson:", "in (-1, 0.5)"},
        BadValue{"DensityNegative", body("density = -1000"), "case.toml:3:11: body[0].density:", "> 0"},
        BadValue{"RayleighMassNegative", body("rayleigh_mass = -0.1"), "case.toml:3:17: body[0].rayleigh_mass:", ">= 0"},
        BadValue{"RayleighStiffnessNegative", body("rayleigh_stiffness = -1e-3"), "case.toml:3:22: body[0].rayleigh_stiffness:", ">= 0"},
        BadValue{"ScaleZero", body("scale = 0"), "case.toml:3:9: body[0].scale:", "> 0"},
        BadValue{"RotateDegreesHuge", body("rotate_degrees = 1e300"), "case.toml:3:18: body[0].rotate_degrees:", "expected a number in [-3600, 3600], found the floating-point number 1e+300"},
        BadValue{"RotateAxisZero", body("rotate_axis = [0, 0, 0]\nrotate_degrees = 30"), "case.toml:3:15: body[0].rotate_axis:", "nonzero axis"},
        BadValue{"VelocityNan", body("velocity = [nan, 0, 0]"), "case.toml:3:13: body[0].velocity[0]:", "finite"},
        BadValue{"CellsZero", body("cells = [1, 0, 1]"), "case.toml:3:13: body[0].cells[1]:", "found the integer 0"},
        BadValue{"CellsBeyondAnIndex", body("cells = [2000, 2000, 2000]"), "case.toml:3:9: body[0].cells:", "[2000, 2000, 2000] makes 4.8e+10 tets and 8012006001 nodes, expected at most 2147483647 of each"},
        BadValue{"CellsBeyondAnIndexByOne", body("cells = [2147483647, 1, 1]"), "case.toml:3:9: body[0].cells:", "expected at most 2147483647"},
        BadValue{"ResolutionBeyondAnIndex", sphere("resolution = 711"), "case.toml:3:14: body[0].resolution:", "711 makes 2156552586 tets"},
        BadValue{"TranslateHuge", body("translate = [0, 1e101, 0]"), "case.toml:3:13: body[0].translate:", "expected coordinates of magnitude at most 1e+100, found [0, 1e+101, 0]"},
        BadValue{"BoxMaxHuge", body("max = [1e200, 1, 1]"), "case.toml:3:7: body[0].max:", "magnitude at most 1e+100"},
        BadValue{"CenterHuge", sphere("center = [-1e200, 0, 0]"), "case.toml:3:10: body[0].center:", "magnitude at most 1e+100"},
        BadValue{"RadiusHuge", sphere("radius = 1e101"), "case.toml:3:10: body[0].radius:", "expected a number in (0, 1e+100]"},
        BadValue{"PlanePointHuge", BOX + "[[obstacle]]\npoint = [0, 0, 1e300]\n", "case.toml:4:9: obstacle[0].point:", "magnitude at most 1e+100"},
        BadValue{"CellsTwoEntries", body("cells = [1, 1]"), "case.toml:3:9: body[0].cells:", "expected an array of 3 integers"},
        BadValue{"BoxMinNotBelowMax", body("min = [0, 1, 0]\nmax = [1, 1, 1]"), "case.toml:4:7: body[0].max:", "expected max > min in every component, found max[1] = 1 and min[1] = 1"},
        BadValue{"BoxMinAboveDefaultMax", body("min = [2, 0, 0]"), "case.toml:3:7: body[0].min:", "max[0] = 1 and min[0] = 2"},
        BadValue{"RadiusZero", sphere("radius = 0"), "case.toml:3:10: body[0].radius:", "in (0, 1e+100], found the integer 0"},
        BadValue{"ResolutionOne", sphere("resolution = 1"), "case.toml:3:14: body[0].resolution:", "expected an integer >= 2, found the integer 1"},
        BadValue{"FixedMinAboveMax", body("[[body.fixed]]\nmin = [0, 0, 0]\nmax = [1, -1, 1]"), "case.toml:5:7: body[0].fixed[0].max:", "expected max >= min"},
        BadValue{"LoadForceNan", body("[[body.load]]\nforce = [0, 0, nan]"), "case.toml:4:16: body[0].load[0].force[2]:", "finite"},
        BadValue{"PlaneNormalZero", BOX + "[[obstacle]]\nnormal = [0, 0, 0]\n", "case.toml:4:10: obstacle[0].normal:", "expected a nonzero vector"},
        BadValue{"BodyNameInvalid", body("name = \"a,b\""), "case.toml:3:8: body[0].name:", "letters, digits"},
        BadValue{"BodyNameDotDot", body("name = \"..\""), "case.toml:3:8: body[0].name:", "found the string \"..\" (\".\" and \"..\" are not allowed: they name the current and the parent folder)"},
        BadValue{"BodyNameTooLong", body("name = \"" + std::string(200, 'b') + "\""), "case.toml:3:8: body[0].name:", "1 to 128 letters, digits, '_', '.' and '-', found the string \"bbb"},
        BadValue{"MeshEmpty", "[[body]]\nmesh = \"\"\n", "case.toml:2:8: body[0].mesh:", "empty"}),
    [](const ::testing::TestParamInfo<BadValue>& param_info) { return param_info.param.name; });

// ---------------------------------------------------------------------------------------------
// Geometry, names, obstacles

TEST(ReadCase, MeshAndShapeTogetherIsAnError)
{
    EXPECT_THAT([] { parse("[[body]]\nmesh = \"a.msh\"\nshape = \"box\"\n"); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:3:1: body[0].shape:"),
                                                      HasSubstr("either 'mesh' or 'shape'"),
                                                      HasSubstr("case.toml:2:1"))));
}

TEST(ReadCase, MissingGeometryPointsAtTheBodyHeader)
{
    EXPECT_THAT([] { parse(BOX + "\n[[body]]\nname = \"b\"\n"); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:4:1: body[1]:"),
                                                      HasSubstr("found neither 'mesh' nor 'shape'"))));
}

TEST(ReadCase, KeysOfAnotherShapeAreErrors)
{
    EXPECT_THAT([] { parse(BOX + "radius = 2.0\n"); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:3:1: body[0].radius:"),
                                                      HasSubstr("shape = \"sphere\""))));
    EXPECT_THAT([] { parse("[[body]]\nshape = \"sphere\"\ncells = [1, 1, 1]\n"); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:3:1: body[0].cells:"),
                                                      HasSubstr("shape = \"box\""))));
    EXPECT_THAT([] { parse("[[body]]\nmesh = \"a.msh\"\nmin = [0, 0, 0]\n"); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:3:1: body[0].min:"),
                                                      HasSubstr("reads a mesh"))));
}

TEST(ReadCase, DuplicateBodyNamesNameBothLines)
{
    EXPECT_THAT([] { parse("[[body]]\nname = \"a\"\nshape = \"box\"\n[[body]]\nname = \"a\"\nshape = \"box\"\n"); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:5:8: body[1].name:"),
                                                      HasSubstr("\"a\" again"), HasSubstr("case.toml:2:8"))));
    // A default name counts too: the second body is "body1" by default.
    EXPECT_THAT([] { parse("[[body]]\nname = \"body1\"\nshape = \"box\"\n" + BOX); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:4:1: body[1].name:"),
                                                      HasSubstr("default name"), HasSubstr("case.toml:2:8"))));
}

TEST(ReadCase, LargestGeneratedMeshesThatAnIndexNumbersAreAccepted)
{
    // 6 · 710³ = 2147466000 tets, 17483 below the limit; 711 is refused (above).
    EXPECT_EQ(parse("[[body]]\nshape = \"sphere\"\nresolution = 710\n").bodies[0].resolution, 710);
    EXPECT_EQ(parse(BOX + "cells = [357913941, 1, 1]\n").bodies[0].cells[0], 357913941); // 6 · that ≤ 2^31 − 1
    EXPECT_THAT([] { parse(BOX + "cells = [357913942, 1, 1]\n"); },
                ThrowsMessage<coro::InputError>(HasSubstr("makes 2147483652 tets")));
}

TEST(ReadCase, ABodyMayNotTakeTheNameOfAnotherOutputBlock)
{
    const std::string obstacle = "[[obstacle]]\ntype = \"mesh\"\nmesh = \"ramp.obj\"\n";
    EXPECT_THAT([&] { parse("[[body]]\nname = \"obstacle0\"\nshape = \"box\"\n" + obstacle); },
                ThrowsMessage<coro::InputError>(
                    AllOf(StartsWith("case.toml:2:8: body[0].name: expected a name that no other block of the output "
                                     "has, found \"obstacle0\""),
                          HasSubstr("the block name of mesh obstacle 0 ([[obstacle]] at case.toml:4)"))));
    // obstacle1 is free with one mesh obstacle; a plane is no mesh obstacle, but has its block.
    EXPECT_EQ(parse("[[body]]\nname = \"obstacle1\"\nshape = \"box\"\n[[obstacle]]\n" + obstacle).bodies[0].name,
              "obstacle1");
    EXPECT_THAT([&] { parse("[[body]]\nname = \"plane0\"\nshape = \"box\"\n[[obstacle]]\n" + obstacle); },
                ThrowsMessage<coro::InputError>(HasSubstr("the block name of plane obstacle 0 ([[obstacle]] at case.toml:4)")));
    EXPECT_THAT([] { parse("[[body]]\nname = \"b_surface\"\nshape = \"box\"\n"
                           "[[body]]\nname = \"b\"\nshape = \"box\"\nsurface = \"fine.obj\"\n"); },
                ThrowsMessage<coro::InputError>(
                    AllOf(StartsWith("case.toml:2:8: body[0].name:"),
                          HasSubstr("the block name of the embedded surface of body 'b' (case.toml:7:1)"))));
    // Without a surface, "b_surface" names no other block.
    EXPECT_EQ(parse("[[body]]\nname = \"b_surface\"\nshape = \"box\"\n[[body]]\nname = \"b\"\nshape = \"box\"\n")
                  .bodies.size(),
              2u);
}

TEST(ReadCase, CaseFileStemMustBeAValidNameUnlessNamed)
{
    EXPECT_THAT([] { coro::parse_case(BOX, "my case.toml"); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("my case.toml:1:1: simulation.name:"),
                                                      HasSubstr("\"my case\""))));
    const coro::CaseSpec spec = coro::parse_case("[simulation]\nname = \"my_case\"\n" + BOX, "my case.toml");
    EXPECT_EQ(spec.simulation.name, "my_case");
}

TEST(ReadCase, MeshObstacleNeedsItsFile)
{
    EXPECT_THAT([] { parse(BOX + "[[obstacle]]\ntype = \"mesh\"\n"); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:3:1: obstacle[0].mesh:"),
                                                      HasSubstr("found no 'mesh'"))));
    EXPECT_THAT([] { parse(BOX + "[[obstacle]]\ntype = \"mesh\"\nmesh = \"g.obj\"\nnormal = [0, 1, 0]\n"); },
                ThrowsMessage<coro::InputError>(StartsWith("case.toml:6:1: obstacle[0].normal:")));
    EXPECT_THAT([] { parse(BOX + "[[obstacle]]\nmesh = \"g.obj\"\n"); },
                ThrowsMessage<coro::InputError>(AllOf(StartsWith("case.toml:4:1: obstacle[0].mesh:"),
                                                      HasSubstr("is a plane"))));
}

TEST(ReadCase, ErrorInSecondObstacleNamesIt)
{
    EXPECT_THAT([] { parse(BOX + "[[obstacle]]\n[[obstacle]]\npoint = [0, 0]\n"); },
                ThrowsMessage<coro::InputError>(StartsWith("case.toml:5:9: obstacle[1].point:")));
}

// ---------------------------------------------------------------------------------------------
// The documentation's examples stay valid

namespace {

/// The `n`th (0-based) ```toml block of docs/case_file.md after the heading `heading`.
std::string doc_example(const std::string& heading, int n)
{
    const fs::path doc = fs::path(CORO_TEST_DATA_DIR) / ".." / ".." / "docs" / "case_file.md";
    std::ifstream in(doc);
    EXPECT_TRUE(in.is_open()) << doc;
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::size_t at = text.find(heading);
    EXPECT_NE(at, std::string::npos) << heading;
    for (int i = 0; i <= n && at != std::string::npos; ++i)
        at = text.find("```toml\n", at + 1);
    if (at == std::string::npos)
        return {};
    at += 8;
    return text.substr(at, text.find("```", at) - at);
}

} // namespace

TEST(ReadCase, DocumentedExamplesParse)
{
    const fs::path dir = coro::test::scratch_dir("case_doc");
    const coro::CaseSpec spec =
        coro::parse_case(doc_example("## A complete example", 0), dir / "cases" / "drop" / "drop.toml");
    EXPECT_EQ(spec.simulation.name, "drop");
    EXPECT_EQ(spec.simulation.output_dir, fs::path("out") / "drop");
    ASSERT_EQ(spec.bodies.size(), 3u);
    EXPECT_EQ(spec.bodies[0].mesh, dir / "cases" / "drop" / "meshes" / "sphere.msh");
    EXPECT_EQ(spec.bodies[0].surface, dir / "cases" / "common" / "sphere_fine.obj");
    EXPECT_EQ(spec.bodies[1].shape, coro::BodyShape::BOX);
    EXPECT_EQ(spec.bodies[1].fixed.size(), 1u);
    EXPECT_EQ(spec.bodies[1].loads.size(), 1u);
    EXPECT_EQ(spec.bodies[2].shape, coro::BodyShape::SPHERE);
    ASSERT_EQ(spec.obstacles.size(), 2u);
    EXPECT_EQ(spec.obstacles[1].mesh, dir / "cases" / "drop" / "bowl.obj");

    const coro::CaseSpec smallest =
        coro::parse_case(doc_example("## A complete example", 1), dir / "smallest.toml");
    ASSERT_EQ(smallest.bodies.size(), 1u);
    EXPECT_EQ(smallest.bodies[0].shape, coro::BodyShape::BOX);
    fs::remove_all(dir);
}
