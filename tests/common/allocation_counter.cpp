#include "allocation_counter.hpp"

#include <atomic>
#include <cstdlib>

namespace {
std::atomic<bool> g_counting{false};
std::atomic<std::size_t> g_allocations{0};

void count_one()
{
    if (g_counting.load(std::memory_order_relaxed))
        g_allocations.fetch_add(1, std::memory_order_relaxed);
}
} // namespace

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
// The sanitizer owns malloc; it calls these hooks for every allocation and release.
// Declared here: GCC ships the sanitizer runtime but not this header (clang's does).
extern "C" int __sanitizer_install_malloc_and_free_hooks(
    void (*on_allocate)(const volatile void*, std::size_t), void (*on_release)(const volatile void*));

namespace {
void on_allocate(const volatile void*, std::size_t) { count_one(); }
void on_release(const volatile void*) {}
const int g_hooks_installed = __sanitizer_install_malloc_and_free_hooks(on_allocate, on_release);
} // namespace
#else
// glibc's allocator under its own names; operator new comes here through malloc.
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* pointer, std::size_t size);
void __libc_free(void* pointer);

void* malloc(std::size_t size)
{
    count_one();
    return __libc_malloc(size);
}

void* calloc(std::size_t count, std::size_t size)
{
    count_one();
    return __libc_calloc(count, size);
}

void* realloc(void* pointer, std::size_t size)
{
    count_one();
    return __libc_realloc(pointer, size);
}

void free(void* pointer) { __libc_free(pointer); }
}
#endif

namespace coro::test {

AllocationCounter::AllocationCounter()
{
    g_allocations = 0;
    g_counting = true;
}

AllocationCounter::~AllocationCounter() { g_counting = false; }

std::size_t AllocationCounter::count() const { return g_allocations.load(); }

bool AllocationCounter::active() const
{
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
    return g_hooks_installed != 0;
#else
    return true;
#endif
}

} // namespace coro::test
