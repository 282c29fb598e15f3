#!/usr/bin/env bash
# Set up (install what is missing, build with tests), then run every test through ctest.
#
#   tools/test.sh [ctest options...]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$root/tools/setup.sh"
cd "$root/build"
exec ctest --output-on-failure -j "$(nproc)" "$@"
