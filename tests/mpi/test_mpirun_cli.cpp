// The corocontact command under mpirun (-np 2 and 3): frames bitwise equal to one process,
// bad input reported once with exit code 2 on every process, a divergence on one process
// stopping all with 3, and checkpoints that continue on another number of processes.

#include "mesh_fixtures.hpp"

#include <corocontact/config.hpp>
#include <corocontact/core/fingerprint.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

namespace {

const std::string DATA = CORO_MPI_TEST_DATA_DIR;

struct Outcome {
    int exit_code;
    std::string out;
    std::string err;
};

std::string slurp(const fs::path& path)
{
    std::ifstream file(path, std::ios::binary);
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
}

// Runs corocontact with `arguments`, alone (ranks = 0) or under mpirun -np ranks. OpenMPI
// refuses root without the two variables; on 2 shared cores its waits must yield the core.
// Under ASan, OpenMPI's own leaks at exit are suppressed (lsan.supp), nothing else.
const std::string MPIRUN = "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_mpi_yield_when_idle=1 "
                           "ASAN_OPTIONS=\"${ASAN_OPTIONS}:fast_unwind_on_malloc=0\" "
                           "LSAN_OPTIONS=\"${LSAN_OPTIONS}:suppressions=" CORO_MPI_LSAN_SUPPRESSIONS "\" " +
                           std::string(CORO_MPIEXEC) + " --oversubscribe --bind-to none ";

Outcome run_shell(const std::string& command, const fs::path& dir)
{
    const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    const int status = std::system((command + " > " + out.string() + " 2> " + err.string() + " < /dev/null").c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

Outcome corocontact(int ranks, const std::string& arguments, const fs::path& dir)
{
    const std::string command = std::string(CORO_CLI_PATH) + " " + arguments;
    return run_shell(ranks > 0 ? MPIRUN + "-np " + std::to_string(ranks) + " " + command : command, dir);
}

// One process in each working directory, each with its own arguments (mpirun's MPMD form).
Outcome corocontact_in(const std::vector<std::pair<fs::path, std::string>>& processes, const fs::path& dir)
{
    std::string command = MPIRUN;
    for (std::size_t p = 0; p < processes.size(); ++p)
        command += (p > 0 ? " : " : "") + std::string("-np 1 -wdir ") + processes[p].first.string() + " " +
                   CORO_CLI_PATH + " " + processes[p].second;
    return run_shell(command, dir);
}

// Every frame file and the .pvd under `a` exist under `b` with the same bytes; the count.
int expect_same_frames(const fs::path& a, const fs::path& b)
{
    int compared = 0;
    for (const auto& entry : fs::recursive_directory_iterator(a)) {
        const std::string extension = entry.path().extension().string();
        if (!entry.is_regular_file() || (extension != ".vtu" && extension != ".vtm" && extension != ".pvd"))
            continue;
        const fs::path relative = fs::relative(entry.path(), a);
        EXPECT_TRUE(fs::exists(b / relative)) << relative;
        EXPECT_TRUE(slurp(entry.path()) == slurp(b / relative)) << relative << " differs";
        ++compared;
    }
    return compared;
}

double json_number(const std::string& json, const std::string& key)
{
    std::smatch match;
    const std::regex pattern("\"" + key + "\": ([-0-9.e+]+)");
    return std::regex_search(json, match, pattern) ? std::stod(match[1]) : -1.0;
}

std::size_t count(const std::string& text, const std::string& what)
{
    std::size_t n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1))
        ++n;
    return n;
}

// `checkpoint` with every body's METIS part count raised by one, its checksum made to fit
// again (the layout of src/sim/checkpoint.cpp: magic, version, fingerprint, body count, then
// per body a 32-bit name length, the name, nodes, tets and parts as int64; the FNV-1a of all
// before it last): what a checkpoint from a machine with other cores looks like.
void raise_part_counts(const fs::path& checkpoint)
{
    std::string bytes = slurp(checkpoint);
    std::size_t at = 8 + 4 + 8;
    std::uint64_t bodies;
    std::memcpy(&bodies, bytes.data() + at, sizeof bodies);
    at += 8;
    for (std::uint64_t b = 0; b < bodies; ++b) {
        std::uint32_t length;
        std::memcpy(&length, bytes.data() + at, sizeof length);
        at += 4 + length + 16;
        std::int64_t parts;
        std::memcpy(&parts, bytes.data() + at, sizeof parts);
        ++parts;
        std::memcpy(bytes.data() + at, &parts, sizeof parts);
        at += 8;
    }
    const std::uint64_t checksum = coro::fnv1a(bytes.data(), bytes.size() - 8);
    std::memcpy(bytes.data() + bytes.size() - 8, &checksum, sizeof checksum);
    std::ofstream(checkpoint, std::ios::binary) << bytes;
}

// The lines of `text` that hold `what`.
std::vector<std::string> lines_with(const std::string& text, const std::string& what)
{
    std::vector<std::string> lines;
    std::istringstream stream(text);
    for (std::string line; std::getline(stream, line);)
        if (line.find(what) != std::string::npos)
            lines.push_back(line);
    return lines;
}

} // namespace

TEST(MpirunRun, FramesAreBitwiseThoseOfOneProcessOnTwoAndThreeProcesses)
{
    const fs::path dir = coro::test::scratch_dir("mpirun_frames");
    const std::string pile = DATA + "/touching_pile.toml";
    Outcome outcome = corocontact(0, "run " + pile + " --quiet --out " + (dir / "one").string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    for (const int ranks : {2, 3}) {
        const fs::path out = dir / ("np" + std::to_string(ranks));
        outcome = corocontact(ranks, "run " + pile + " --threads 1 --quiet --out " + out.string(), dir);
        ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
        EXPECT_EQ(count(outcome.out, "touching_pile: 30 steps"), 1u) << "rank 0 alone prints:\n" << outcome.out;
        // 4 frames of 12 bodies and a plane, their .vtm, the .pvd.
        EXPECT_EQ(expect_same_frames(dir / "one", out), 4 * 13 + 4 + 1) << ranks << " processes";
        const std::string summary = slurp(out / "touching_pile.summary.json");
        EXPECT_EQ(json_number(summary, "ranks"), ranks);
        EXPECT_GT(json_number(summary, "cross_rank_contacts_mean"), 1.0) << "bodies on different processes touch";
        EXPECT_GT(json_number(summary, "mpi_bytes_per_step"), 0.0);
        EXPECT_EQ(count(summary, "\"rank\": "), static_cast<std::size_t>(ranks));
        EXPECT_EQ(json_number(summary, "contacts_mean"),
                  json_number(slurp(dir / "one" / "touching_pile.summary.json"), "contacts_mean"));
    }
}

TEST(MpirunRun, BadInputIsReportedOnceAndEveryProcessExitsWithTwo)
{
    const fs::path dir = coro::test::scratch_dir("mpirun_bad_input");
    std::string text = slurp(DATA + "/touching_pile.toml");
    text.replace(text.find("stiffness = 2e5"), 15, "stifness = 2e5");
    std::ofstream(dir / "typo.toml") << text;
    const Outcome outcome = corocontact(2, "run " + (dir / "typo.toml").string() + " --quiet --out " +
                                               (dir / "out").string(), dir);
    EXPECT_EQ(outcome.exit_code, 2);
    EXPECT_EQ(count(outcome.err, "error: "), 1u) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr("typo.toml:"));
    EXPECT_THAT(outcome.err, HasSubstr("stifness"));
    EXPECT_FALSE(fs::exists(dir / "out")) << "nothing written for bad input";
}

TEST(MpirunRun, ARestartWarnsAboutEveryBodyAsOneProcessDoes)
{
    // Parts that differ from the checkpoint's are warned about body by body; on several
    // processes the warnings of every process's bodies, in case order, as alone.
    const fs::path dir = coro::test::scratch_dir("mpirun_restart_parts");
    const std::string pile = DATA + "/touching_pile.toml";
    const fs::path first = dir / "first";
    Outcome outcome = corocontact(0, "run " + pile + " --steps 10 --checkpoint-every 10 --quiet --out " + first.string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    const fs::path checkpoint = dir / "other_machine.checkpoint";
    fs::copy_file(first / "touching_pile.checkpoint", checkpoint);
    raise_part_counts(checkpoint);
    std::vector<std::string> alone;
    for (const int ranks : {0, 2, 3}) {
        const fs::path out = dir / ("np" + std::to_string(ranks));
        fs::create_directories(out);
        outcome = corocontact(ranks, "run " + pile + " --steps 12 --quiet --restart " + checkpoint.string() +
                                         " --out " + out.string(), dir);
        ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
        const std::vector<std::string> warnings = lines_with(outcome.err, "METIS parts when saved");
        if (ranks == 0) {
            alone = warnings;
            EXPECT_EQ(alone.size(), 12u) << outcome.err;
            EXPECT_THAT(alone.front(), HasSubstr("body 'b00' was split into"));
        } else {
            EXPECT_EQ(warnings, alone) << ranks << " processes";
        }
    }
}

TEST(MpirunRun, ARestartCountsContactsAcrossProcessesOverItsOwnDetections)
{
    // Restarted one step before the end, the mean is that of the last detections, close to the
    // uninterrupted run's, not their count spread over the first run's detections too.
    const fs::path dir = coro::test::scratch_dir("mpirun_restart_cross");
    const std::string pile = DATA + "/touching_pile.toml";
    const fs::path whole = dir / "whole", restarted = dir / "restarted";
    ASSERT_EQ(corocontact(2, "run " + pile + " --steps 20 --quiet --out " + whole.string(), dir).exit_code, 0);
    ASSERT_EQ(corocontact(2, "run " + pile + " --steps 19 --checkpoint-every 19 --quiet --out " + restarted.string(), dir)
                  .exit_code,
              0);
    const Outcome outcome = corocontact(2, "run " + pile + " --steps 20 --quiet --restart " + restarted.string() +
                                               "/touching_pile.checkpoint --out " + restarted.string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    const double all = json_number(slurp(whole / "touching_pile.summary.json"), "cross_rank_contacts_mean");
    const double last = json_number(slurp(restarted / "touching_pile.summary.json"), "cross_rank_contacts_mean");
    ASSERT_GT(all, 1.0) << "the pile must have contacts across the processes";
    EXPECT_GT(last, 0.5 * all);
    EXPECT_LT(last, 2.0 * all);
}

TEST(MpirunRun, ProcessesGivenOtherOptionsOrFilesStopWithTwo)
{
    const fs::path dir = coro::test::scratch_dir("mpirun_mismatch");
    const std::string pile = DATA + "/touching_pile.toml", out = (dir / "out").string();
    // Another --steps on the second process: it would wait in an exchange the first never enters.
    Outcome outcome = corocontact_in({{dir, "run " + pile + " --steps 3 --quiet --out " + out},
                                      {dir, "run " + pile + " --steps 4 --quiet --out " + out}},
                                     dir);
    EXPECT_EQ(outcome.exit_code, 2);
    EXPECT_EQ(count(outcome.err, "error: "), 1u) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr("were started with different command lines"));
    EXPECT_FALSE(fs::exists(dir / "out"));
    // Another subcommand, and a command line one process cannot parse: the same.
    for (const std::string& other : {"detect " + pile, "run " + pile + " --steps 0"}) {
        outcome = corocontact_in({{dir, "run " + pile + " --steps 3 --quiet --out " + out}, {dir, other}}, dir);
        EXPECT_EQ(outcome.exit_code, 2) << other;
        EXPECT_THAT(outcome.err, HasSubstr("were started with different command lines")) << other;
    }
    // The same case file on both "nodes", but its mesh file differs: one tet, twice as large.
    const std::string tet_case = "[simulation]\ndt = 0.01\nsteps = 2\n[[body]]\nname = \"tet\"\nmesh = \"tet.node\"\n";
    for (const auto& [node, size] : {std::pair{"node1", "1"}, std::pair{"node2", "2"}}) {
        fs::create_directories(dir / node);
        std::ofstream(dir / node / "tet.toml") << tet_case;
        std::ofstream(dir / node / "tet.node")
            << "4 3 0 0\n1 0 0 0\n2 " << size << " 0 0\n3 0 " << size << " 0\n4 0 0 " << size << "\n";
        std::ofstream(dir / node / "tet.ele") << "1 4 0\n1 1 2 3 4\n";
    }
    outcome = corocontact_in({{dir / "node1", "run tet.toml --quiet --out " + out},
                              {dir / "node2", "run tet.toml --quiet --out " + out}},
                             dir);
    EXPECT_EQ(outcome.exit_code, 2);
    EXPECT_EQ(count(outcome.err, "error: "), 1u) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr("loaded different bodies"));
    EXPECT_FALSE(fs::exists(dir / "out"));
    // The same command line, but the case file differs between the "nodes".
    std::ofstream(dir / "node2" / "tet.toml") << tet_case << "velocity = [1.0, 0.0, 0.0]\n";
    outcome = corocontact_in({{dir / "node1", "run tet.toml --quiet --out " + out},
                              {dir / "node2", "run tet.toml --quiet --out " + out}},
                             dir);
    EXPECT_EQ(outcome.exit_code, 2);
    EXPECT_EQ(count(outcome.err, "error: "), 1u) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr("tet.toml: the processes of this run read different case files"));
    std::ofstream(dir / "node2" / "tet.toml") << tet_case;
    // The same files on both: it runs.
    fs::copy_file(dir / "node1" / "tet.node", dir / "node2" / "tet.node", fs::copy_options::overwrite_existing);
    outcome = corocontact_in({{dir / "node1", "run tet.toml --quiet --out " + out},
                              {dir / "node2", "run tet.toml --quiet --out " + out}},
                             dir);
    EXPECT_EQ(outcome.exit_code, 0) << outcome.err;
}

#if CORO_WITH_AMG
TEST(MpirunRun, AmgIsRefusedForADistributedRun)
{
    const fs::path dir = coro::test::scratch_dir("mpirun_amg");
    std::string text = slurp(DATA + "/touching_pile.toml");
    text.replace(text.find("\"block_jacobi\""), 14, "\"amg\"");
    std::ofstream(dir / "amg.toml") << text;
    const Outcome outcome =
        corocontact(2, "run " + (dir / "amg.toml").string() + " --quiet --out " + (dir / "out").string(), dir);
    EXPECT_EQ(outcome.exit_code, 2);
    EXPECT_EQ(count(outcome.err, "error: "), 1u) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr("amg.toml: solver.preconditioner = \"amg\" runs in one process only, and this "
                                       "run has 2 (mpirun)"));
    EXPECT_FALSE(fs::exists(dir / "out")) << "nothing written for bad input";
}
#endif

TEST(MpirunRun, DivergenceOnOneProcessStopsAllWithThree)
{
    const fs::path dir = coro::test::scratch_dir("mpirun_divergence");
    const Outcome outcome =
        corocontact(2, "run " + DATA + "/diverging_pair.toml --quiet --out " + (dir / "out").string(), dir);
    EXPECT_EQ(outcome.exit_code, 3);
    EXPECT_EQ(count(outcome.err, "error: "), 1u) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr("step 2 (t = 0.02)"));
    EXPECT_THAT(outcome.err, HasSubstr("body 'soft': element"));
}

TEST(MpirunRun, TheFirstDivergingBodyInCaseOrderIsNamedAsByOneProcess)
{
    const fs::path dir = coro::test::scratch_dir("mpirun_two_diverging");
    std::string alone;
    for (const int ranks : {0, 2, 3}) {
        const Outcome outcome = corocontact(ranks, "run " + DATA + "/two_diverging.toml --quiet --out " +
                                                       (dir / std::to_string(ranks)).string(), dir);
        EXPECT_EQ(outcome.exit_code, 3);
        const std::vector<std::string> errors = lines_with(outcome.err, "error: ");
        ASSERT_EQ(errors.size(), 1u) << outcome.err;
        if (ranks == 0) {
            alone = errors[0];
            EXPECT_THAT(alone, HasSubstr("step 2 (t = 0.02): body 'soft_a': element"));
        } else {
            EXPECT_EQ(errors[0], alone) << ranks << " processes";
        }
    }
}

TEST(MpirunRun, CheckpointOfTwoProcessesContinuesOnThreeAndAlone)
{
    const fs::path dir = coro::test::scratch_dir("mpirun_restart");
    const std::string pile = DATA + "/touching_pile.toml";
    const fs::path one = dir / "one", three = dir / "three", alone = dir / "alone";
    Outcome outcome = corocontact(0, "run " + pile + " --quiet --out " + one.string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    for (const fs::path& out : {three, alone}) {
        outcome = corocontact(2, "run " + pile + " --steps 20 --checkpoint-every 10 --quiet --out " + out.string(), dir);
        ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
        EXPECT_THAT(outcome.out, HasSubstr("checkpoint: "));
    }
    const std::string checkpoint = "/touching_pile.checkpoint";
    outcome = corocontact(3, "run " + pile + " --quiet --restart " + three.string() + checkpoint + " --out " +
                                 three.string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.err, Not(HasSubstr("warning")));
    EXPECT_EQ(expect_same_frames(one, three), 4 * 13 + 4 + 1);
    outcome = corocontact(0, "run " + pile + " --quiet --restart " + alone.string() + checkpoint + " --out " +
                                 alone.string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_EQ(expect_same_frames(one, alone), 4 * 13 + 4 + 1);
}
