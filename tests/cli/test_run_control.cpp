// The run command under stress: divergence, SIGINT/SIGTERM, SIGKILL at random moments, and
// checkpoint/restart producing frames bitwise equal to an uninterrupted run.

#include "cli_run.hpp"
#include "mesh_fixtures.hpp"
#include "series_check.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <csignal>
#include <random>
#include <regex>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using coro::test::expect_every_listed_frame_loads;
using coro::test::listed_frames;
using coro::test::Outcome;
using coro::test::run;
using coro::test::slurp;
using coro::test::spawn;
using coro::test::wait_for;
using coro::test::wait_for_frames;
using coro::test::wait_for_text;

namespace {

const std::string TWO_SPHERES = std::string(CORO_CASES_DIR) + "/two_spheres/two_spheres.toml";
// A block falling for 4 steps, frames at steps 0 and 4.
const std::string BLOCK = R"toml([simulation]
dt = 0.01
steps = 4
[[body]]
name = "block"
shape = "box"
min = [0.0, 0.0, 0.0]
max = [2.0, 1.0, 1.0]
cells = [4, 2, 2]
)toml";

// Every regular file under `a` (but the summary) exists under `b` with the same bytes; returns
// how many were compared. `from_step` > 0 compares only the frames of steps ≥ from_step.
int expect_same_files(const fs::path& a, const fs::path& b, long from_step = 0)
{
    const std::regex frame_step(".*_([0-9]{6,})(\\.vtm|/.*)$");
    int compared = 0;
    for (const auto& entry : fs::recursive_directory_iterator(a)) {
        const std::string relative = fs::relative(entry.path(), a).generic_string();
        if (!entry.is_regular_file() || entry.path().extension() == ".json" ||
            entry.path().extension() == ".checkpoint")
            continue;
        std::smatch match;
        const bool frame = std::regex_match(relative, match, frame_step);
        if (from_step > 0 && (!frame || std::stol(match[1]) < from_step))
            continue; // the .pvd of a run stopped between frames lists one frame more
        EXPECT_TRUE(fs::exists(b / relative)) << relative;
        EXPECT_TRUE(slurp(entry.path()) == slurp(b / relative)) << relative << " differs";
        ++compared;
    }
    return compared;
}

long summary_steps(const fs::path& summary)
{
    std::smatch match;
    const std::string text = slurp(summary);
    return std::regex_search(text, match, std::regex("\"steps\": ([0-9]+)")) ? std::stol(match[1]) : -1;
}

} // namespace

TEST(CorocontactDivergence, InvertedElementStopsWithExitThreeNamingStepBodyAndElement)
{
    const fs::path dir = coro::test::scratch_dir("cli_explode");
    const std::string case_file = std::string(CORO_CLI_DATA_DIR) + "/soft_block_hit_hard.toml";
    const Outcome outcome = run("run " + case_file + " --quiet --out " + (dir / "out").string(), dir);
    EXPECT_EQ(outcome.exit_code, 3) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr("the simulation diverged: step "));
    EXPECT_THAT(outcome.err, HasSubstr("body 'soft': element "));
    EXPECT_THAT(outcome.err, HasSubstr("inverted beyond recovery: det F = -"));
    // Steps 0 and 1 were written before step 2 diverged: they stay listed and load.
    EXPECT_THAT(outcome.err, HasSubstr("step 2 (t = 0.02): body 'soft': element 90 (mesh file order)"));
    EXPECT_EQ(expect_every_listed_frame_loads(dir / "out" / "soft_block_hit_hard.pvd", {"soft"}), 2);
}

TEST(CorocontactInterrupt, SigintAndSigtermFinishTheStepCloseTheSeriesAndExit130And143)
{
    for (const int signal_number : {SIGINT, SIGTERM}) {
        const std::string tag = signal_number == SIGINT ? "SIGINT" : "SIGTERM";
        const fs::path dir = coro::test::scratch_dir("cli_" + tag);
        const fs::path out = dir / "out";
        // Far more steps than the test waits for: only the signal ends it.
        const pid_t pid = spawn({"run", TWO_SPHERES, "--steps", "100000", "--threads", "1", "--out", out.string()}, dir);
        ASSERT_GT(pid, 0);
        ASSERT_TRUE(wait_for_frames(out / "two_spheres.pvd", 3, 60.0)) << tag;
        kill(pid, signal_number);
        const int status = wait_for(pid, 60.0);
        ASSERT_TRUE(WIFEXITED(status)) << tag << ": status " << status;
        EXPECT_EQ(WEXITSTATUS(status), 128 + signal_number) << tag;

        const std::string err = slurp(dir / "stderr.txt");
        std::smatch match;
        ASSERT_TRUE(std::regex_search(err, match, std::regex("interrupted by " + tag + " at step ([0-9]+)"))) << err;
        const long step = std::stol(match[1]);
        // The interrupted step's frame is the last listed, and the summary counts up to it.
        const std::vector<std::string> frames = listed_frames(out / "two_spheres.pvd");
        ASSERT_FALSE(frames.empty());
        char last[32];
        std::snprintf(last, sizeof last, "two_spheres_%06ld.vtm", step);
        EXPECT_EQ(frames.back(), last) << tag;
        EXPECT_EQ(summary_steps(out / "two_spheres.summary.json"), step) << tag;
        EXPECT_EQ(expect_every_listed_frame_loads(out / "two_spheres.pvd", {"left", "right"}),
                  static_cast<int>(frames.size()));
        for (const auto& entry : fs::recursive_directory_iterator(out))
            EXPECT_NE(entry.path().extension(), ".tmp") << entry.path();
    }
}

TEST(CorocontactInterrupt, KillNineAtRandomMomentsLeavesEveryListedFileLoadable)
{
    const fs::path dir = coro::test::scratch_dir("cli_kill9");
    const fs::path out = dir / "out";
    std::mt19937 random(20261121);
    std::uniform_int_distribution<int> delay_ms(0, 900);
    int frames_checked = 0;
    for (int kill_number = 0; kill_number < 8; ++kill_number) {
        // The same directory every time: leftovers of earlier kills must not hurt either.
        const pid_t pid = spawn({"run", TWO_SPHERES, "--steps", "100000", "--threads", "1",
                                 "--checkpoint-every", "7", "--out", out.string()},
                                dir);
        ASSERT_GT(pid, 0);
        // Each kill waits for its run's own first frames, so that the check below does not
        // depend on how fast this build runs (under ASan the first frame can take longer than
        // the random delays). A later run first takes over the killed run's lock and removes its
        // series (the .pvd first, so what is listed always exists): it says so before its first
        // frame.
        if (kill_number > 0) {
            ASSERT_TRUE(wait_for_text(dir / "stderr.txt", "of an earlier run of two_spheres", 120.0))
                << slurp(dir / "stderr.txt");
        }
        ASSERT_TRUE(wait_for_frames(out / "two_spheres.pvd", kill_number == 0 ? 2 : 1, 120.0));
        std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms(random)));
        kill(pid, SIGKILL);
        const int status = wait_for(pid, 30.0);
        ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "kill " << kill_number;
        if (kill_number > 0) {
            EXPECT_THAT(slurp(dir / "stderr.txt"), HasSubstr("taking over the lock of a run that ended without "
                                                             "removing it"));
        }
        frames_checked += expect_every_listed_frame_loads(out / "two_spheres.pvd", {"left", "right"});
    }
    EXPECT_GT(frames_checked, 8) << "the kills should have hit runs that had written frames";
}

TEST(CorocontactRestart, ContinuedRunWritesFramesBitwiseEqualToAnUninterruptedRun)
{
    const fs::path dir = coro::test::scratch_dir("cli_restart");
    const std::string a = (dir / "a").string(), b = (dir / "b").string();
    // Contact starts at about step 20: the checkpoint at 30 carries a contact state.
    Outcome outcome = run("run " + TWO_SPHERES + " --steps 40 --quiet --out " + a, dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    outcome = run("run " + TWO_SPHERES + " --steps 30 --checkpoint-every 10 --quiet --out " + b, dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.out, HasSubstr("checkpoint: "));
    outcome = run("run " + TWO_SPHERES + " --steps 40 --threads 1 --quiet --restart " + b +
                      "/two_spheres.checkpoint --out " + b,
                  dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    // Every frame file (0..40) and the .pvd, which lists all 9 frames.
    EXPECT_EQ(expect_same_files(a, b), 1 + 9 * 3);
    EXPECT_EQ(listed_frames(fs::path(b) / "two_spheres.pvd").size(), 9u);
    EXPECT_EQ(summary_steps(fs::path(b) / "two_spheres.summary.json"), 40);
}

TEST(CorocontactRestart, AfterSigtermContinuesBitwise)
{
    const fs::path dir = coro::test::scratch_dir("cli_restart_sigterm");
    const fs::path b = dir / "b";
    const pid_t pid =
        spawn({"run", TWO_SPHERES, "--steps", "100000", "--checkpoint-every", "1000000", "--out", b.string()}, dir);
    ASSERT_GT(pid, 0);
    ASSERT_TRUE(wait_for_frames(b / "two_spheres.pvd", 4, 60.0));
    kill(pid, SIGTERM);
    const int status = wait_for(pid, 60.0);
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 143) << status;
    const long stopped = summary_steps(b / "two_spheres.summary.json");
    ASSERT_GT(stopped, 0);

    const std::string last = std::to_string(stopped + 12);
    Outcome outcome = run("run " + TWO_SPHERES + " --steps " + last + " --quiet --restart " +
                              (b / "two_spheres.checkpoint").string() + " --out " + b.string(),
                          dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    outcome = run("run " + TWO_SPHERES + " --steps " + last + " --quiet --out " + (dir / "a").string(), dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_GE(expect_same_files(dir / "a", b, stopped + 1), 3 * 2); // at least 2 frames after the stop
    EXPECT_EQ(summary_steps(b / "two_spheres.summary.json"), stopped + 12);
}

TEST(CorocontactRestart, BadCheckpointsExitWithTwo)
{
    const fs::path dir = coro::test::scratch_dir("cli_restart_bad");
    const fs::path case_file = coro::test::write_text(dir / "block.toml", BLOCK);
    const std::string out = (dir / "o").string();
    ASSERT_EQ(run("run " + case_file.string() + " --steps 2 --checkpoint-every 1 --quiet --out " + out, dir).exit_code, 0);
    const fs::path checkpoint = fs::path(out) / "block.checkpoint";
    ASSERT_TRUE(fs::exists(checkpoint));

    const std::string bytes = slurp(checkpoint);
    coro::test::write_text(dir / "truncated.checkpoint", bytes.substr(0, bytes.size() - 100));
    Outcome outcome = run("run " + case_file.string() + " --quiet --restart " + (dir / "truncated.checkpoint").string() +
                              " --out " + out,
                          dir);
    EXPECT_EQ(outcome.exit_code, 2);
    EXPECT_THAT(outcome.err, HasSubstr("truncated.checkpoint: truncated or corrupt checkpoint"));

    outcome = run("run " + TWO_SPHERES + " --quiet --restart " + checkpoint.string() + " --out " +
                      (dir / "other").string(),
                  dir);
    EXPECT_EQ(outcome.exit_code, 2);
    EXPECT_THAT(outcome.err, HasSubstr("written by another case file"));
    EXPECT_FALSE(fs::exists(dir / "other")) << "nothing written for a rejected restart";

    outcome = run("run " + case_file.string() + " --steps 2 --quiet --restart " + checkpoint.string() + " --out " + out,
                  dir);
    EXPECT_EQ(outcome.exit_code, 2);
    EXPECT_THAT(outcome.err, HasSubstr("nothing to continue"));

    outcome = run("run " + case_file.string() + " --quiet --restart " + (dir / "absent.checkpoint").string(), dir);
    EXPECT_EQ(outcome.exit_code, 2);
    EXPECT_THAT(outcome.err, HasSubstr("absent.checkpoint"));

    outcome = run("run " + case_file.string() + " --quiet --restart " + checkpoint.string() + " --out " + out, dir);
    EXPECT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_EQ(summary_steps(fs::path(out) / "block.summary.json"), 4);
}

TEST(CorocontactRestart, AFrameThatIsNoLongerAFileIsLeftOutWithAWarning)
{
    const fs::path dir = coro::test::scratch_dir("cli_restart_frame_dir");
    std::string every_step = BLOCK;
    every_step.insert(every_step.find("[[body]]"), "output_every = 1\n");
    const fs::path case_file = coro::test::write_text(dir / "block.toml", every_step);
    const fs::path out = dir / "o";
    ASSERT_EQ(run("run " + case_file.string() + " --steps 2 --checkpoint-every 2 --quiet --out " + out.string(), dir)
                  .exit_code,
              0);
    // Frame 1's .vtm replaced by a folder of that name: not a frame, so left out (once it made
    // the restart fail after the earlier run's .pvd and summary were removed).
    fs::remove(out / "block_000001.vtm");
    fs::create_directory(out / "block_000001.vtm");
    const Outcome outcome = run("run " + case_file.string() + " --quiet --restart " +
                                    (out / "block.checkpoint").string() + " --out " + out.string(),
                                dir);
    ASSERT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_THAT(outcome.err, HasSubstr("1 of the 3 frames the first run wrote up to step 2 are not in"));
    EXPECT_EQ(listed_frames(out / "block.pvd").size(), 4u); // 0, 2, 3, 4
    EXPECT_EQ(summary_steps(out / "block.summary.json"), 4);
}
