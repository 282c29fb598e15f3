#pragma once
// Running the corocontact binary from a test: its exit code and output, and the frames its
// .pvd lists.

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace coro::test {

struct Outcome {
    int exit_code;
    std::string out;
    std::string err;
};

inline std::string slurp(const std::filesystem::path& path)
{
    std::ifstream file(path);
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
}

/// Runs `corocontact ARGUMENTS` in the shell, stdout and stderr kept in `dir`; `environment`
/// (e.g. "CORO_DEBUG=1") is set for that command only.
inline Outcome run(const std::string& arguments, const std::filesystem::path& dir, const std::string& environment = "")
{
    const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    const std::string command = (environment.empty() ? "" : "env " + environment + " ") + std::string(CORO_CLI_PATH) +
                                " " + arguments + " > " + out.string() + " 2> " + err.string() + " < /dev/null";
    const int status = std::system(command.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

// Every .vtm the .pvd lists, in order.
inline std::vector<std::string> listed_frames(const std::filesystem::path& pvd)
{
    const std::string text = slurp(pvd);
    std::vector<std::string> files;
    const std::regex entry("file=\"([^\"]+)\"");
    for (auto it = std::sregex_iterator(text.begin(), text.end(), entry); it != std::sregex_iterator(); ++it)
        files.push_back((*it)[1]);
    return files;
}

} // namespace coro::test
