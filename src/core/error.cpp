#include <corocontact/core/error.hpp>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace coro {
namespace {

bool shown_by_environment()
{
    const char* value = std::getenv("CORO_DEBUG");
    return value != nullptr && std::strcmp(value, "") != 0 && std::strcmp(value, "0") != 0;
}

std::atomic<bool>& shown()
{
    static std::atomic<bool> flag{shown_by_environment()};
    return flag;
}

} // namespace

void set_source_locations_shown(bool shown_now) { shown().store(shown_now); }

bool source_locations_shown() { return shown().load(); }

namespace detail {

std::string with_source_location(const std::string& message, const char* file, int line)
{
    if (!source_locations_shown())
        return message;
    return message + " [" + std::filesystem::path(file).filename().string() + ":" + std::to_string(line) + "]";
}

} // namespace detail
} // namespace coro
