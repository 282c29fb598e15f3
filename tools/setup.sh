#!/usr/bin/env bash
# Set up corocontact from nothing: install the missing Debian packages, configure and
# build into build/. Non-interactive and idempotent; safe to run again.
#
#   tools/setup.sh [--build-type Release|Debug] [--no-build] [--target NAME]...
#
# --target NAME builds only that CMake target and what it needs (tools/run.sh builds
# `corocontact`); without it everything is built, tests and benchmarks included.
# Environment: CI=true turns warnings into errors (CORO_WARNINGS_AS_ERRORS=ON).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_type=Release
do_build=1
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build-type) build_type=$2; shift 2 ;;
    --no-build) do_build=0; shift ;;
    --target) [ $# -ge 2 ] || { echo "setup.sh: --target needs a target name" >&2; exit 2; }
              targets+=(--target "$2"); shift 2 ;;
    -h|--help) sed -n 2,9p "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "setup.sh: unknown option '$1' (expected --build-type, --no-build or --target)" >&2; exit 2 ;;
  esac
done

packages=(
  build-essential cmake pkg-config
  libeigen3-dev libtbb-dev libmetis-dev libembree-dev libgmp-dev
  libvtk9-dev libcli11-dev libtomlplusplus-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  petsc-dev libhypre-dev   # the AMG preconditioner (PETSc GAMG) and bench_amg's hypre
  libopenmpi-dev openmpi-bin   # runs over several processes (CORO_WITH_MPI)
  calculix-ccx python3-matplotlib
  python3-vtk9 python3-numpy xvfb xauth libgl1-mesa-dri
  pybind11-dev python3-pybind11 python3-dev python3-pytest
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q '^install ok installed$' || missing+=("$p")
done

if [ ${#missing[@]} -gt 0 ]; then
  echo "setup.sh: installing ${missing[*]}"
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  apt_opts=(-o DPkg::Lock::Timeout=600 -y -q --no-install-recommends)
  # A fresh machine has empty package lists; update once, then install.
  "${sudo_cmd[@]}" apt-get -o DPkg::Lock::Timeout=600 update -q
  "${sudo_cmd[@]}" apt-get "${apt_opts[@]}" install "${missing[@]}"
fi

[ "$do_build" -eq 1 ] || exit 0

werror=OFF
[ "${CI:-}" = "true" ] && werror=ON
cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE="$build_type" \
  -DCORO_WARNINGS_AS_ERRORS="$werror" >/dev/null
cmake --build "$root/build" -j "$(nproc)" "${targets[@]}"
