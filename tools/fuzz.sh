#!/usr/bin/env bash
# Fuzz corocontact's readers with libFuzzer (clang, ASan+UBSan), each target for a set time.
#
#   tools/fuzz.sh [--seconds N] [--build-only] [target...]
#
# Targets: msh tetgen obj stl off case scene (default: all). Builds in build-fuzz/ with
# clang++ (installed with apt-get if missing, like tools/setup.sh does), then runs each
# build-fuzz/fuzz/fuzz_<target> for N seconds (default 60) in one process on the committed
# seed corpus fuzz/corpus/<target>/ (read only) plus build-fuzz/corpus/<target>/ (new inputs
# found go there), with the dictionary fuzz/dict/<target>.dict when there is one. A crash,
# sanitizer report, uncaught exception other than InputError/NumericalError, an input that
# takes over 10 s or allocates over 1 GB is saved as build-fuzz/artifacts/<target>/crash-*
# (or timeout-*, oom-*, leak-*); replay it with build-fuzz/fuzz/fuzz_<target> FILE.
# Prints executions and time per target; exits 1 if any target found something.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
all_targets=(msh tetgen obj stl off case scene)

seconds=60
build_only=0
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds=$2; shift 2 ;;
    --build-only) build_only=1; shift ;;
    -h|--help) sed -n 2,16p "${BASH_SOURCE[0]}"; exit 0 ;;
    -*) echo "fuzz.sh: unknown option '$1' (expected --seconds N, --build-only)" >&2; exit 2 ;;
    *)
      case " ${all_targets[*]} " in
        *" $1 "*) targets+=("$1") ;;
        *) echo "fuzz.sh: unknown target '$1' (expected one of: ${all_targets[*]})" >&2; exit 2 ;;
      esac
      shift ;;
  esac
done
[ ${#targets[@]} -gt 0 ] || targets=("${all_targets[@]}")

# The libraries and headers the project needs, then clang (libFuzzer ships with it).
"$root/tools/setup.sh" --no-build
if ! dpkg-query -W -f='${Status}' clang 2>/dev/null | grep -q '^install ok installed$'; then
  echo "fuzz.sh: installing clang"
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get -o DPkg::Lock::Timeout=600 update -q
  "${sudo_cmd[@]}" apt-get -o DPkg::Lock::Timeout=600 -y -q --no-install-recommends install clang
fi

build="$root/build-fuzz"
# -O1 -g without NDEBUG: Eigen's and our debug assertions stay on, stacks stay readable.
cmake -S "$root" -B "$build" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DCORO_FUZZ=ON -DCORO_BUILD_TESTS=OFF \
  -DCORO_BUILD_BENCHMARKS=OFF -DCORO_WITH_EMBREE=OFF >/dev/null
cmake --build "$build" -j "$(nproc)" --target "${targets[@]/#/fuzz_}"
[ "$build_only" -eq 0 ] || exit 0

summary=()
found=0
for t in "${targets[@]}"; do
  mkdir -p "$build/corpus/$t" "$build/artifacts/$t"
  args=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024
        -print_final_stats=1 -artifact_prefix="$build/artifacts/$t/")
  [ -f "$root/fuzz/dict/$t.dict" ] && args+=(-dict="$root/fuzz/dict/$t.dict")
  log="$build/fuzz_$t.log"
  echo "fuzz.sh: fuzz_$t for ${seconds} s (log: $log)"
  start=$(date +%s)
  set +e
  "$build/fuzz/fuzz_$t" "${args[@]}" "$build/corpus/$t" "$root/fuzz/corpus/$t" >"$log" 2>&1
  rc=$?
  set -e
  elapsed=$(( $(date +%s) - start ))
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  corpus=$(find "$build/corpus/$t" -type f | wc -l)
  if [ "$rc" -eq 0 ]; then
    result="no crash"
  else
    found=1
    artifact=$(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$log" | tail -1)
    result="FOUND (exit $rc): ${artifact:-see the log}"
    grep -m1 -E 'ERROR: (AddressSanitizer|libFuzzer|UndefinedBehaviorSanitizer)|runtime error|terminate called' "$log" || true
  fi
  summary+=("$(printf '%-7s %10s execs %6s s  %5s new corpus files  %s' "$t" "${execs:-?}" "$elapsed" "$corpus" "$result")")
done

echo
echo "fuzz.sh summary (target, executions, wall time, corpus, result):"
printf '  %s\n' "${summary[@]}"
exit "$found"
