// What the command says: option messages, source tags only when asked, the thread count used,
// static bodies held by nothing, contact counts, set-up time, plane blocks and `info` of
// surfaces.

#include "cli_run.hpp"
#include "mesh_fixtures.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <vtkCellData.h>
#include <vtkCompositeDataSet.h>
#include <vtkDataArray.h>
#include <vtkInformation.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLMultiBlockDataReader.h>

#include <tbb/info.h>

#include <algorithm>
#include <regex>
#include <set>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::ContainsRegex;
using ::testing::HasSubstr;
using ::testing::Not;
using coro::test::Outcome;
using coro::test::run;
using coro::test::slurp;

namespace {

const char* BLOCK = R"([simulation]
dt = 0.01
steps = 2
output_every = 1

[[body]]
name = "block"
shape = "box"
min = [0.0, 0.0, 0.0]
max = [2.0, 1.0, 1.0]
cells = [2, 1, 1]
)";

const char* SOURCE_TAG = R"(\[[a-z_]+\.cpp:[0-9]+\])";

/// The number after `key` in the summary JSON.
double json_number(const std::string& json, const std::string& key)
{
    const std::regex pattern("\"" + key + "\": ([-+0-9.eE]+)");
    std::smatch match;
    if (!std::regex_search(json, match, pattern))
        throw std::runtime_error("no " + key + " in " + json);
    return std::stod(match[1]);
}

} // namespace

TEST(CorocontactMessages, OptionValuesGetPlainRangeMessages)
{
    const fs::path dir = coro::test::scratch_dir("msg_options");
    const std::string case_file = coro::test::write_text(dir / "block.toml", BLOCK).string();
    for (const char* option_text : {"--threads 0", "--threads abc", "--threads -3", "--steps 0", "--steps 2.5",
                                     "--steps 99999999999", "--checkpoint-every 0"}) {
        const std::string option = option_text;
        const Outcome outcome = run("run " + case_file + " " + option + " --out " + (dir / "o").string(), dir);
        EXPECT_EQ(outcome.exit_code, 2) << option;
        const std::string name = option.substr(0, option.find(' '));
        const std::string value = option.substr(option.find(' ') + 1);
        EXPECT_THAT(outcome.err, HasSubstr(name + ": expected a whole number from 1 to 2147483647, found '" + value +
                                           "'"))
            << option;
        EXPECT_THAT(outcome.err, Not(HasSubstr("not in range"))) << option;
        EXPECT_THAT(outcome.err, Not(HasSubstr("179769"))) << option; // DBL_MAX's digits
        EXPECT_FALSE(fs::exists(dir / "o")) << option;
    }
    const Outcome parts = run("info " + std::string(CORO_CASES_DIR) + "/ring/ring.msh --parts 0", dir);
    EXPECT_EQ(parts.exit_code, 2);
    EXPECT_THAT(parts.err, HasSubstr("--parts: expected a whole number from 1 to 2147483647, found '0'"));
}

TEST(CorocontactMessages, ReportsTheThreadsActuallyUsed)
{
    const fs::path dir = coro::test::scratch_dir("msg_threads");
    const std::string case_file = coro::test::write_text(dir / "block.toml", BLOCK).string();
    const Outcome outcome = run("run " + case_file + " --threads 100000 --out " + (dir / "o").string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    const int cores = tbb::info::default_concurrency();
    const std::string used = std::to_string(cores) + (cores == 1 ? " thread" : " threads");
    EXPECT_THAT(outcome.err, HasSubstr("note: --threads 100000: this process may run on " + std::to_string(cores) +
                                       (cores == 1 ? " core" : " cores") + " only; using " + used + "\n"));
    EXPECT_THAT(outcome.err, HasSubstr(", " + used + "\n")); // the header
    EXPECT_THAT(outcome.out, HasSubstr(", " + used + " (set-up"));
    EXPECT_EQ(json_number(slurp(dir / "o" / "block.summary.json"), "threads"), cores);
    EXPECT_THAT(outcome.err, Not(HasSubstr("100000 threads")));
}

TEST(CorocontactMessages, OneBodyAndOneThreadAreSingular)
{
    const fs::path dir = coro::test::scratch_dir("msg_singular");
    const std::string case_file = coro::test::write_text(dir / "block.toml", BLOCK).string();
    const Outcome outcome = run("run " + case_file + " --threads 1 --out " + (dir / "o").string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr("block, 1 body, 12 tets, 12 nodes, 1 thread\n"));
    EXPECT_THAT(outcome.out, HasSubstr("2 steps in"));
    EXPECT_THAT(outcome.out, HasSubstr(", 1 thread (set-up"));
}

TEST(CorocontactMessages, SourceTagsOnlyWithVerboseOrCoroDebug)
{
    const fs::path dir = coro::test::scratch_dir("msg_tags");
    std::string text = BLOCK;
    text.replace(text.find("cells = [2, 1, 1]"), 17, "cells = [2, 0, 1]");
    const std::string case_file = coro::test::write_text(dir / "bad.toml", text).string();

    const Outcome plain = run("run " + case_file, dir, "-u CORO_DEBUG");
    EXPECT_EQ(plain.exit_code, 2);
    EXPECT_THAT(plain.err, AllOf(HasSubstr("bad.toml:"), HasSubstr("cells")));
    EXPECT_THAT(plain.err, Not(ContainsRegex(SOURCE_TAG)));

    const Outcome verbose = run("run " + case_file + " --verbose", dir, "-u CORO_DEBUG");
    EXPECT_EQ(verbose.exit_code, 2);
    EXPECT_THAT(verbose.err, ContainsRegex(SOURCE_TAG));

    const Outcome debug = run("run " + case_file, dir, "CORO_DEBUG=1");
    EXPECT_EQ(debug.exit_code, 2);
    EXPECT_THAT(debug.err, ContainsRegex(SOURCE_TAG));
    EXPECT_THAT(run("run " + case_file, dir, "CORO_DEBUG=0").err, Not(ContainsRegex(SOURCE_TAG)));

    // A divergence message too (exit 3): it is built from several nested messages. The block is
    // thrown at its clamp at 1e6 m/s (values whose products overflow double are refused at load).
    const std::string diverging = std::string(BLOCK) + "velocity = [-1e6, 0.0, 0.0]\n[[body.fixed]]\nmax = [0.0, 2.0, 2.0]\n";
    const std::string diverging_file = coro::test::write_text(dir / "diverge.toml", diverging).string();
    const Outcome diverged = run("run " + diverging_file + " --out " + (dir / "d").string(), dir, "-u CORO_DEBUG");
    EXPECT_EQ(diverged.exit_code, 3);
    EXPECT_THAT(diverged.err, HasSubstr("step 1"));
    EXPECT_THAT(diverged.err, Not(ContainsRegex(SOURCE_TAG)));
}

TEST(CorocontactMessages, StaticBodyHeldByNothingIsNamedAtLoad)
{
    const fs::path dir = coro::test::scratch_dir("msg_static");
    std::string text = BLOCK;
    text.replace(text.find("dt = 0.01"), 9, "analysis = \"static\"\nload_steps = 2");
    text += "young = 1e5\n[[body.load]]\nmin = [1.9, -1.0, -1.0]\nforce = [0.0, -1.0, 0.0]\n";
    const std::string case_file = coro::test::write_text(dir / "static.toml", text).string();
    const Outcome outcome = run("run " + case_file + " --out " + (dir / "o").string(), dir);
    EXPECT_EQ(outcome.exit_code, 2);
    EXPECT_THAT(outcome.err, HasSubstr("static.toml:7: body 'block': static analysis, but no node of the body is "
                                       "fixed, so its rigid-body motion is unconstrained"));
    EXPECT_THAT(outcome.err, HasSubstr("[[body.fixed]]"));
    EXPECT_THAT(outcome.err, Not(HasSubstr("positive definite")));
    EXPECT_FALSE(fs::exists(dir / "o"));

    // Held along one edge only (the nodes at x = 0, y = 0): it can still turn about that edge.
    const std::string hinge = coro::test::write_text(dir / "hinge.toml",
                                                     text + "[[body.fixed]]\nmin = [-1.0, -1.0, -1.0]\n"
                                                            "max = [0.01, 0.01, 2.0]\n")
                                  .string();
    const Outcome hinged = run("run " + hinge + " --out " + (dir / "o").string(), dir);
    EXPECT_EQ(hinged.exit_code, 2);
    EXPECT_THAT(hinged.err, HasSubstr("its 2 fixed nodes lie on one line, which leaves the rotation about that line "
                                      "unconstrained"));

    // Held on the whole face x = 0: it runs.
    const std::string clamped = coro::test::write_text(dir / "clamped.toml",
                                                       text + "[[body.fixed]]\nmin = [-1.0, -1.0, -1.0]\n"
                                                              "max = [0.01, 2.0, 2.0]\n")
                                    .string();
    const Outcome ok = run("run " + clamped + " --quiet --out " + (dir / "o").string(), dir);
    EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

TEST(CorocontactMessages, SummaryHasSetUpTimeApartFromTheLoop)
{
    const fs::path dir = coro::test::scratch_dir("msg_setup");
    const std::string case_file = coro::test::write_text(dir / "block.toml", BLOCK).string();
    const Outcome outcome = run("run " + case_file + " --quiet --out " + (dir / "o").string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.out, ContainsRegex("set-up before the steps: [0-9.]+ s"));
    const std::string json = slurp(dir / "o" / "block.summary.json");
    EXPECT_GT(json_number(json, "setup_s"), 0.0);
    EXPECT_GT(json_number(json, "wall_s"), 0.0);
}

// detect's contact points are its CSV rows; its vertices inside are the vertices the first
// frame of a run marks with contact_inside = 1; the run's contacts_mean over one detection
// (--steps would add more) is the detect count when no step has moved anything yet.
TEST(CorocontactMessages, ContactCountsAgreeBetweenDetectCsvAndFrames)
{
    const fs::path dir = coro::test::scratch_dir("msg_counts");
    const std::string case_file = std::string(CORO_CASES_DIR) + "/overlap/overlap.toml";
    const Outcome detect = run("detect " + case_file + " --csv " + (dir / "c.csv").string(), dir);
    ASSERT_EQ(detect.exit_code, 0) << detect.err;
    std::smatch match;
    ASSERT_TRUE(std::regex_search(detect.out, match, std::regex("([0-9]+) contact points at ([0-9]+) vertices inside")))
        << detect.out;
    const long points = std::stol(match[1]), vertices = std::stol(match[2]);
    EXPECT_GT(points, 0);

    std::istringstream csv(slurp(dir / "c.csv"));
    std::string line;
    std::getline(csv, line); // header
    long rows = 0;
    std::set<std::string> distinct;
    while (std::getline(csv, line)) {
        ++rows;
        const std::size_t second_comma = line.find(',', line.find(',') + 1);
        distinct.insert(line.substr(0, second_comma));
    }
    EXPECT_EQ(rows, points);
    EXPECT_EQ(static_cast<long>(distinct.size()), vertices);

    const Outcome ran = run("run " + case_file + " --steps 1 --quiet --out " + (dir / "o").string(), dir);
    ASSERT_EQ(ran.exit_code, 0) << ran.err;
    vtkNew<vtkXMLMultiBlockDataReader> reader;
    reader->SetFileName((dir / "o" / "overlap_000000.vtm").string().c_str());
    reader->Update();
    auto* blocks = vtkMultiBlockDataSet::SafeDownCast(reader->GetOutput());
    ASSERT_NE(blocks, nullptr);
    double marked = 0.0;
    for (unsigned b = 0; b < blocks->GetNumberOfBlocks(); ++b) {
        auto* grid = vtkUnstructuredGrid::SafeDownCast(blocks->GetBlock(b));
        vtkDataArray* inside = grid != nullptr ? grid->GetPointData()->GetArray("contact_inside") : nullptr;
        for (vtkIdType i = 0; inside != nullptr && i < inside->GetNumberOfTuples(); ++i)
            marked += inside->GetTuple1(i);
    }
    EXPECT_EQ(static_cast<long>(marked), vertices);
    EXPECT_THAT(ran.out, HasSubstr("contact points per detection"));
}

TEST(CorocontactFrames, PlaneObstaclesAreBlocksUnderTheScene)
{
    const fs::path dir = coro::test::scratch_dir("msg_planes");
    const Outcome outcome = run("run " + std::string(CORO_CASES_DIR) + "/ring/ring.toml --steps 1 --quiet --out " +
                                    (dir / "o").string(),
                                dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    vtkNew<vtkXMLMultiBlockDataReader> reader;
    reader->SetFileName((dir / "o" / "ring_000000.vtm").string().c_str());
    reader->Update();
    auto* blocks = vtkMultiBlockDataSet::SafeDownCast(reader->GetOutput());
    ASSERT_NE(blocks, nullptr);
    ASSERT_EQ(blocks->GetNumberOfBlocks(), 2u);
    EXPECT_STREQ(blocks->GetMetaData(1u)->Get(vtkCompositeDataSet::NAME()), "plane0");
    auto* ring = vtkUnstructuredGrid::SafeDownCast(blocks->GetBlock(0));
    auto* floor = vtkUnstructuredGrid::SafeDownCast(blocks->GetBlock(1));
    ASSERT_NE(ring, nullptr);
    ASSERT_NE(floor, nullptr);
    EXPECT_EQ(floor->GetNumberOfPoints(), 4);
    EXPECT_EQ(floor->GetNumberOfCells(), 2);
    double r[6], f[6];
    ring->GetBounds(r);
    floor->GetBounds(f);
    EXPECT_EQ(f[2], 0.0); // y: the floor plane itself
    EXPECT_EQ(f[3], 0.0);
    EXPECT_LT(f[0], r[0]); // x and z: under the whole ring
    EXPECT_GT(f[1], r[1]);
    EXPECT_LT(f[4], r[4]);
    EXPECT_GT(f[5], r[5]);
}

TEST(CorocontactInfo, DescribesSurfacesAndTheirGenus)
{
    const fs::path dir = coro::test::scratch_dir("msg_info");
    const std::string ring = std::string(CORO_CASES_DIR) + "/ring/ring";
    const Outcome surface = run("info " + ring + ".obj", dir);
    ASSERT_EQ(surface.exit_code, 0) << surface.err;
    EXPECT_THAT(surface.out, HasSubstr("triangle surface: vertices 192 (192 used by faces), edges 576, faces 384"));
    EXPECT_THAT(surface.out, HasSubstr("closed, consistently oriented, 1 piece, Euler characteristic 0, genus 1"));
    EXPECT_THAT(surface.out, HasSubstr("bounding box [-0.5, 0, -0.5] - [0.5, 0.2, 0.5]"));
    EXPECT_THAT(surface.out, HasSubstr("normals point outward"));

    const Outcome mesh = run("info " + ring + ".msh", dir);
    ASSERT_EQ(mesh.exit_code, 0) << mesh.err;
    EXPECT_THAT(mesh.out, HasSubstr("tet mesh: nodes 216, tets 576, boundary faces 384, boundary nodes 192"));
    EXPECT_THAT(mesh.out, HasSubstr("boundary surface closed, consistently oriented, 1 piece, Euler characteristic 0, "
                                    "genus 1"));

    const fs::path open = coro::test::write_text(dir / "open.OFF", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
                                                                   "3 0 1 2\n3 0 2 3\n");
    const Outcome square = run("info " + open.string(), dir);
    ASSERT_EQ(square.exit_code, 0) << square.err;
    EXPECT_THAT(square.out, HasSubstr("NOT closed, consistently oriented, 1 piece, Euler characteristic 1 (no genus"));
    EXPECT_THAT(square.out, HasSubstr("open edges 4"));
    EXPECT_THAT(square.out, Not(HasSubstr("enclosed volume")));

    const Outcome parts = run("info " + ring + ".obj --parts 2", dir);
    EXPECT_EQ(parts.exit_code, 2);
    EXPECT_THAT(parts.err, HasSubstr("is a triangle surface; METIS parts are for tet meshes"));
}
