#include <corocontact/io/run_files.hpp>

#include <corocontact/core/error.hpp>

#include <algorithm>
#include <cctype>
#include <optional>
#include <string_view>
#include <system_error>
#include <vector>

namespace fs = std::filesystem;

namespace coro {
namespace {

constexpr std::string_view TMP = ".tmp";

bool ends_with(std::string_view text, std::string_view end)
{
    return text.size() >= end.size() && text.substr(text.size() - end.size()) == end;
}

/// The step of a frame's file or folder name, `NAME_<digits><suffix>` (suffix ".vtm",
/// ".vtm.tmp" or "" for the folder); nothing for any other name.
std::optional<long long> frame_step(std::string_view file, const std::string& name, std::string_view suffix)
{
    if (file.size() <= name.size() + 1 + suffix.size() || file.substr(0, name.size()) != name ||
        file[name.size()] != '_' || !ends_with(file, suffix))
        return std::nullopt;
    const std::string_view digits = file.substr(name.size() + 1, file.size() - name.size() - 1 - suffix.size());
    if (digits.size() > 18 || !std::all_of(digits.begin(), digits.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }))
        return std::nullopt;
    return std::stoll(std::string(digits));
}

/// Removes `path` if it exists; counts it.
void remove_file(const fs::path& path, RemovedFiles& removed)
{
    std::error_code ec;
    const bool done = fs::remove(path, ec);
    CORO_CHECK(!ec, OutputError, path.string() << ": cannot remove this file of an earlier run (" << ec.message() << ")");
    if (done)
        ++removed.files;
}

/// Removes the .vtu files (and their temporaries) of a frame folder, then the folder if
/// nothing else is in it.
void remove_frame_folder(const fs::path& folder, RemovedFiles& removed)
{
    std::error_code ec;
    std::vector<fs::path> blocks;
    for (const fs::directory_entry& entry : fs::directory_iterator(folder, ec)) {
        const std::string file = entry.path().filename().string();
        if (entry.is_regular_file(ec) && (ends_with(file, ".vtu") || ends_with(file, ".vtu.tmp")))
            blocks.push_back(entry.path());
    }
    for (const fs::path& block : blocks)
        remove_file(block, removed);
    if (fs::is_empty(folder, ec))
        fs::remove(folder, ec);
}

} // namespace

fs::path summary_path(const fs::path& dir, const std::string& name) { return dir / (name + ".summary.json"); }

fs::path checkpoint_path(const fs::path& dir, const std::string& name) { return dir / (name + ".checkpoint"); }

RemovedFiles remove_earlier_run(const fs::path& dir, const std::string& name, Index keep_through_step,
                                bool keep_checkpoint)
{
    RemovedFiles removed;
    const fs::path pvd = dir / (name + ".pvd");
    remove_file(pvd, removed);
    remove_file(fs::path(pvd).concat(TMP), removed);

    std::vector<fs::path> frames, folders;
    std::error_code ec;
    for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
        const std::string file = entry.path().filename().string();
        if (entry.is_directory(ec)) {
            const auto step = frame_step(file, name, "");
            if (step && *step > keep_through_step)
                folders.push_back(entry.path());
            continue;
        }
        const auto step = frame_step(file, name, ".vtm");
        const auto temporary = frame_step(file, name, ".vtm.tmp");
        if ((step && *step > keep_through_step) || temporary)
            frames.push_back(entry.path());
    }
    CORO_CHECK(!ec, OutputError, dir.string() << ": cannot list the output folder (" << ec.message() << ")");
    for (const fs::path& frame : frames) {
        remove_file(frame, removed);
        if (!ends_with(frame.filename().string(), TMP))
            ++removed.frames;
    }
    for (const fs::path& folder : folders)
        remove_frame_folder(folder, removed);

    const fs::path checkpoint = checkpoint_path(dir, name);
    for (const fs::path& file : {summary_path(dir, name), checkpoint}) {
        if (file == checkpoint && !keep_checkpoint) {
            const Index before = removed.files;
            remove_file(file, removed);
            removed.checkpoint = removed.files > before;
        } else if (file != checkpoint) {
            remove_file(file, removed);
        }
        remove_file(fs::path(file).concat(TMP), removed);
    }
    return removed;
}

} // namespace coro
