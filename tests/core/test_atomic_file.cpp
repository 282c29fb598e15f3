// Files written whole or not at all, with the system's reason when they cannot be.

#include "mesh_fixtures.hpp"

#include <corocontact/core/atomic_file.hpp>
#include <corocontact/core/error.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

using namespace coro;
namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

namespace {

std::string slurp(const fs::path& path)
{
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

bool any_temporary(const fs::path& dir)
{
    for (const fs::directory_entry& entry : fs::recursive_directory_iterator(dir))
        if (entry.path().extension() == ".tmp")
            return true;
    return false;
}

} // namespace

TEST(WriteFileAtomically, ReplacesTheFileWholeAndLeavesNoTemporary)
{
    const fs::path dir = test::scratch_dir("atomic_replace");
    const fs::path file = dir / "series.pvd";
    for (const Sync sync : {Sync::FILE, Sync::NONE}) {
        write_file_atomically(file, "first version, longer than the second\n", sync);
        write_file_atomically(file, "second\n", sync);
        EXPECT_EQ(slurp(file), "second\n");
        EXPECT_FALSE(any_temporary(dir));
    }
    write_file_atomically(file, std::string("\0binary\0", 8));
    EXPECT_EQ(slurp(file), std::string("\0binary\0", 8));
}

TEST(WriteFileAtomically, NamesThePathAndTheSystemsReasonAndLeavesTheOldFile)
{
    const fs::path dir = test::scratch_dir("atomic_fail");
    const fs::path regular = test::write_text(dir / "a_file", "not a folder\n");
    EXPECT_THAT([&] { write_file_atomically(regular / "x.pvd", "text"); },
                ThrowsMessage<OutputError>(AllOf(HasSubstr((regular / "x.pvd").string() + ": cannot create x.pvd.tmp"),
                                                 HasSubstr("(Not a directory)"))));
    // A rename onto a folder fails after the temporary was written: the temporary goes again.
    fs::create_directories(dir / "folder.pvd");
    EXPECT_THAT([&] { write_file_atomically(dir / "folder.pvd", "text"); },
                ThrowsMessage<OutputError>(AllOf(HasSubstr("folder.pvd: cannot rename folder.pvd.tmp into place"),
                                                 HasSubstr("(Is a directory)"))));
    EXPECT_FALSE(any_temporary(dir));
    EXPECT_EQ(slurp(regular), "not a folder\n");
}

TEST(CommitFile, MovesAFinishedTemporaryOrRemovesIt)
{
    const fs::path dir = test::scratch_dir("atomic_commit");
    const fs::path target = dir / "block.vtu";
    test::write_text(temporary_path(target), "block\n");
    commit_file(temporary_path(target), target);
    EXPECT_EQ(slurp(target), "block\n");
    EXPECT_FALSE(fs::exists(temporary_path(target)));

    fs::create_directories(dir / "taken.vtu" / "inside");
    test::write_text(temporary_path(dir / "taken.vtu"), "block\n");
    EXPECT_THAT([&] { commit_file(temporary_path(dir / "taken.vtu"), dir / "taken.vtu"); },
                ThrowsMessage<OutputError>(HasSubstr("taken.vtu: cannot rename taken.vtu.tmp into place")));
    EXPECT_FALSE(any_temporary(dir));
}
