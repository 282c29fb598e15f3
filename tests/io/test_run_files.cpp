// What an earlier run of a series left in the output folder goes before a new run writes
// there; everything else stays.

#include <corocontact/io/run_files.hpp>

#include "mesh_fixtures.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

namespace coro {
namespace {

namespace fs = std::filesystem;

/// Every file and folder under `dir`, relative, sorted.
std::vector<std::string> listing(const fs::path& dir)
{
    std::vector<std::string> names;
    for (const fs::directory_entry& entry : fs::recursive_directory_iterator(dir))
        names.push_back(fs::relative(entry.path(), dir).generic_string());
    std::sort(names.begin(), names.end());
    return names;
}

/// A folder as two runs of series "run" and one of series "run_b" leave it, plus a user's files.
fs::path earlier_runs(const std::string& tag)
{
    const fs::path dir = test::scratch_dir(tag);
    for (const char* file :
         {"run.pvd", "run.pvd.tmp", "run.summary.json", "run.summary.json.tmp", "run.checkpoint",
          "run.checkpoint.tmp", "run_000000.vtm", "run_000005.vtm", "run_000010.vtm", "run_000015.vtm.tmp",
          "run_000000/a.vtu", "run_000005/a.vtu", "run_000010/a.vtu", "run_000010/b.vtu.tmp",
          "run_b.pvd", "run_b.summary.json", "run_b_000000.vtm", "run_b_000000/a.vtu", "notes.txt",
          "run_000005/my_notes.txt", "run_x.vtm"})
        test::write_text(dir / file, "x");
    return dir;
}

TEST(RemoveEarlierRun, AFreshRunRemovesEveryFileOfItsSeriesAndNothingElse)
{
    const fs::path dir = earlier_runs("run_files_fresh");
    const RemovedFiles removed = remove_earlier_run(dir, "run", -1, false);
    EXPECT_EQ(listing(dir), (std::vector<std::string>{"notes.txt", "run_000005", "run_000005/my_notes.txt", "run_b.pvd",
                                                      "run_b.summary.json", "run_b_000000", "run_b_000000.vtm",
                                                      "run_b_000000/a.vtu", "run_x.vtm"}));
    EXPECT_EQ(removed.frames, 3);
    EXPECT_EQ(removed.files, 14);
    EXPECT_TRUE(removed.checkpoint);
}

TEST(RemoveEarlierRun, ARestartKeepsItsFramesUpToTheCheckpointAndTheCheckpoint)
{
    const fs::path dir = earlier_runs("run_files_restart");
    const RemovedFiles removed = remove_earlier_run(dir, "run", 5, true);
    const std::vector<std::string> left = listing(dir);
    for (const char* kept : {"run_000000.vtm", "run_000000/a.vtu", "run_000005.vtm", "run_000005/a.vtu", "run.checkpoint"})
        EXPECT_NE(std::find(left.begin(), left.end(), kept), left.end()) << kept;
    for (const char* gone : {"run.pvd", "run.summary.json", "run_000010.vtm", "run_000010", "run_000015.vtm.tmp",
                             "run.checkpoint.tmp", "run.pvd.tmp"})
        EXPECT_EQ(std::find(left.begin(), left.end(), gone), left.end()) << gone;
    EXPECT_EQ(removed.frames, 1);
    EXPECT_FALSE(removed.checkpoint);
}

TEST(RemoveEarlierRun, AnEmptyOrForeignFolderIsLeftAsItIs)
{
    const fs::path dir = test::scratch_dir("run_files_empty");
    EXPECT_EQ(remove_earlier_run(dir, "run", -1, false).files, 0);
    test::write_text(dir / "other.pvd", "x");
    EXPECT_EQ(remove_earlier_run(dir, "run", -1, false).files, 0);
    EXPECT_EQ(listing(dir), std::vector<std::string>{"other.pvd"});
}

TEST(RunFiles, NamesTheSummaryAndTheCheckpointAfterTheSeries)
{
    EXPECT_EQ(summary_path("out", "pile"), fs::path("out/pile.summary.json"));
    EXPECT_EQ(checkpoint_path("out", "pile"), fs::path("out/pile.checkpoint"));
}

} // namespace
} // namespace coro
