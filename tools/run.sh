#!/usr/bin/env bash
# Set up (install what is missing, build the corocontact command only), then run a case into a
# VTK series and say where it is.
#
#   tools/run.sh [CASE.toml] [corocontact run options...]
#
# Default case: cases/two_spheres/two_spheres.toml, written to out/two_spheres/. An argument
# that starts with '-' is an option, not a case: `tools/run.sh --steps 50` runs the default case
# for 50 steps. The tests are built by tools/test.sh.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
case "${1:-}" in
  -h|--help) sed -n 2,9p "${BASH_SOURCE[0]}"; exit 0 ;;
esac
case_file=$root/cases/two_spheres/two_spheres.toml
if [ $# -gt 0 ] && [ "${1#-}" = "$1" ]; then
  case_file=$1
  shift
fi
"$root/tools/setup.sh" --target corocontact
status=0
"$root/build/bin/corocontact" run "$case_file" "$@" || status=$?
if [ "$status" -eq 0 ] || [ "$status" -ge 128 ]; then
  echo "Open the .pvd above in ParaView (File > Open, Apply), or render it to PNGs:"
  echo "  tools/render.sh SERIES.pvd --array von_mises --out pictures/"
fi
exit "$status"
