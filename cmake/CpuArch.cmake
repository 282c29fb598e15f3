# CORO_ARCH: the instruction set of Release builds. "auto" (the default) picks x86-64-v3
# (AVX2 + FMA: the element kernels and PCG's products run about 30 % fewer instructions)
# when the building machine runs it, and the compiler's baseline otherwise; valgrind runs
# x86-64-v3 binaries, unlike -march=native ones on AVX-512 machines. "none" keeps the
# compiler's baseline; any other value is passed to -march=. CORO_NATIVE overrides it.
set(CORO_ARCH "auto" CACHE STRING "Release instruction set: auto | none | an -march= value")

if(CORO_NATIVE)
  # Every translation unit, tests included, so that Eigen's fixed-size types agree on alignment.
  string(APPEND CMAKE_CXX_FLAGS_RELEASE " -march=native")
  return()
endif()

set(_coro_march "")
if(CORO_ARCH STREQUAL "auto")
  if(CMAKE_SYSTEM_PROCESSOR MATCHES "x86_64|AMD64")
    include(CheckCXXSourceRuns)
    set(CMAKE_REQUIRED_FLAGS "-march=x86-64-v3")
    check_cxx_source_runs([=[
      int main() {
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
               __builtin_cpu_supports("bmi2") ? 0 : 1;
      }]=] CORO_HOST_RUNS_X86_64_V3)
    unset(CMAKE_REQUIRED_FLAGS)
    if(CORO_HOST_RUNS_X86_64_V3)
      set(_coro_march "x86-64-v3")
    endif()
  endif()
elseif(NOT CORO_ARCH STREQUAL "none")
  set(_coro_march "${CORO_ARCH}")
endif()

if(_coro_march)
  # Every translation unit, tests included, so that Eigen's fixed-size types agree on alignment.
  string(APPEND CMAKE_CXX_FLAGS_RELEASE " -march=${_coro_march}")
  message(STATUS "corocontact: Release builds use -march=${_coro_march} (CORO_ARCH=${CORO_ARCH})")
endif()
