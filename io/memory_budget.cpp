#include "detail/memory_budget.hpp"

#include <corocontact/core/error.hpp>

#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>

namespace coro::detail {
namespace {

/// Lowers `limit` to `bytes` (if smaller) and names its `source`.
void lower(MemoryLimit& limit, double bytes, const char* source)
{
    if (bytes > 0.0 && bytes < limit.bytes) {
        limit.bytes = bytes;
        limit.source = source;
    }
}

double rlimit_bytes(int resource)
{
    rlimit value{};
    if (getrlimit(resource, &value) != 0 || value.rlim_cur == RLIM_INFINITY)
        return 0.0;
    return static_cast<double>(value.rlim_cur);
}

/// The first number in `file`, or 0 ("max", absent, unreadable: no limit).
double number_in(const std::string& file)
{
    std::ifstream in(file);
    double value = 0.0;
    return in >> value ? value : 0.0;
}

/// The memory limit of this process's control group: cgroup v2 `memory.max`, or v1
/// `memory.limit_in_bytes` (a huge value when unlimited); 0 if there is none.
double cgroup_bytes()
{
    std::ifstream groups("/proc/self/cgroup");
    double bytes = 0.0;
    for (std::string line; std::getline(groups, line);) {
        const std::size_t colon = line.find(':'), second = line.find(':', colon + 1);
        if (colon == std::string::npos || second == std::string::npos)
            continue;
        const std::string controllers = line.substr(colon + 1, second - colon - 1), path = line.substr(second + 1);
        double here = 0.0;
        if (controllers.empty())
            here = number_in("/sys/fs/cgroup" + path + "/memory.max");
        else if (controllers == "memory")
            here = number_in("/sys/fs/cgroup/memory" + path + "/memory.limit_in_bytes");
        if (here > 0.0 && (bytes == 0.0 || here < bytes))
            bytes = here;
    }
    return bytes;
}

} // namespace

MemoryLimit memory_limit()
{
    MemoryLimit limit;
    limit.bytes = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE));
    limit.source = "physical memory";
    lower(limit, rlimit_bytes(RLIMIT_AS), "the address-space limit (ulimit -v)");
    lower(limit, rlimit_bytes(RLIMIT_DATA), "the data-segment limit (ulimit -d)");
    lower(limit, cgroup_bytes(), "the memory limit of its control group (memory.max)");
    return limit;
}

std::string memory_text(double bytes)
{
    char text[32];
    if (bytes >= 1e9)
        std::snprintf(text, sizeof text, "%.1f GB", bytes / 1e9);
    else
        std::snprintf(text, sizeof text, "%.0f MB", bytes / 1e6);
    return text;
}

std::pair<double, std::string> generated_tets(const BodySpec& spec)
{
    if (spec.shape == BodyShape::BOX) {
        const auto& c = spec.cells;
        return {6.0 * c[0] * c[1] * c[2], "cells = [" + std::to_string(c[0]) + ", " + std::to_string(c[1]) + ", " +
                                             std::to_string(c[2]) + "]"};
    }
    if (spec.shape == BodyShape::SPHERE) {
        const double r = spec.resolution;
        return {6.0 * r * r * r, "resolution = " + std::to_string(spec.resolution)};
    }
    return {0.0, ""};
}

void check_memory(double total_tets, const std::string& cause)
{
    const MemoryLimit limit = memory_limit();
    const double need = total_tets * BYTES_PER_TET;
    CORO_CHECK(need <= limit.bytes, InputError,
               cause << ": the scene would have " << static_cast<long long>(total_tets) << " tets, which need about "
                     << memory_text(need) << " of memory (" << BYTES_PER_TET
                     << " bytes per tet), more than the " << memory_text(limit.bytes) << " of "
                     << limit.source);
}

} // namespace coro::detail
