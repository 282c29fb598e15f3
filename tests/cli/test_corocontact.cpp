#include "cli_run.hpp"
#include "mesh_fixtures.hpp"

#include <corocontact/config.hpp>
#include <corocontact/core/primitives.hpp>
#include <corocontact/core/surface_mesh.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkCompositeDataSet.h>
#include <vtkDataSet.h>
#include <vtkInformation.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLMultiBlockDataReader.h>

#include <sched.h>
#include <sys/wait.h>

#include <algorithm>
#include <fstream>
#include <set>
#include <regex>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;
using coro::test::listed_frames;
using coro::test::Outcome;
using coro::test::run;
using coro::test::slurp;

namespace {

const char* SMALL_CASE = R"([simulation]
dt = 0.01
steps = 4
output_every = 2
gravity = [0.0, -9.81, 0.0]

[solver]
max_iterations = 50

[[body]]
name = "block"
shape = "box"
min = [0.0, 0.0, 0.0]
max = [2.0, 1.0, 1.0]
cells = [4, 2, 2]
young = 1e5

[[body.fixed]]
min = [-1.0, -1.0, -1.0]
max = [0.0, 2.0, 2.0]
)";

/// The first CPU this process may run on (for `taskset -c`).
int first_allowed_cpu()
{
    cpu_set_t set;
    CPU_ZERO(&set);
    if (sched_getaffinity(0, sizeof(set), &set) == 0)
        for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
            if (CPU_ISSET(cpu, &set))
                return cpu;
    return 0;
}

} // namespace

TEST(CorocontactRun, WritesSeriesThatVtkLoadsAndASummary)
{
    const fs::path dir = coro::test::scratch_dir("cli_run");
    const fs::path case_file = coro::test::write_text(dir / "small.toml", SMALL_CASE);
    const Outcome outcome = run("run " + case_file.string() + " --out " + (dir / "out").string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.out, HasSubstr("small: 4 steps"));
    EXPECT_THAT(outcome.out, HasSubstr("phases [s]: rotation"));

    const std::vector<std::string> frames = listed_frames(dir / "out" / "small.pvd");
    ASSERT_EQ(frames.size(), 3u); // steps 0, 2, 4
    for (const std::string& frame : frames) {
        vtkNew<vtkXMLMultiBlockDataReader> reader;
        reader->SetFileName((dir / "out" / frame).string().c_str());
        reader->Update();
        auto* blocks = vtkMultiBlockDataSet::SafeDownCast(reader->GetOutput());
        ASSERT_NE(blocks, nullptr) << frame;
        ASSERT_EQ(blocks->GetNumberOfBlocks(), 1u);
        EXPECT_STREQ(blocks->GetMetaData(0u)->Get(vtkCompositeDataSet::NAME()), "block");
        auto* grid = vtkUnstructuredGrid::SafeDownCast(blocks->GetBlock(0));
        ASSERT_NE(grid, nullptr) << frame;
        EXPECT_EQ(grid->GetNumberOfPoints(), 5 * 3 * 3);
        EXPECT_EQ(grid->GetNumberOfCells(), 6 * 4 * 2 * 2);
        EXPECT_NE(grid->GetPointData()->GetArray("displacement"), nullptr);
        EXPECT_NE(grid->GetPointData()->GetArray("velocity"), nullptr);
        EXPECT_NE(grid->GetCellData()->GetArray("von_mises"), nullptr);
    }
    const std::string summary = slurp(dir / "out" / "small.summary.json");
    for (const char* key : {"\"steps\": 4", "\"wall_s\"", "\"steps_per_s\"", "\"threads\"", "\"bodies\": 1",
                            "\"tets\": 96", "\"rotation\"", "\"assembly\"", "\"solve\"", "\"contact\"",
                            "\"output\"", "\"cg_iterations_mean\"", "\"cg_residual_mean\"", "\"peak_rss_mb\""})
        EXPECT_THAT(summary, HasSubstr(key));
}

TEST(CorocontactRun, BadCaseExitsWithTwoNamingLineAndWritesNothing)
{
    const fs::path dir = coro::test::scratch_dir("cli_bad");
    std::string text = SMALL_CASE;
    text.replace(text.find("young"), 5, "yuong");
    const fs::path case_file = coro::test::write_text(dir / "bad.toml", text);
    const Outcome outcome = run("run " + case_file.string() + " --out " + (dir / "out").string(), dir);
    EXPECT_EQ(outcome.exit_code, 2);
    EXPECT_THAT(outcome.err, HasSubstr("bad.toml:16:"));
    EXPECT_THAT(outcome.err, HasSubstr("yuong"));
    EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(CorocontactRun, MissingCaseFileExitsWithTwo)
{
    const fs::path dir = coro::test::scratch_dir("cli_missing");
    const Outcome outcome = run("run " + (dir / "nope.toml").string(), dir);
    EXPECT_EQ(outcome.exit_code, 2);
    EXPECT_THAT(outcome.err, HasSubstr("nope.toml"));
}

TEST(CorocontactRun, DivergenceExitsWithThreeAndKeepsReadableFrames)
{
    const fs::path dir = coro::test::scratch_dir("cli_diverge");
    // Thrown at its clamp at 1e6 m/s: step 1 turns its tets inside out. (Values whose products
    // overflow double, such as gravity = 1e300 with dt = 1e20, are refused at load instead.)
    std::string text = SMALL_CASE;
    text.replace(text.find("young = 1e5"), 11, "young = 1e5\nvelocity = [-1e6, 0.0, 0.0]");
    const fs::path case_file = coro::test::write_text(dir / "diverge.toml", text);
    const Outcome outcome = run("run " + case_file.string() + " --out " + (dir / "out").string(), dir);
    EXPECT_EQ(outcome.exit_code, 3);
    EXPECT_THAT(outcome.err, HasSubstr("step 1"));
    EXPECT_THAT(outcome.err, HasSubstr("body 'block': "));
    const std::vector<std::string> frames = listed_frames(dir / "out" / "diverge.pvd");
    ASSERT_EQ(frames.size(), 1u);
    vtkNew<vtkXMLMultiBlockDataReader> reader;
    reader->SetFileName((dir / "out" / frames[0]).string().c_str());
    reader->Update();
    EXPECT_EQ(vtkMultiBlockDataSet::SafeDownCast(reader->GetOutput())->GetNumberOfBlocks(), 1u);
}

TEST(CorocontactRun, StepsAndThreadsOptions)
{
    const fs::path dir = coro::test::scratch_dir("cli_opts");
    const fs::path case_file = coro::test::write_text(dir / "small.toml", SMALL_CASE);
    const Outcome outcome =
        run("run " + case_file.string() + " --steps 2 --threads 1 --quiet --out " + (dir / "o").string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.out, HasSubstr("2 steps"));
    EXPECT_THAT(outcome.out, HasSubstr(", 1 thread ("));
    EXPECT_EQ(outcome.err, "");
    EXPECT_EQ(run("run " + case_file.string() + " --threads 0", dir).exit_code, 2);
    EXPECT_EQ(run("run", dir).exit_code, 2);
}

TEST(CorocontactRun, OneAndTwoThreadsAndOneBoundCoreWriteIdenticalFiles)
{
    // Two partitioned bodies (a mesh file and a sphere), dynamic, gravity and damping.
    const fs::path dir = coro::test::scratch_dir("cli_threads");
    const std::string text = std::string(R"toml([simulation]
dt = 0.01
steps = 6
output_every = 3
gravity = [0.0, -9.81, 0.0]

[solver]
max_iterations = 15
parts_per_thread = 4

[[body]]
name = "cube"
mesh = ")toml") + CORO_TEST_DATA_DIR + R"toml(/msh/cube_v41.msh"
young = 1e4
rayleigh_stiffness = 0.01

[[body.fixed]]
min = [-10.0, -10.0, -10.0]
max = [0.01, 10.0, 10.0]

[[body]]
name = "ball"
shape = "sphere"
center = [0.0, 3.0, 0.0]
radius = 0.5
resolution = 12
velocity = [1.0, 0.0, 0.0]
young = 2e4
)toml";
    const fs::path case_file = coro::test::write_text(dir / "threads.toml", text);
    for (const char* threads : {"1", "2"}) {
        const Outcome outcome = run("run " + case_file.string() + " --quiet --threads " + threads + " --out " +
                                        (dir / ("t" + std::string(threads))).string(),
                                    dir);
        ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    }
    // A process bound to one core, as `mpirun` binds its ranks: the ball (10k tets) was split into
    // 4 parts there and 5 elsewhere on two cores, and its frames differed.
    const Outcome bound = run("run " + case_file.string() + " --quiet --threads 1 --out " + (dir / "bound").string(),
                              dir, "", "taskset -c " + std::to_string(first_allowed_cpu()));
    ASSERT_EQ(bound.exit_code, 0) << bound.err;
    for (const char* variant : {"t2", "bound"}) {
        int compared = 0;
        for (const auto& entry : fs::recursive_directory_iterator(dir / "t1")) {
            if (!entry.is_regular_file() || entry.path().extension() == ".json")
                continue;
            const fs::path other = dir / variant / fs::relative(entry.path(), dir / "t1");
            ASSERT_TRUE(fs::exists(other)) << other;
            EXPECT_TRUE(slurp(entry.path()) == slurp(other)) << entry.path() << " differs from " << other;
            ++compared;
        }
        EXPECT_EQ(compared, 1 + 3 + 3 * 2) << variant; // pvd, 3 vtm, 3 × 2 vtu
    }
}

TEST(CorocontactRun, OneAndTwoThreadsWriteIdenticalFramesThroughAnImpact)
{
    // The default case through the first 70 steps: the spheres touch at about step 20.
    const fs::path dir = coro::test::scratch_dir("cli_threads_contact");
    const std::string case_file = std::string(CORO_CASES_DIR) + "/two_spheres/two_spheres.toml";
    for (const char* threads : {"1", "2"}) {
        const Outcome outcome = run("run " + case_file + " --steps 70 --quiet --threads " + threads + " --out " +
                                        (dir / ("t" + std::string(threads))).string(),
                                    dir);
        ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
        EXPECT_THAT(outcome.out, HasSubstr("contact:"));
    }
    int compared = 0;
    for (const auto& entry : fs::recursive_directory_iterator(dir / "t1")) {
        if (!entry.is_regular_file() || entry.path().extension() == ".json")
            continue;
        EXPECT_EQ(slurp(entry.path()), slurp(dir / "t2" / fs::relative(entry.path(), dir / "t1"))) << entry.path();
        ++compared;
    }
    EXPECT_GT(compared, 20);
    const std::string summary = slurp(dir / "t1" / "two_spheres.summary.json");
    EXPECT_THAT(summary, ::testing::Not(HasSubstr("\"max_contact_depth\": 0,")));
}

// Solver settings of the pile below: the default preconditioner with double values, and every
// other preconditioner and precision.
class PileSolver : public ::testing::TestWithParam<const char*> {};

TEST_P(PileSolver, OneAndTwoThreadsWriteIdenticalFrames)
{
    // Bodies stacked on a floor and against a wall, touching each other from the first steps:
    // contact couples them into one system every step.
    const std::string settings = GetParam();
    const fs::path dir = coro::test::scratch_dir("cli_threads_pile_" + std::to_string(std::hash<std::string>()(settings)));
    std::string text = R"toml([simulation]
dt = 0.004
steps = 45
output_every = 15
gravity = [0.0, -9.81, 0.0]
[solver]
max_iterations = 25
tolerance = 1e-7
)toml" + settings + R"toml(
[contact]
enabled = true
stiffness = 4e4
damping = 20.0
friction = 0.4
[[obstacle]]
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
[[obstacle]]
type = "plane"
point = [-0.32, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]
)toml";
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const double x = -0.2 + 0.205 * i, y = 0.1 + 0.205 * j;
            const std::string name = "b" + std::to_string(3 * i + j);
            text += (i + j) % 2 == 0
                        ? "[[body]]\nname = \"" + name + "\"\nshape = \"sphere\"\ncenter = [" + std::to_string(x) +
                              ", " + std::to_string(y) + ", 0.0]\nradius = 0.105\nresolution = 3\n"
                        : "[[body]]\nname = \"" + name + "\"\nshape = \"box\"\nmin = [" + std::to_string(x - 0.1) +
                              ", " + std::to_string(y - 0.1) + ", -0.1]\nmax = [" + std::to_string(x + 0.1) + ", " +
                              std::to_string(y + 0.1) + ", 0.1]\ncells = [2, 2, 2]\n";
            text += "young = 2e4\ndensity = 500.0\n";
        }
    const fs::path case_file = coro::test::write_text(dir / "pile.toml", text);
    std::string summary;
    // PETSc (AMG) under ASan: the slow unwinder, as tests/CMakeLists.txt says for PETSC tests.
    const bool amg = settings.find("amg") != std::string::npos;
    const std::string environment = amg ? "ASAN_OPTIONS=\"${ASAN_OPTIONS}:fast_unwind_on_malloc=0\"" : "";
    for (const char* threads : {"1", "2"}) {
        const Outcome outcome = run("run " + case_file.string() + " --quiet --threads " + threads + " --out " +
                                        (dir / ("t" + std::string(threads))).string(),
                                    dir, environment);
        ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
        summary = outcome.out;
    }
    int compared = 0;
    for (const auto& entry : fs::recursive_directory_iterator(dir / "t1")) {
        if (!entry.is_regular_file() || entry.path().extension() == ".json")
            continue;
        EXPECT_EQ(slurp(entry.path()), slurp(dir / "t2" / fs::relative(entry.path(), dir / "t1"))) << entry.path();
        ++compared;
    }
    EXPECT_EQ(compared, 1 + 4 + 4 * (9 + 2)); // pvd, 4 vtm, 4 × (9 bodies + 2 plane blocks) vtu
    EXPECT_THAT(summary, HasSubstr("contact:"));
    EXPECT_THAT(summary, ::testing::Not(HasSubstr("contact: 0.0 contact points")));
    if (amg) {
        EXPECT_THAT(summary, HasSubstr("AMG: "));
    }
}

INSTANTIATE_TEST_SUITE_P(BlockJacobiDouble, PileSolver, ::testing::Values(""));
INSTANTIATE_TEST_SUITE_P(JacobiSingle, PileSolver,
                         ::testing::Values("preconditioner = \"jacobi\"\nmatrix_precision = \"single\""));
#if CORO_WITH_AMG
INSTANTIATE_TEST_SUITE_P(AmgDouble, PileSolver, ::testing::Values("preconditioner = \"amg\""));
INSTANTIATE_TEST_SUITE_P(AmgSingle, PileSolver,
                         ::testing::Values("preconditioner = \"amg\"\nmatrix_precision = \"single\""));
#endif

TEST(CorocontactRun, FramePointsKeepTheMeshFileNodeOrder)
{
    // A body large enough to be split into METIS parts (whose nodes are renumbered inside) is
    // written in the input's node order: here the order in which make_box numbers them.
    const fs::path dir = coro::test::scratch_dir("cli_order");
    const fs::path case_file = coro::test::write_text(dir / "order.toml", R"toml([simulation]
steps = 1
[solver]
parts_per_thread = 8
[[body]]
name = "cube"
shape = "box"
min = [0.0, 0.0, 0.0]
max = [1.0, 0.5, 0.8]
cells = [12, 12, 12]
)toml");
    ASSERT_EQ(run("run " + case_file.string() + " --quiet --out " + (dir / "o").string(), dir).exit_code, 0);
    vtkNew<vtkXMLMultiBlockDataReader> reader;
    reader->SetFileName((dir / "o" / "order_000000.vtm").string().c_str());
    reader->Update();
    auto* grid = vtkUnstructuredGrid::SafeDownCast(vtkMultiBlockDataSet::SafeDownCast(reader->GetOutput())->GetBlock(0));
    ASSERT_NE(grid, nullptr);
    const coro::TetMesh input = coro::make_box(coro::Vec3(0.0, 0.0, 0.0), coro::Vec3(1.0, 0.5, 0.8), {12, 12, 12});
    ASSERT_EQ(grid->GetNumberOfPoints(), input.num_vertices());
    for (coro::Index i = 0; i < input.num_vertices(); ++i) {
        double q[3];
        grid->GetPoint(i, q);
        for (int d = 0; d < 3; ++d)
            ASSERT_EQ(q[d], input.rest_positions(i, d)) << "node " << i;
    }
    auto* partition = grid->GetCellData()->GetArray("partition");
    ASSERT_NE(partition, nullptr);
    EXPECT_GT(partition->GetRange()[1], 0.0); // really partitioned
}

TEST(CorocontactDetect, CsvRowsAreTheBallVerticesInsideTheSlab)
{
    // A partitioned ball half sunk into a slab: its surface vertex i (input order, as
    // make_sphere numbers them) is inside the slab exactly when it lies below y = 0.
    const fs::path dir = coro::test::scratch_dir("cli_detect");
    const fs::path case_file = coro::test::write_text(dir / "sunk.toml", R"toml([solver]
parts_per_thread = 8
[[body]]
name = "slab"
shape = "box"
min = [-1.0, -0.5, -1.0]
max = [1.0, 0.0, 1.0]
cells = [8, 2, 8]
[[body]]
name = "ball"
shape = "sphere"
center = [0.0, 0.13, 0.0]
radius = 0.4
resolution = 10
)toml");
    const Outcome outcome = run("detect " + case_file.string() + " --csv " + (dir / "out.csv").string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.out, HasSubstr("1 overlapping pair,"));

    std::set<long> ball_rows;
    std::istringstream csv(slurp(dir / "out.csv"));
    std::string line;
    std::getline(csv, line);
    EXPECT_EQ(line, "body,vertex,other,depth");
    bool seen_ball = false;
    long previous_vertex = -1;
    while (std::getline(csv, line)) {
        const bool is_ball = line.rfind("ball,", 0) == 0;
        EXPECT_FALSE(seen_ball && !is_ball) << "rows sorted by body order (slab before ball): " << line;
        seen_ball = seen_ball || is_ball;
        if (is_ball) {
            const std::size_t comma = line.find(',', 5);
            const long vertex = std::stol(line.substr(5, comma - 5));
            EXPECT_GT(vertex, previous_vertex) << "rows sorted by vertex";
            previous_vertex = vertex;
            ball_rows.insert(vertex);
            EXPECT_EQ(line.substr(comma + 1, 5), "slab,");
        }
    }
    const coro::TetMesh ball = coro::make_sphere(coro::Vec3(0.0, 0.13, 0.0), 0.4, 10);
    std::set<long> expected;
    for (const coro::Index v : coro::surface_vertices(coro::boundary_faces(ball)))
        if (ball.rest_positions(v, 1) < 0.0)
            expected.insert(v);
    EXPECT_FALSE(expected.empty());
    EXPECT_EQ(ball_rows, expected);
}

TEST(CorocontactDetect, SameCsvWithOneAndTwoThreadsAndNoEmbreeDisagreement)
{
    const fs::path dir = coro::test::scratch_dir("cli_detect_threads");
    const std::string case_file = std::string(CORO_CASES_DIR) + "/overlap/overlap.toml";
    std::string outputs[2];
    for (int threads = 1; threads <= 2; ++threads) {
        const fs::path csv = dir / ("t" + std::to_string(threads) + ".csv");
        std::string arguments = "detect " + case_file + " --threads " + std::to_string(threads) + " --csv " + csv.string();
#if CORO_WITH_EMBREE
        arguments += " --cross-check embree";
#endif
        const Outcome outcome = run(arguments, dir);
        ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
#if CORO_WITH_EMBREE
        EXPECT_THAT(outcome.out, HasSubstr("embree cross-check: 0 disagreements"));
        EXPECT_THAT(outcome.out, HasSubstr(", 0 depth disagreements"));
#endif
        outputs[threads - 1] = slurp(csv);
    }
    EXPECT_GT(std::count(outputs[0].begin(), outputs[0].end(), '\n'), 100);
    EXPECT_EQ(outputs[0], outputs[1]);
}

TEST(CorocontactDetect, PaperModeAndBadOptions)
{
    const fs::path dir = coro::test::scratch_dir("cli_detect_modes");
    const std::string case_file = std::string(CORO_CASES_DIR) + "/overlap/overlap.toml";
    const Outcome paper = run("detect " + case_file + " --mode paper", dir);
    ASSERT_EQ(paper.exit_code, 0) << paper.err;
    EXPECT_THAT(paper.out, HasSubstr("paper mode"));
    EXPECT_EQ(run("detect " + case_file + " --mode sloppy", dir).exit_code, 2);
    EXPECT_EQ(run("detect " + (dir / "absent.toml").string(), dir).exit_code, 2);
}

TEST(CorocontactRun, ContactArraysInFrames)
{
    const fs::path dir = coro::test::scratch_dir("cli_contact_run");
    const std::string case_file = std::string(CORO_CASES_DIR) + "/overlap/overlap.toml";
    const Outcome outcome = run("run " + case_file + " --quiet --out " + (dir / "o").string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.out, HasSubstr("contact:"));
    vtkNew<vtkXMLMultiBlockDataReader> reader;
    reader->SetFileName((dir / "o" / "overlap_000000.vtm").string().c_str());
    reader->Update();
    auto* blocks = vtkMultiBlockDataSet::SafeDownCast(reader->GetOutput());
    ASSERT_EQ(blocks->GetNumberOfBlocks(), 3u);
    auto* ball = vtkUnstructuredGrid::SafeDownCast(blocks->GetBlock(1));
    auto* inside = ball->GetPointData()->GetArray("contact_inside");
    auto* depth = ball->GetPointData()->GetArray("contact_depth");
    ASSERT_NE(inside, nullptr);
    ASSERT_NE(depth, nullptr);
    EXPECT_EQ(inside->GetRange()[1], 1.0);
    EXPECT_GT(depth->GetRange()[1], 0.05);
    const std::string summary = slurp(dir / "o" / "overlap.summary.json");
    EXPECT_THAT(summary, HasSubstr("\"max_contact_depth\""));
}

TEST(CorocontactInfo, DescribesAMesh)
{
    const fs::path dir = coro::test::scratch_dir("cli_info");
    const Outcome outcome = run(std::string("info ") + CORO_TEST_DATA_DIR + "/msh/cube_v41.msh", dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.out, HasSubstr("nodes 76, tets 172"));
    EXPECT_THAT(outcome.out, HasSubstr("closed, consistently oriented, 1 piece, Euler characteristic 2, genus 0"));
    // --threads after the command, as run and detect take it.
    const Outcome parts = run(std::string("info ") + CORO_TEST_DATA_DIR + "/msh/cube_v41.msh --parts 3 --threads 1", dir);
    ASSERT_EQ(parts.exit_code, 0) << parts.err;
    EXPECT_THAT(parts.out, HasSubstr("METIS parts 3: edge-cut"));
    EXPECT_THAT(parts.err, Not(HasSubstr("note:")));
    // More parts than tets: capped at one tet per part, and said so.
    const Outcome capped = run(std::string("info ") + CORO_TEST_DATA_DIR + "/msh/cube_v41.msh --parts 1000000000", dir);
    ASSERT_EQ(capped.exit_code, 0) << capped.err;
    EXPECT_THAT(capped.err, HasSubstr("note: --parts 1000000000: the mesh has 172 tets, and a part holds at least one; "
                                      "using 172 parts"));
    EXPECT_THAT(capped.out, HasSubstr("METIS parts 172: edge-cut"));
    EXPECT_EQ(run("info " + (dir / "absent.msh").string(), dir).exit_code, 2);
    EXPECT_THAT(outcome.out, HasSubstr("nodes where another node lies 0"));
    EXPECT_THAT(outcome.err, Not(HasSubstr("warning")));
    // Two tets that share a face by position only: nodes 5, 6, 7 repeat nodes 1, 2, 3.
    const fs::path unmerged = coro::test::write_text(
        dir / "unmerged.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n8\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
                              "5 1 1 1\n6 1 0 0\n7 0 1 0\n8 0 0 1\n$EndNodes\n$Elements\n2\n1 4 2 0 1 1 2 3 4\n"
                              "2 4 2 0 1 6 7 8 5\n$EndElements\n");
    const Outcome split = run("info " + unmerged.string(), dir);
    ASSERT_EQ(split.exit_code, 0) << split.err;
    EXPECT_THAT(split.out, HasSubstr("nodes where another node lies 3"));
    EXPECT_THAT(split.err, HasSubstr("warning: 3 nodes lie exactly where another node lies (e.g. nodes 3 and 7"));
}

TEST(Corocontact, HelpAndVersion)
{
    const fs::path dir = coro::test::scratch_dir("cli_help");
    Outcome outcome = run("--version", dir);
    EXPECT_EQ(outcome.exit_code, 0);
    EXPECT_THAT(outcome.out, HasSubstr("corocontact 0."));
    outcome = run("run --help", dir);
    EXPECT_EQ(outcome.exit_code, 0);
    EXPECT_THAT(outcome.out, HasSubstr("--threads"));
    EXPECT_EQ(run("info --version", dir).exit_code, 0);
    EXPECT_EQ(run("frobnicate", dir).exit_code, 2);
}

TEST(CorocontactRun, WarnsWhenSolvesStopAtTheCapUnlessToleranceIsZero)
{
    const fs::path dir = coro::test::scratch_dir("cli_cap");
    std::string text = SMALL_CASE;
    text.replace(text.find("max_iterations = 50"), 19, "max_iterations = 2");
    const fs::path capped = coro::test::write_text(dir / "capped.toml", text);
    Outcome outcome = run("run " + capped.string() + " --quiet --out " + (dir / "a").string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.out, HasSubstr("warning: 4 of 4 PCG solves stopped at solver.max_iterations = 2"));

    text.replace(text.find("max_iterations = 2"), 18, "max_iterations = 2\ntolerance = 0");
    const fs::path on_purpose = coro::test::write_text(dir / "on_purpose.toml", text);
    outcome = run("run " + on_purpose.string() + " --quiet --out " + (dir / "b").string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.out, HasSubstr("2.0 iterations per solve"));
    EXPECT_THAT(outcome.out, ::testing::Not(HasSubstr("warning")));
}

TEST(CorocontactRun, StaticAnalysisSaysItDoesNotApplyContact)
{
    // Two clamped blocks that overlap at rest: a dynamic run would find contact at once.
    const fs::path dir = coro::test::scratch_dir("cli_static_contact");
    const fs::path case_file = coro::test::write_text(dir / "pressed.toml", R"([simulation]
analysis = "static"
load_steps = 2

[contact]
enabled = true

[[body]]
name = "lower"
shape = "box"
min = [0.0, 0.0, 0.0]
max = [2.0, 1.0, 1.0]
cells = [4, 2, 2]
[[body.fixed]]
min = [-1.0, -1.0, -1.0]
max = [1e-9, 2.0, 2.0]

[[body]]
name = "upper"
shape = "box"
min = [0.0, 0.8, 0.0]
max = [2.0, 1.8, 1.0]
cells = [4, 2, 2]
[[body.fixed]]
min = [-1.0, -1.0, -1.0]
max = [1e-9, 2.0, 2.0]
[[body.load]]
min = [1.999, -1.0, -1.0]
max = [3.0, 3.0, 3.0]
force = [0.0, -1e3, 0.0]
)");
    const Outcome outcome = run("run " + case_file.string() + " --quiet --out " + (dir / "o").string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr("pressed.toml: note: contact.enabled = true is not applied in static analysis"));
    EXPECT_THAT(outcome.out, HasSubstr("Newton:"));
    EXPECT_THAT(outcome.out, ::testing::Not(HasSubstr("contact:")));
    vtkNew<vtkXMLMultiBlockDataReader> reader;
    reader->SetFileName((dir / "o" / "pressed_000002.vtm").string().c_str());
    reader->Update();
    auto* blocks = vtkMultiBlockDataSet::SafeDownCast(reader->GetOutput());
    ASSERT_NE(blocks, nullptr);
    for (unsigned b = 0; b < 2; ++b) {
        auto* grid = vtkUnstructuredGrid::SafeDownCast(blocks->GetBlock(b));
        ASSERT_NE(grid, nullptr);
        for (const char* name : {"contact_inside", "contact_force"}) {
            auto* array = grid->GetPointData()->GetArray(name);
            ASSERT_NE(array, nullptr) << name;
            for (int c = 0; c < array->GetNumberOfComponents(); ++c) {
                EXPECT_EQ(array->GetRange(c)[0], 0.0) << name;
                EXPECT_EQ(array->GetRange(c)[1], 0.0) << name;
            }
        }
    }
    const std::string summary = slurp(dir / "o" / "pressed.summary.json");
    EXPECT_THAT(summary, HasSubstr("\"static_iterations_mean\""));
    EXPECT_THAT(summary, HasSubstr("\"static_iterations_max\""));
}
