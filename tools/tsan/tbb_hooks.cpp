// Part of every executable of a TSan build (see README.md here): makes the hand-offs that
// Debian's uninstrumented libtbb does internally visible to ThreadSanitizer, where the ITT
// collector (itt_collector.cpp) cannot.
//
// oneTBB's headers call these exported libtbb functions from our (instrumented) code. Defining
// them in the executable takes those calls; each forwards to libtbb's own (dlsym RTLD_NEXT)
// and adds the edge that libtbb's atomics create but TSan cannot see:
//  - allocate/deallocate, the small-object pool of task objects: a task freed by one thread
//    goes back to its allocating thread's pool and is reused there. Release at free, acquire
//    at allocation (the address is the sync object).
//  - wait/execute_and_wait: the waiting thread returns once the wait_context's reference count,
//    decremented by the last finishing task (an atomic RMW in our code), reads zero; that
//    acquire load runs inside libtbb. Acquire every word of the wait_context after the wait
//    (the counter's position is private to TBB).
#include <oneapi/tbb/detail/_small_object_pool.h>
#include <oneapi/tbb/detail/_task.h>

#include <sanitizer/tsan_interface.h>

#include <dlfcn.h>

#include <cstddef>
#include <cstdio>
#include <cstdlib>

namespace {

using namespace tbb::detail;

// libtbb's definition of `symbol` (mangled name, oneTBB 2021 ABI).
template <class Fn>
Fn libtbb(const char* symbol)
{
    void* fn = dlsym(RTLD_NEXT, symbol);
    if (fn == nullptr) {
        std::fprintf(stderr, "tsan TBB hooks: %s not found in libtbb\n", symbol);
        std::abort();
    }
    return reinterpret_cast<Fn>(fn);
}

// Acquires every word of a wait_context when the wait returns, also when it rethrows a task's
// exception.
struct AcquireOnReturn {
    d1::wait_context& wait_ctx;
    ~AcquireOnReturn()
    {
        char* bytes = reinterpret_cast<char*>(&wait_ctx);
        for (std::size_t offset = 0; offset < sizeof(d1::wait_context); offset += sizeof(void*))
            __tsan_acquire(bytes + offset);
    }
};

} // namespace

namespace tbb::detail::r1 {

using Pool = d1::small_object_pool;

void* allocate(Pool*& pool, std::size_t bytes, const d1::execution_data& ed)
{
    static const auto real = libtbb<void* (*)(Pool*&, std::size_t, const d1::execution_data&)>(
        "_ZN3tbb6detail2r18allocateERPNS0_2d117small_object_poolEmRKNS2_14execution_dataE");
    void* object = real(pool, bytes, ed);
    __tsan_acquire(object);
    return object;
}

void* allocate(Pool*& pool, std::size_t bytes)
{
    static const auto real = libtbb<void* (*)(Pool*&, std::size_t)>(
        "_ZN3tbb6detail2r18allocateERPNS0_2d117small_object_poolEm");
    void* object = real(pool, bytes);
    __tsan_acquire(object);
    return object;
}

void deallocate(Pool& pool, void* object, std::size_t bytes, const d1::execution_data& ed)
{
    static const auto real = libtbb<void (*)(Pool&, void*, std::size_t, const d1::execution_data&)>(
        "_ZN3tbb6detail2r110deallocateERNS0_2d117small_object_poolEPvmRKNS2_14execution_dataE");
    __tsan_release(object);
    real(pool, object, bytes, ed);
}

void deallocate(Pool& pool, void* object, std::size_t bytes)
{
    static const auto real = libtbb<void (*)(Pool&, void*, std::size_t)>(
        "_ZN3tbb6detail2r110deallocateERNS0_2d117small_object_poolEPvm");
    __tsan_release(object);
    real(pool, object, bytes);
}

void execute_and_wait(d1::task& task, d1::task_group_context& task_ctx, d1::wait_context& wait_ctx,
                      d1::task_group_context& wait_group_ctx)
{
    static const auto real = libtbb<void (*)(d1::task&, d1::task_group_context&, d1::wait_context&,
                                             d1::task_group_context&)>(
        "_ZN3tbb6detail2r116execute_and_waitERNS0_2d14taskERNS2_18task_group_contextERNS2_12wait_contextES6_");
    const AcquireOnReturn acquire{wait_ctx};
    real(task, task_ctx, wait_ctx, wait_group_ctx);
}

void wait(d1::wait_context& wait_ctx, d1::task_group_context& ctx)
{
    static const auto real = libtbb<void (*)(d1::wait_context&, d1::task_group_context&)>(
        "_ZN3tbb6detail2r14waitERNS0_2d112wait_contextERNS2_18task_group_contextE");
    const AcquireOnReturn acquire{wait_ctx};
    real(wait_ctx, ctx);
}

} // namespace tbb::detail::r1
