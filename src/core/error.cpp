#include <corocontact/core/error.hpp>

#include <filesystem>

namespace coro::detail {

std::string with_source_location(const std::string& message, const char* file, int line)
{
    return message + " [" + std::filesystem::path(file).filename().string() + ":" +
           std::to_string(line) + "]";
}

} // namespace coro::detail
