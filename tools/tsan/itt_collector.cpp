// An ITT notify collector that turns oneTBB's synchronisation notifications into
// ThreadSanitizer happens-before edges (TSan builds only; see README.md here).
//
// libtbb.so.12 carries the static half of Intel's ITT notify API. When INTEL_LIBITTNOTIFY64
// names a shared library, TBB dlopen()s it at scheduler start-up; a library that exports
// __itt_api_init is handed the table of ITT function pointers to fill. We fill two:
//   __itt_sync_releasing(p) -> __tsan_release(p)
//   __itt_sync_acquired(p)  -> __tsan_acquire(p)
// and leave the rest (prepare, cancel, create, destroy, tasks, frames...) as no-ops. The
// __tsan_* functions come from the TSan runtime of the executable that loads us.
#include <sanitizer/tsan_interface.h>

#include <pthread.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace {

// The leading members of ittnotify's __itt_api_info and __itt_global (ittnotify_config.h,
// ITT API 3.x as built into oneTBB 2021): only these are read.
struct IttApiInfo {
    const char* name;
    void** func_ptr;
    void* init_func;
    void* null_func;
    int group;
};

struct IttGlobal {
    unsigned char magic[8];
    unsigned long version_major;
    unsigned long version_minor;
    unsigned long version_build;
    volatile long api_initialized;
    volatile long mutex_initialized;
    volatile long atomic_counter;
    pthread_mutex_t mutex;
    void* lib;
    void* error_handler;
    const char** dll_path_ptr;
    IttApiInfo* api_list_ptr;
};

constexpr unsigned char ITT_MAGIC[8] = {0xED, 0xAB, 0xAB, 0xEC, 0x0D, 0xEE, 0xDA, 0x30};

void sync_releasing(void* addr) { __tsan_release(addr); }
void sync_acquired(void* addr) { __tsan_acquire(addr); }

[[noreturn]] void fail(const char* what)
{
    std::fprintf(stderr, "tsan ITT collector: %s; TSan would report races that are not there\n", what);
    std::abort();
}

} // namespace

// Called once per library with ITT built in (libtbb, and libtbbmalloc when TBB loads it).
extern "C" __attribute__((visibility("default"))) void __itt_api_init(IttGlobal* global, int /*groups*/)
{
    if (std::memcmp(global->magic, ITT_MAGIC, sizeof ITT_MAGIC) != 0 || global->version_major != 3)
        fail("unknown ITT API layout (expected ITT 3.x as in oneTBB 2021)");
    bool releasing = false, acquired = false;
    for (IttApiInfo* api = global->api_list_ptr; api->name != nullptr; ++api) {
        if (std::strcmp(api->name, "__itt_sync_releasing") == 0) {
            *api->func_ptr = reinterpret_cast<void*>(&sync_releasing);
            releasing = true;
        } else if (std::strcmp(api->name, "__itt_sync_acquired") == 0) {
            *api->func_ptr = reinterpret_cast<void*>(&sync_acquired);
            acquired = true;
        }
    }
    if (!releasing || !acquired)
        fail("__itt_sync_releasing or __itt_sync_acquired is missing from the ITT table");
}
