#!/usr/bin/env bash
# Set up (install what is missing, build with tests), then run every test through ctest.
#
#   tools/test.sh [ctest options...]              build/       the whole suite
#   tools/test.sh --sanitize [ctest options...]   build-asan/  the whole suite under ASan+UBSan
#   tools/test.sh --tsan [ctest options...]       build-tsan/  the whole suite under TSan
#
# --sanitize: RelWithDebInfo with CORO_SANITIZE=address,undefined (every target instrumented,
#   UBSan reports are fatal; LeakSanitizer ignores the leaks PETSc and OpenMPI keep by design,
#   tools/asan). Sanitized builds leave out the Python module (the plain suite tests it).
# --tsan: RelWithDebInfo with CORO_SANITIZE=thread; the suite plus tsan.DeliberateRace, which
#   checks that a race in a parallel_for body is still reported. Debian's libtbb is not
#   instrumented; tools/tsan makes its task hand-offs visible to TSan (tools/tsan/README.md).
#   The TSan options (halt_on_error=1, the suppressions of tools/tsan.supp) are built into every
#   executable of that build, so plain ctest in build-tsan/ behaves the same; TSAN_OPTIONS adds
#   to them.
# Environment: CI=true turns warnings into errors (CORO_WARNINGS_AS_ERRORS=ON).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

mode=default
case "${1:-}" in
  --sanitize) mode=asan; shift ;;
  --tsan) mode=tsan; shift ;;
  -h|--help) sed -n 2,17p "${BASH_SOURCE[0]}"; exit 0 ;;
esac

if [ "$mode" = default ]; then
  "$root/tools/setup.sh"
  cd "$root/build"
  exec ctest --output-on-failure -j "$(nproc)" "$@"
fi

# Sanitized builds: packages as for the normal build, then a build directory of their own.
"$root/tools/setup.sh" --no-build
werror=OFF
[ "${CI:-}" = "true" ] && werror=ON
if [ "$mode" = asan ]; then
  build="$root/build-asan"
  sanitize="address,undefined"
else
  build="$root/build-tsan"
  sanitize="thread"
fi
# Without the Python module: an instrumented module cannot load into Debian's uninstrumented
# python3 (the sanitizer runtime must come first in the process); the plain suite runs its tests.
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCORO_SANITIZE="$sanitize" \
  -DCORO_BUILD_BENCHMARKS=OFF -DCORO_WITH_PYTHON=OFF -DCORO_WARNINGS_AS_ERRORS="$werror" >/dev/null
cmake --build "$build" -j "$(nproc)"
cd "$build"

if [ "$mode" = asan ]; then
  # A UBSan report aborts the process (with -fno-sanitize-recover) and prints its stack.
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
  export ASAN_OPTIONS="strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
fi
exec ctest --output-on-failure -j "$(nproc)" "$@"
