#pragma once
// Private to io/: how much memory a scene will need, estimated from its tet count before the
// allocations that count drives, and how much this process may have.

#include <corocontact/sim/case_spec.hpp>

#include <string>
#include <utility>

namespace coro::detail {

/// Memory a running body needs per tet: the peak RSS of dynamic box runs of 48 k to 1.3 M tets
/// grows by 568 bytes per tet (2026-11-26), rounded up. Contact trees and embedded surfaces add
/// less than the estimate's margin for such bodies.
constexpr double BYTES_PER_TET = 600.0;

/// The memory this process may use, and what sets it.
struct MemoryLimit {
    double bytes = 0.0;
    std::string source; ///< "physical memory", "the address-space limit (ulimit -v)", ...
};

/// The smallest of the machine's physical memory, the address-space and data-segment limits
/// (setrlimit) and the control group's memory.max, where set.
MemoryLimit memory_limit();

/// "23.4 GB", "640 MB" for a byte count.
std::string memory_text(double bytes);

/// Tets a generated body will have (0 for a mesh file, whose count is known once it is read),
/// and how the case says it ("cells = [2, 2, 2]").
std::pair<double, std::string> generated_tets(const BodySpec& spec);

/// Refuses a scene of `total_tets` that cannot fit in memory(), before the allocations it
/// drives; `cause` ("case.toml:5: body 'block': cells = [..]") says what brought the total there.
/// @throws InputError naming `cause`, the memory needed and the limit with its source
void check_memory(double total_tets, const std::string& cause);

} // namespace coro::detail
