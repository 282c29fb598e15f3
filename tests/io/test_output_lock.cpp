// One run per output folder: the lock refuses a second holder at once and names the first,
// takes over the lock file of a run that ended without removing it, and leaves nothing behind.

#include <corocontact/io/output_lock.hpp>

#include <corocontact/core/error.hpp>

#include "mesh_fixtures.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

namespace coro {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::ThrowsMessage;

std::string slurp(const fs::path& path)
{
    std::ifstream in(path);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

TEST(OutputLock, ASecondHolderIsRefusedAtOnceAndToldWhoHoldsIt)
{
    const fs::path dir = test::scratch_dir("lock_second") / "out";
    std::optional<OutputLock> first;
    first.emplace(dir, "corocontact run first.toml");
    EXPECT_TRUE(fs::is_directory(dir));
    const std::string text = slurp(first->path());
    EXPECT_THAT(text, HasSubstr("pid " + std::to_string(getpid()) + "\n"));
    EXPECT_THAT(text, HasSubstr("command corocontact run first.toml\n"));
    EXPECT_THAT(first->stale_owner(), IsEmpty());
    // flock(2) locks belong to an open file description: a second open in this process is
    // refused like another process would be.
    EXPECT_THAT([&] { OutputLock second(dir, "corocontact run second.toml"); },
                ThrowsMessage<OutputError>(AllOf(HasSubstr(dir.string() + ": the output folder is in use by another run"),
                                                 HasSubstr("(pid " + std::to_string(getpid()) + " on host "),
                                                 HasSubstr(": corocontact run first.toml; lock file"))));
    EXPECT_EQ(slurp(first->path()), text) << "the refused run must not touch the holder's lock file";
    first.reset();
    EXPECT_FALSE(fs::exists(dir / "corocontact.lock"));
    EXPECT_FALSE(fs::exists(dir)) << "the lock made the empty folder, so it removes it";
    OutputLock third(dir, "corocontact run third.toml"); // free again
    EXPECT_THAT(third.stale_owner(), IsEmpty());
}

TEST(OutputLock, IsHeldAgainstAnotherProcess)
{
    const fs::path dir = test::scratch_dir("lock_process");
    const OutputLock lock(dir, "corocontact run parent.toml");
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        // The child inherits no lock of its own: taking one must fail. No gtest here.
        int code = 0;
        try {
            OutputLock other(dir, "child");
            code = 1;
        } catch (const OutputError& error) {
            code = std::string(error.what()).find("corocontact run parent.toml") != std::string::npos ? 0 : 2;
        }
        _exit(code);
    }
    int status = 0;
    waitpid(child, &status, 0);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << "1: the child got the lock, 2: the message did not name the holder";
}

TEST(OutputLock, TakesOverTheLockFileOfARunThatNoLongerHoldsIt)
{
    // What a run killed with SIGKILL leaves: the lock file, no lock on it.
    const fs::path dir = test::scratch_dir("lock_stale");
    test::write_text(dir / "corocontact.lock",
                     "pid 4242\nhost elsewhere\nstarted 2026-11-26 10:00:00 UTC\ncommand corocontact run old.toml\n");
    const OutputLock lock(dir, "corocontact run new.toml");
    EXPECT_EQ(lock.stale_owner(), "pid 4242 on host elsewhere, started 2026-11-26 10:00:00 UTC: corocontact run old.toml");
    EXPECT_THAT(slurp(lock.path()), AllOf(HasSubstr("pid " + std::to_string(getpid()) + "\n"),
                                          HasSubstr("command corocontact run new.toml\n")));
    EXPECT_THAT(slurp(lock.path()), ::testing::Not(HasSubstr("4242")));
}

TEST(OutputLock, RemovesEveryEmptyFolderItMade)
{
    const fs::path dir = test::scratch_dir("lock_nested");
    { const OutputLock lock(dir / "a" / "b" / "c", "x"); }
    EXPECT_FALSE(fs::exists(dir / "a"));
    EXPECT_TRUE(fs::is_directory(dir));
    {
        const OutputLock lock(dir / "a" / "b" / "c", "x");
        test::write_text(dir / "a" / "note.txt", "written while the lock was held");
    }
    EXPECT_FALSE(fs::exists(dir / "a" / "b"));
    EXPECT_TRUE(fs::is_regular_file(dir / "a" / "note.txt"));
}

TEST(OutputLock, KeepsAFolderThatExistedOrWasWrittenTo)
{
    const fs::path dir = test::scratch_dir("lock_keep");
    { const OutputLock lock(dir, "x"); }
    EXPECT_TRUE(fs::is_directory(dir)) << "the folder existed before";
    const fs::path made = dir / "made";
    {
        const OutputLock lock(made, "x");
        test::write_text(made / "result.pvd", "x");
    }
    EXPECT_TRUE(fs::is_regular_file(made / "result.pvd"));
    EXPECT_FALSE(fs::exists(made / "corocontact.lock"));
}

TEST(OutputLock, AFolderThatCannotBeMadeIsAnOutputErrorWithTheReason)
{
    const fs::path file = test::write_text(test::scratch_dir("lock_file") / "plain", "x");
    EXPECT_THAT([&] { OutputLock lock(file / "out", "x"); },
                ThrowsMessage<OutputError>(AllOf(HasSubstr((file / "out").string() + ": cannot create the output folder"),
                                                 HasSubstr("(Not a directory)"))));
    EXPECT_THAT([&] { OutputLock lock(file, "x"); },
                ThrowsMessage<OutputError>(HasSubstr(file.string() + ": cannot create the output folder")));
}

} // namespace
} // namespace coro
