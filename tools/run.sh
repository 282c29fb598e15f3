#!/usr/bin/env bash
# Set up (install what is missing, build), then run a case into a VTK series.
#
#   tools/run.sh [CASE.toml] [corocontact run options...]
#
# Default case: cases/two_spheres/two_spheres.toml, written to out/two_spheres/.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$root/tools/setup.sh"
case_file=${1:-$root/cases/two_spheres/two_spheres.toml}
[ $# -gt 0 ] && shift
exec "$root/build/bin/corocontact" run "$case_file" "$@"
