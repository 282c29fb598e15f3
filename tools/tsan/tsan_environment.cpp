// Part of every executable of a TSan build (see README.md here): the same TSan settings however
// the executable is run (tools/test.sh --tsan, plain ctest in build-tsan/, or by hand).
#include <cstdlib>

#ifndef CORO_TSAN_ITT_COLLECTOR
#error "CORO_TSAN_ITT_COLLECTOR must name the ITT collector library (tools/tsan/CMakeLists.txt)"
#endif
#ifndef CORO_TSAN_SUPPRESSIONS
#error "CORO_TSAN_SUPPRESSIONS must name tools/tsan.supp (tools/tsan/CMakeLists.txt)"
#endif

// Read by the TSan runtime before anything else runs; TSAN_OPTIONS adds to and overrides it.
// halt_on_error: the first report ends the process (exit code 66), so it fails its test.
extern "C" __attribute__((visibility("default"))) const char* __tsan_default_options()
{
    return "halt_on_error=1:second_deadlock_stack=1:suppressions=" CORO_TSAN_SUPPRESSIONS;
}

namespace {

// Before any TBB or VTK code runs (an already set variable is kept):
//  - INTEL_LIBITTNOTIFY64 = the ITT collector, so that it and tbb_hooks.cpp are always used
//    together. libtbb reads it when its scheduler starts.
//  - VTK_SMP_BACKEND_IN_USE = Sequential: Debian's VTK runs its own loops (e.g. array ranges in
//    the VTU writer) on TBB, in uninstrumented code that notifies nothing, so a block that VTK
//    allocates on a TBB worker and frees on the main thread shows as a race. VTK 9.1 reads it
//    at its first SMP call.
__attribute__((constructor)) void set_environment()
{
    setenv("INTEL_LIBITTNOTIFY64", CORO_TSAN_ITT_COLLECTOR, /*overwrite=*/0);
    setenv("VTK_SMP_BACKEND_IN_USE", "Sequential", /*overwrite=*/0);
}

} // namespace
