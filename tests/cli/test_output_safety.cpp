// The run command's output folder: one run at a time (a lock file), exit 4 with the path and
// the system's reason when the output cannot be written, no temporary left behind, no file of
// an earlier run of the series beside the new one; counts from the command line never wrap.

#include "cli_run.hpp"
#include "mesh_fixtures.hpp"
#include "series_check.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <csignal>
#include <regex>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::Not;
using ::testing::StartsWith;
using coro::test::expect_every_listed_frame_loads;
using coro::test::listed_frames;
using coro::test::Outcome;
using coro::test::run;
using coro::test::slurp;
using coro::test::spawn;
using coro::test::wait_for;
using coro::test::wait_for_frames;

namespace {

const std::string TWO_SPHERES = std::string(CORO_CASES_DIR) + "/two_spheres/two_spheres.toml";
const std::string OVERLAP = std::string(CORO_CASES_DIR) + "/overlap/overlap.toml"; // 663 contact rows
const std::string RING_MESH = std::string(CORO_CASES_DIR) + "/ring/ring.msh";

/// Every temporary file under `dir`.
std::vector<std::string> temporaries(const fs::path& dir)
{
    std::vector<std::string> found;
    if (fs::exists(dir))
        for (const fs::directory_entry& entry : fs::recursive_directory_iterator(dir))
            if (entry.path().extension() == ".tmp")
                found.push_back(entry.path().string());
    return found;
}

long summary_steps(const fs::path& summary)
{
    std::smatch match;
    const std::string text = slurp(summary);
    return std::regex_search(text, match, std::regex("\"steps\": ([0-9]+)")) ? std::stol(match[1]) : -1;
}

/// Runs the command under bash with a file-size limit of `kib` KiB: a write failure anywhere, also
/// as root. SIGXFSZ is given its default action (killing the process) here, for the command to
/// inherit whatever the test runner set: the command ignores it itself, so that the write fails
/// with EFBIG, as on a full disk.
Outcome run_with_file_size_limit(long kib, const std::string& arguments, const fs::path& dir)
{
    const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    std::signal(SIGXFSZ, SIG_DFL); // an ignored signal stays ignored across exec: bash could not undo it
    const std::string command = "bash -c \"ulimit -f " + std::to_string(kib) + "; exec " +
                                CORO_CLI_PATH + " " + arguments + "\" > " + out.string() + " 2> " + err.string() +
                                " < /dev/null";
    const int status = std::system(command.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

} // namespace

TEST(CorocontactOutputFolder, ASecondRunIntoTheSameFolderRefusesAtOnceNamingTheFirst)
{
    const fs::path dir = coro::test::scratch_dir("cli_two_runs");
    const fs::path out = dir / "out";
    const fs::path first_dir = dir / "first";
    fs::create_directories(first_dir);
    const pid_t first = spawn({"run", TWO_SPHERES, "--steps", "100000", "--threads", "1", "--quiet", "--out", out.string()},
                              first_dir);
    ASSERT_GT(first, 0);
    ASSERT_TRUE(wait_for_frames(out / "two_spheres.pvd", 2, 120.0));

    // The same case and another one (another series), into the same folder: both refused.
    const auto start = std::chrono::steady_clock::now();
    Outcome second = run("run " + TWO_SPHERES + " --steps 5 --quiet --out " + out.string(), dir);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(second.exit_code, 4) << second.err;
    EXPECT_THAT(second.err, AllOf(HasSubstr(out.string() + ": the output folder is in use by another run (pid " +
                                            std::to_string(first) + " on host "),
                                  HasSubstr(", started "), HasSubstr("corocontact run " + TWO_SPHERES),
                                  HasSubstr("lock file " + (out / "corocontact.lock").string())));
    EXPECT_THAT(second.out, IsEmpty());
    EXPECT_LT(seconds, 5.0) << "refused before loading, not after";
    const fs::path other = coro::test::write_text(dir / "other.toml", "[[body]]\nshape = \"box\"\n");
    second = run("run " + other.string() + " --steps 2 --quiet --out " + out.string(), dir);
    EXPECT_EQ(second.exit_code, 4) << second.err;
    EXPECT_FALSE(fs::exists(out / "other.pvd"));

    // The first run was not disturbed: its series holds only its own frames, all loadable.
    kill(first, SIGTERM);
    const int status = wait_for(first, 60.0);
    ASSERT_TRUE(WIFEXITED(status)) << status;
    EXPECT_EQ(WEXITSTATUS(status), 143);
    const std::vector<std::string> frames = listed_frames(out / "two_spheres.pvd");
    ASSERT_FALSE(frames.empty());
    char last[40];
    std::snprintf(last, sizeof last, "two_spheres_%06ld.vtm", summary_steps(out / "two_spheres.summary.json"));
    EXPECT_EQ(frames.back(), last) << "the summary and the series are the first run's";
    EXPECT_EQ(expect_every_listed_frame_loads(out / "two_spheres.pvd", {"left", "right"}),
              static_cast<int>(frames.size()));
    EXPECT_FALSE(fs::exists(out / "corocontact.lock")) << "the first run removes its lock when it ends";

    // Once the first run has ended, the folder is free again.
    second = run("run " + TWO_SPHERES + " --steps 5 --quiet --out " + out.string(), dir);
    EXPECT_EQ(second.exit_code, 0) << second.err;
}

TEST(CorocontactOutputFolder, ALockLeftByAKilledRunIsTakenOver)
{
    const fs::path dir = coro::test::scratch_dir("cli_stale_lock");
    const fs::path out = dir / "out";
    const pid_t killed = spawn({"run", TWO_SPHERES, "--steps", "100000", "--threads", "1", "--quiet", "--out", out.string()},
                               dir);
    ASSERT_GT(killed, 0);
    ASSERT_TRUE(wait_for_frames(out / "two_spheres.pvd", 1, 120.0));
    kill(killed, SIGKILL);
    wait_for(killed, 30.0);
    ASSERT_TRUE(fs::exists(out / "corocontact.lock"));

    const Outcome outcome = run("run " + TWO_SPHERES + " --steps 5 --quiet --out " + out.string(), dir);
    EXPECT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr("warning: " + (out / "corocontact.lock").string() +
                                       ": taking over the lock of a run that ended without removing it (pid " +
                                       std::to_string(killed)));
}

TEST(CorocontactOutputFolder, ARerunReplacesTheEarlierRunsSeriesWhole)
{
    const fs::path dir = coro::test::scratch_dir("cli_rerun");
    const std::string out = (dir / "out").string();
    ASSERT_EQ(run("run " + TWO_SPHERES + " --steps 20 --quiet --out " + out, dir).exit_code, 0);
    ASSERT_EQ(listed_frames(fs::path(out) / "two_spheres.pvd").size(), 5u);

    Outcome outcome = run("run " + TWO_SPHERES + " --steps 7 --out " + out, dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr("(5 frames) of an earlier run of two_spheres from " + out));
    EXPECT_EQ(listed_frames(fs::path(out) / "two_spheres.pvd"),
              (std::vector<std::string>{"two_spheres_000000.vtm", "two_spheres_000005.vtm", "two_spheres_000007.vtm"}));
    EXPECT_EQ(summary_steps(fs::path(out) / "two_spheres.summary.json"), 7);
    for (const char* stale : {"two_spheres_000010.vtm", "two_spheres_000010", "two_spheres_000020.vtm"})
        EXPECT_FALSE(fs::exists(fs::path(out) / stale)) << stale;

    // A rerun that fails part way leaves its own frames, and no summary of the earlier run.
    outcome = run_with_file_size_limit(900, "run " + TWO_SPHERES + " --steps 20 --quiet --checkpoint-every 6 --out " + out,
                                       dir);
    EXPECT_EQ(outcome.exit_code, 4) << outcome.err;
    EXPECT_FALSE(fs::exists(fs::path(out) / "two_spheres.summary.json"));
    EXPECT_EQ(listed_frames(fs::path(out) / "two_spheres.pvd"),
              (std::vector<std::string>{"two_spheres_000000.vtm", "two_spheres_000005.vtm"}));
    EXPECT_FALSE(fs::exists(fs::path(out) / "two_spheres_000007.vtm")) << "a frame of the earlier run";
}

TEST(CorocontactOutputFailure, ExitsFourNamingThePathAndTheSystemsReasonAndLeavesNoTemporary)
{
    const fs::path dir = coro::test::scratch_dir("cli_output_failure");
    const fs::path out = dir / "out";
    // A block file (about 630 kB) fits under the limit, the checkpoint (about 1.5 MB) does not.
    Outcome outcome = run_with_file_size_limit(
        900, "run " + TWO_SPHERES + " --steps 20 --quiet --checkpoint-every 7 --out " + out.string(), dir);
    EXPECT_EQ(outcome.exit_code, 4) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr("error: " + (out / "two_spheres.checkpoint").string() +
                                       ": cannot write (File too large)"));
    EXPECT_THAT(temporaries(out), IsEmpty());
    const std::vector<std::string> frames = listed_frames(out / "two_spheres.pvd");
    EXPECT_EQ(frames.size(), 2u) << "frames 0 and 5, written before the checkpoint at step 7";
    EXPECT_EQ(expect_every_listed_frame_loads(out / "two_spheres.pvd", {"left", "right"}), 2);
    EXPECT_FALSE(fs::exists(out / "two_spheres.summary.json"));
    EXPECT_FALSE(fs::exists(out / "corocontact.lock"));

    // Not even a block file fits: the first frame fails, and the folder the run made goes again.
    const fs::path none = dir / "none";
    outcome = run_with_file_size_limit(200, "run " + TWO_SPHERES + " --steps 20 --quiet --out " + none.string(), dir);
    EXPECT_EQ(outcome.exit_code, 4) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr((none / "two_spheres_000000" / "left.vtu").string() +
                                       ": VTK cannot write block 'left' (File too large)"));
    EXPECT_FALSE(fs::exists(none));
}

TEST(CorocontactOutputFailure, AnOutputFolderThatCannotBeMadeExitsFour)
{
    const fs::path dir = coro::test::scratch_dir("cli_output_folder");
    const fs::path file = coro::test::write_text(dir / "a_file", "x");
    Outcome outcome = run("run " + TWO_SPHERES + " --steps 2 --quiet --out " + (file / "out").string(), dir);
    EXPECT_EQ(outcome.exit_code, 4);
    EXPECT_THAT(outcome.err, HasSubstr((file / "out").string() + ": cannot create the output folder (Not a directory)"));
    // detect --csv writes through the same path.
    outcome = run("detect " + TWO_SPHERES + " --csv " + (file / "contacts.csv").string(), dir);
    EXPECT_EQ(outcome.exit_code, 4);
    EXPECT_THAT(outcome.err, HasSubstr((file / "contacts.csv").string() + ": cannot create contacts.csv.tmp (Not a directory)"));
}

TEST(CorocontactOutputFailure, AFailedWriteToStandardOutputExitsFour)
{
    // /dev/full takes the bytes and fails every write with ENOSPC, as a full disk does.
    ASSERT_TRUE(fs::is_character_file("/dev/full")) << "this test needs /dev/full (Linux)";
    const fs::path dir = coro::test::scratch_dir("cli_stdout_full");
    for (const std::string& arguments :
         {"run " + TWO_SPHERES + " --steps 2 --quiet --out " + (dir / "o").string(), "detect " + OVERLAP,
          "detect " + OVERLAP + " --csv -", "info " + RING_MESH, "info " + RING_MESH + " --parts 2",
          std::string("--help")}) {
        const std::string command = std::string(CORO_CLI_PATH) + " " + arguments + " > /dev/full 2> " +
                                    (dir / "err.txt").string() + " < /dev/null";
        const int status = std::system(command.c_str());
        ASSERT_TRUE(WIFEXITED(status)) << arguments;
        EXPECT_EQ(WEXITSTATUS(status), 4) << arguments;
        EXPECT_THAT(slurp(dir / "err.txt"), HasSubstr("error: writing to standard output: No space left on device"))
            << arguments;
    }
}

TEST(CorocontactDetect, CsvIntoANamedPipeOrThroughASymlinkLeavesThemWhatTheyAre)
{
    const fs::path dir = coro::test::scratch_dir("cli_csv_targets");
    const fs::path regular = dir / "regular.csv";
    Outcome outcome = run("detect " + OVERLAP + " --csv " + regular.string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    const std::string rows = slurp(regular);
    ASSERT_THAT(rows, StartsWith("body,vertex,other,depth\n"));

    // A named pipe, read as the command writes: the reader gets the rows, the pipe stays a pipe.
    const fs::path fifo = dir / "contacts.fifo";
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    std::string received;
    std::thread reader([&] { received = slurp(fifo); });
    outcome = run("detect " + OVERLAP + " --csv " + fifo.string(), dir);
    // If the command never opened the pipe, the reader still waits for a writer: be that writer.
    if (const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK); fd >= 0)
        ::close(fd);
    reader.join();
    EXPECT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_TRUE(fs::is_fifo(fs::symlink_status(fifo)));
    EXPECT_EQ(received, rows);

    // A symlink: its target gets the rows, the link stays a link.
    const fs::path target = coro::test::write_text(dir / "target.csv", "old\n");
    const fs::path link = dir / "link.csv";
    fs::create_symlink(target, link);
    outcome = run("detect " + OVERLAP + " --csv " + link.string(), dir);
    EXPECT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_TRUE(fs::is_symlink(fs::symlink_status(link)));
    EXPECT_EQ(slurp(target), rows);
    EXPECT_THAT(temporaries(dir), IsEmpty());
}

TEST(CorocontactCommandLine, CountsBeyondAnIndexAreRefusedNotWrapped)
{
    const fs::path dir = coro::test::scratch_dir("cli_wrap");
    // 2^32 + 1 steps would wrap to 1 step, 2^32 checkpoints to none.
    Outcome outcome = run("run " + TWO_SPHERES + " --steps 4294967297 --quiet --out " + (dir / "o").string(), dir);
    EXPECT_EQ(outcome.exit_code, 2);
    EXPECT_THAT(outcome.err, HasSubstr("--steps: expected a whole number from 1 to 2147483647, found '4294967297'"));
    outcome = run("run " + TWO_SPHERES + " --checkpoint-every 4294967296 --quiet --out " + (dir / "o").string(), dir);
    EXPECT_EQ(outcome.exit_code, 2);
    EXPECT_THAT(outcome.err,
                HasSubstr("--checkpoint-every: expected a whole number from 1 to 2147483647, found '4294967296'"));
    EXPECT_FALSE(fs::exists(dir / "o"));
}

TEST(CorocontactCommandLine, StepsOfAStaticCaseAreNotSilentlyIgnored)
{
    const fs::path dir = coro::test::scratch_dir("cli_static_steps");
    const fs::path case_file = coro::test::write_text(
        dir / "static.toml", "[simulation]\nanalysis = \"static\"\nload_steps = 2\n[[body]]\nshape = \"box\"\n"
                             "[[body.fixed]]\nmax = [0.0, 1e9, 1e9]\n");
    Outcome outcome = run("run " + case_file.string() + " --steps 7 --quiet --out " + (dir / "o").string(), dir);
    EXPECT_EQ(outcome.exit_code, 2);
    EXPECT_THAT(outcome.err, HasSubstr("--steps 7: " + case_file.string() +
                                       " is a static analysis, whose steps are simulation.load_steps"));
    EXPECT_FALSE(fs::exists(dir / "o"));
    outcome = run("run " + case_file.string() + " --quiet --out " + (dir / "o").string(), dir);
    EXPECT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.err, Not(HasSubstr("note:")));

    // The time-step keys in a static case file: a note names them, and the run goes on.
    const fs::path with_steps = coro::test::write_text(
        dir / "static_steps.toml", "[simulation]\nanalysis = \"static\"\nload_steps = 2\nsteps = 3\ndt = 0.1\n"
                                   "output_every = 7\n[[body]]\nshape = \"box\"\n[[body.fixed]]\nmax = [0.0, 1e9, 1e9]\n");
    outcome = run("run " + with_steps.string() + " --quiet --out " + (dir / "o2").string(), dir);
    EXPECT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr("note: " + with_steps.string() +
                                       ":5:1: simulation.dt, simulation.steps and simulation.output_every are not used "
                                       "by a static analysis, which has no time steps: it runs simulation.load_steps = "
                                       "2 load steps and writes every one\n"));
    EXPECT_EQ(listed_frames(dir / "o2" / "static_steps.pvd").size(), 3u) << "load steps 0, 1 and 2";
}

// Not in ASan or TSan builds: an instrumented command reserves terabytes of address space for its
// shadow memory at start, so it cannot start under an address-space limit at all (the plain
// suite runs this test).
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
TEST(CorocontactLoad, ASceneBeyondTheMemoryLimitIsRefusedNamingTheKey)
{
    // 6 million tets need about 3.6 GB at the estimate's 600 bytes per tet (a run measures
    // about 570): refused under a 2.5 GB address-space limit before anything is allocated.
    const fs::path dir = coro::test::scratch_dir("cli_memory");
    const fs::path case_file = coro::test::write_text(
        dir / "big.toml", "[[body]]\nname = \"big\"\nshape = \"box\"\ncells = [100, 100, 100]\n");
    const std::string command = "bash -c \"ulimit -v 2500000; exec " + std::string(CORO_CLI_PATH) + " run " +
                                case_file.string() + " --steps 1 --quiet --out " + (dir / "o").string() + "\" 2> " +
                                (dir / "err.txt").string();
    const int status = std::system(command.c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 2);
    EXPECT_THAT(slurp(dir / "err.txt"),
                AllOf(HasSubstr("big.toml:1: body 'big': cells = [100, 100, 100]: the scene would have 6000000 tets, "
                                "which need about 3.6 GB of memory"),
                      HasSubstr("more than the 2.6 GB of the address-space limit (ulimit -v)")));
    EXPECT_FALSE(fs::exists(dir / "o"));
}
#endif

TEST(CorocontactLoad, ObstaclesWithoutContactAreNamedAsIneffective)
{
    const fs::path dir = coro::test::scratch_dir("cli_no_contact");
    const fs::path case_file = coro::test::write_text(
        dir / "floor.toml", "[simulation]\nsteps = 1\n[[body]]\nshape = \"box\"\n\n[[obstacle]]\ntype = \"plane\"\n");
    const Outcome outcome = run("run " + case_file.string() + " --quiet --out " + (dir / "o").string(), dir);
    EXPECT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr("warning: " + case_file.string() +
                                       ":6: the obstacles have no effect, because contact.enabled is false"));
}
