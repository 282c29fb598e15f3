#pragma once
// Running the corocontact binary from a test: its exit code and output, started in the
// background and stopped, and the frames its .pvd lists.

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

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
inline Outcome run(const std::string& arguments, const std::filesystem::path& dir, const std::string& environment = "",
                   const std::string& launcher = "")
{
    const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    const std::string command = (environment.empty() ? "" : "env " + environment + " ") +
                                (launcher.empty() ? "" : launcher + " ") + std::string(CORO_CLI_PATH) +
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

// Starts the binary with `arguments` (stdout, stderr to files in `dir`); returns its pid.
inline pid_t spawn(const std::vector<std::string>& arguments, const std::filesystem::path& dir)
{
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    const std::string out = (dir / "stdout.txt").string(), err = (dir / "stderr.txt").string();
    posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    std::vector<std::string> args{CORO_CLI_PATH};
    args.insert(args.end(), arguments.begin(), arguments.end());
    std::vector<char*> argv;
    for (std::string& a : args)
        argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid = -1;
    const int error = posix_spawn(&pid, CORO_CLI_PATH, &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    return error == 0 ? pid : -1;
}

// Waits for the child, at most `seconds` (then kills it and returns −1); the raw wait status.
inline int wait_for(pid_t pid, double seconds)
{
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    int status = 0;
    while (waitpid(pid, &status, WNOHANG) == 0) {
        if (std::chrono::steady_clock::now() > deadline) {
            kill(pid, SIGKILL);
            waitpid(pid, &status, 0);
            return -1;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return status;
}

// Waits until `file` contains `text` (false after `seconds`).
inline bool wait_for_text(const std::filesystem::path& file, const std::string& text, double seconds)
{
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < deadline) {
        if (slurp(file).find(text) != std::string::npos)
            return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
}

// Waits until the .pvd lists at least `frames` frames (false after `seconds`).
inline bool wait_for_frames(const std::filesystem::path& pvd, std::size_t frames, double seconds)
{
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < deadline) {
        if (listed_frames(pvd).size() >= frames)
            return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
}

} // namespace coro::test
