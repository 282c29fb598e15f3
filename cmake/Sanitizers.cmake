# Sanitizer and fuzzing instrumentation for every target of the project (included from the
# top-level CMakeLists.txt before any target is defined).
#
# CORO_SANITIZE   "" (off), "address,undefined" or "thread": adds -fsanitize=<value> and
#                 -fno-omit-frame-pointer to every compile and link; with "undefined" also
#                 -fno-sanitize-recover=undefined, so a UBSan report fails the test that hit it.
# CORO_FUZZ       builds the libFuzzer targets in fuzz/ (clang only): every target is compiled
#                 with -fsanitize=fuzzer-no-link,address,undefined (coverage for the fuzzer,
#                 ASan and UBSan for the findings); the fuzz executables link -fsanitize=fuzzer.
# Third-party libraries (TBB, VTK, Embree, METIS) come from Debian and are not instrumented;
# for "thread", tools/tsan makes TBB's task hand-offs visible to TSan (tools/tsan/README.md).

set(CORO_SANITIZE "" CACHE STRING
    "Sanitizers for every target: \"\" (none), \"address,undefined\" or \"thread\"")
set_property(CACHE CORO_SANITIZE PROPERTY STRINGS "" "address,undefined" "thread")
option(CORO_FUZZ "Build the libFuzzer targets in fuzz/ (needs clang; implies ASan+UBSan)" OFF)

if(CORO_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "CORO_FUZZ=ON needs clang (libFuzzer); configure with "
                        "-DCMAKE_CXX_COMPILER=clang++ (tools/fuzz.sh does)")
  endif()
  if(CORO_SANITIZE AND NOT CORO_SANITIZE STREQUAL "address,undefined")
    message(FATAL_ERROR "CORO_FUZZ=ON builds with address,undefined; CORO_SANITIZE='${CORO_SANITIZE}' "
                        "cannot be combined with it")
  endif()
  set(CORO_SANITIZE "address,undefined")
endif()

if(CORO_SANITIZE)
  if(NOT CORO_SANITIZE MATCHES "^(address,undefined|undefined,address|address|undefined|thread)$")
    message(FATAL_ERROR "CORO_SANITIZE='${CORO_SANITIZE}': expected \"\", \"address,undefined\" or \"thread\"")
  endif()
  add_compile_options(-fsanitize=${CORO_SANITIZE} -fno-omit-frame-pointer)
  add_link_options(-fsanitize=${CORO_SANITIZE})
  if(CORO_SANITIZE MATCHES "undefined")
    add_compile_options(-fno-sanitize-recover=undefined)
  endif()
  if(CORO_FUZZ)
    add_compile_options(-fsanitize=fuzzer-no-link)
  endif()
  if(CORO_SANITIZE STREQUAL "thread")
    # oneTBB's headers then tell the ITT collector of tools/tsan about each spawn, each task-tree
    # join and each wait (call_itt_task_notify). Every translation unit must agree (the inline
    # TBB code differs), hence the whole project.
    add_compile_definitions(TBB_USE_PROFILING_TOOLS=2)
  endif()
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    # GCC 12's -Wmaybe-uninitialized gives false positives inside libstdc++ (std::function in
    # <regex>'s automaton) once the sanitizers instrument the code (GCC bugs 105562, 107138),
    # which -Werror in CI turns into a failed build. Off in sanitized builds only: the normal
    # build keeps the warning for our code.
    add_compile_options(-Wno-maybe-uninitialized)
  endif()
  message(STATUS "corocontact: instrumented with -fsanitize=${CORO_SANITIZE}")
endif()
