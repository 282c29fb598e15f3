#pragma once
/// @file allocation_counter.hpp
/// @brief Counts the heap allocations (malloc, calloc, realloc, operator new) the whole process
/// makes while a counter is alive. Link allocation_counter.cpp into a test executable of its
/// own: without a sanitizer it replaces malloc (forwarding to glibc's), under ASan or TSan it
/// installs the sanitizer's allocation hook.

#include <cstddef>

namespace coro::test {

/// Counts allocations from construction to destruction (one counter at a time).
class AllocationCounter {
public:
    AllocationCounter();
    ~AllocationCounter();
    AllocationCounter(const AllocationCounter&) = delete;
    AllocationCounter& operator=(const AllocationCounter&) = delete;

    /// Allocations so far.
    std::size_t count() const;
    /// False if the counting could not be installed (a sanitizer refused the hook).
    bool active() const;
};

} // namespace coro::test
