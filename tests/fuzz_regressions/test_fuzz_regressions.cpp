// Every fuzz seed and every input that once crashed a fuzz target (tests/data/fuzz_regressions/
// <target>/<file>) goes through the fuzz harness's reader call: it must be read, or rejected
// with InputError; a crash, a sanitizer report or any other exception fails the test.
#include "fuzz_input.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

struct Input {
    std::string target; // fuzz target name: msh, tetgen, obj, stl, off, case, scene
    fs::path file;
    std::string kind; // "seed" or "regression"
};

std::vector<Input> all_inputs()
{
    std::vector<Input> inputs;
    const std::vector<std::pair<fs::path, std::string>> roots{
        {CORO_FUZZ_CORPUS_DIR, "seed"},
        {fs::path(CORO_TEST_DATA_DIR) / "fuzz_regressions", "regression"}};
    for (const auto& [root, kind] : roots) {
        if (!fs::is_directory(root))
            continue;
        for (const auto& target_dir : fs::directory_iterator(root)) {
            if (!target_dir.is_directory())
                continue;
            for (const auto& file : fs::directory_iterator(target_dir.path()))
                if (file.is_regular_file())
                    inputs.push_back({target_dir.path().filename().string(), file.path(), kind});
        }
    }
    std::sort(inputs.begin(), inputs.end(),
              [](const Input& a, const Input& b) { return a.file < b.file; });
    return inputs;
}

std::string test_name(const testing::TestParamInfo<Input>& info)
{
    std::string name = info.param.kind + "_" + info.param.target + "_" +
                       info.param.file.filename().string();
    for (char& c : name)
        if (std::isalnum(static_cast<unsigned char>(c)) == 0)
            c = '_';
    return name;
}

/// What a failing test prints as its parameter: the file, not the struct's bytes.
void PrintTo(const Input& input, std::ostream* os) { *os << input.file.string(); }

class FuzzInput : public testing::TestWithParam<Input> {};

TEST_P(FuzzInput, IsReadOrRejectedWithInputError)
{
    const Input& input = GetParam();
    std::ifstream stream(input.file, std::ios::binary);
    ASSERT_TRUE(stream) << input.file;
    const std::string bytes((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
    std::string message;
    const auto outcome = coro::fuzz::feed(coro::fuzz::target_from_name(input.target),
                                          reinterpret_cast<const std::uint8_t*>(bytes.data()),
                                          bytes.size(), &message);
    EXPECT_NE(outcome, coro::fuzz::Outcome::NUMERICAL_ERROR)
        << input.file << ": bad input should be an InputError, got a NumericalError: " << message;
    if (outcome == coro::fuzz::Outcome::INPUT_ERROR) {
        EXPECT_FALSE(message.empty()) << input.file;
    }
}

INSTANTIATE_TEST_SUITE_P(Corpus, FuzzInput, testing::ValuesIn(all_inputs()), test_name);

} // namespace
