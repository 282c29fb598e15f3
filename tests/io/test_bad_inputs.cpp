// The bad-input corpus (tests/data/bad, listed in expected.tsv) through the real `corocontact`
// command: each entry must exit with its code, print a message that names the file and the
// line, byte or element, let no VTK text through, and write nothing.

#include "mesh_fixtures.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace coro {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::Not;
using ::testing::StartsWith;

fs::path corpus_dir() { return fs::path(CORO_TEST_DATA_DIR) / "bad"; }

std::string slurp(const fs::path& path)
{
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

/// One line of expected.tsv.
struct Entry {
    std::string file;
    std::string command; // info | run | detect
    int exit_code = 0;
    std::string message;
    int line = 0; // in expected.tsv, for failure messages
};

/// How gtest shows an entry: "file command".
void PrintTo(const Entry& entry, std::ostream* os) { *os << entry.file << " " << entry.command; }

std::vector<Entry> read_manifest()
{
    std::vector<Entry> entries;
    std::istringstream text(slurp(corpus_dir() / "expected.tsv"));
    std::string line;
    for (int number = 1; std::getline(text, line); ++number) {
        if (line.empty() || line.front() == '#')
            continue;
        std::vector<std::string> fields;
        std::istringstream columns(line);
        for (std::string field; std::getline(columns, field, '\t');)
            fields.push_back(field);
        if (fields.size() != 4)
            throw std::runtime_error("expected.tsv:" + std::to_string(number) +
                                     ": expected 4 tab-separated columns, found " +
                                     std::to_string(fields.size()));
        entries.push_back({fields[0], fields[1], std::stoi(fields[2]), fields[3], number});
    }
    return entries;
}

/// A test name from "file command": letters and digits, the rest as '_'.
std::string entry_name(const ::testing::TestParamInfo<Entry>& info)
{
    std::string name = info.param.file + "_" + info.param.command;
    for (char& c : name)
        if (std::isalnum(static_cast<unsigned char>(c)) == 0)
            c = '_';
    return name;
}

struct Outcome {
    int exit_code = -1;
    std::string out;
    std::string err;
};

Outcome run_cli(const std::string& arguments, const fs::path& dir)
{
    const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    const std::string command = std::string(CORO_CLI_PATH) + " " + arguments + " > '" +
                                out.string() + "' 2> '" + err.string() + "' < /dev/null";
    const int status = std::system(command.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

class BadInput : public ::testing::TestWithParam<Entry> {};

TEST_P(BadInput, ExitsWithItsCodeNamesTheLocationAndWritesNothing)
{
    const Entry& entry = GetParam();
    SCOPED_TRACE("expected.tsv:" + std::to_string(entry.line) + ": " + entry.file);
    const fs::path dir = test::scratch_dir("bad_" + entry_name({entry, 0}));
    const fs::path out = dir / "out";
    std::string arguments = entry.command + " '" + (corpus_dir() / entry.file).string() + "'";
    if (entry.command == "run")
        arguments += " --out '" + out.string() + "' --steps 1 --quiet";
    else if (entry.command == "detect")
        arguments += " --csv '" + (out / "contacts.csv").string() + "'";
    else
        ASSERT_EQ(entry.command, "info") << "unknown command in expected.tsv";

    const Outcome outcome = run_cli(arguments, dir);
    EXPECT_EQ(outcome.exit_code, entry.exit_code) << outcome.err;
    EXPECT_THAT(outcome.err, StartsWith("error: "));
    EXPECT_THAT(outcome.err, HasSubstr(entry.message));
    EXPECT_THAT(outcome.err, Not(HasSubstr("ERROR: In "))) << "VTK printed its own message";
    EXPECT_THAT(outcome.err, Not(HasSubstr("Warning: In "))) << "VTK printed its own message";
    EXPECT_THAT(outcome.out, IsEmpty());
    EXPECT_FALSE(fs::exists(out)) << out << " was created";
}

INSTANTIATE_TEST_SUITE_P(Corpus, BadInput, ::testing::ValuesIn(read_manifest()), entry_name);

TEST(BadInputCorpus, HasAtLeastThirtyFilesAndListsEveryOne)
{
    const std::vector<Entry> entries = read_manifest();
    std::set<std::string> listed;
    std::set<std::string> tetgen_stems; // a listed .node or .ele covers its other half
    std::string cases_text;
    for (const Entry& entry : entries) {
        listed.insert(entry.file);
        const fs::path path(entry.file);
        if (path.extension() == ".node" || path.extension() == ".ele")
            tetgen_stems.insert(path.stem().string());
        if (fs::path(entry.file).extension() == ".toml" &&
            fs::is_regular_file(corpus_dir() / entry.file))
            cases_text += slurp(corpus_dir() / entry.file);
    }
    std::size_t files = 0;
    for (const fs::directory_entry& item : fs::directory_iterator(corpus_dir())) {
        const std::string name = item.path().filename().string();
        if (name == "expected.tsv" || name == "make_corpus.py" || name == "README.md")
            continue;
        ++files;
        const std::string extension = item.path().extension().string();
        const bool tetgen_half = (extension == ".node" || extension == ".ele") &&
                                 tetgen_stems.count(item.path().stem().string()) > 0;
        const bool covered = listed.count(name) > 0 || tetgen_half ||
                             cases_text.find('"' + name + '"') != std::string::npos;
        EXPECT_TRUE(covered) << name << " is in the corpus but neither listed in expected.tsv "
                                        "nor named by a listed case file";
    }
    EXPECT_GE(files, 30u);
    EXPECT_GE(entries.size(), 30u);
}

} // namespace
} // namespace coro
