#!/usr/bin/env bash
# Smoke test of tools/render.sh: run a tiny case (one small box, 2 steps) with the given
# corocontact, render one frame and the whole series off screen, check that the PNGs exist
# and show a coloured body, and that a bad array name fails with exit code 2.
#
#   tools/render_test.sh PATH/TO/corocontact
#
# render.sh installs python3-vtk9, xvfb and xauth when missing (apt-get; root or sudo).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cli=${1:?usage: render_test.sh PATH/TO/corocontact}
render="$root/tools/render.sh"

work=$(mktemp -d "${TMPDIR:-/tmp}/render_test.XXXXXX")
trap 'rm -rf "$work"' EXIT

fail() { echo "render_test.sh: FAIL: $*" >&2; exit 1; }

cat > "$work/tiny.toml" <<'EOF'
# One small box falling and moving sideways, 2 steps: a series of 3 frames.
[simulation]
analysis = "dynamic"
dt = 0.01
steps = 2
gravity = [0.0, -9.81, 0.0]

[[body]]
name = "box"
shape = "box"
min = [0.0, 0.0, 0.0]
max = [1.0, 0.5, 0.5]
cells = [4, 2, 2]
velocity = [1.0, 0.0, 0.0]
young = 1e5
poisson = 0.3
density = 1000.0
EOF

"$cli" run "$work/tiny.toml" --out "$work/out" --quiet >/dev/null
[ -f "$work/out/tiny.pvd" ] || fail "corocontact wrote no $work/out/tiny.pvd"

# One frame, coloured by a cell array, with edges.
"$render" "$work/out/tiny.pvd" --last --array von_mises --edges --size 480 320 \
  --out "$work/last.png"
# The whole series into a directory, coloured by velocity (point data), no animation.
"$render" "$work/out/tiny.pvd" --array velocity --size 320 240 --no-animation \
  --out "$work/frames"

frames=$(grep -c '<DataSet ' "$work/out/tiny.pvd")
pngs=$(find "$work/frames" -name 'tiny_*.png' | wc -l)
[ "$pngs" -eq "$frames" ] || fail "$pngs PNGs for $frames frames in $work/frames"

# Each picture must be a real image: more than a few KB, and the body drawn in colour
# (saturated pixels left of the scalar bar; the background is a pale grey-blue gradient).
check_png() {
  local png=$1 w=$2 h=$3
  [ -f "$png" ] || fail "missing $png"
  [ "$(stat -c %s "$png")" -gt 3000 ] || fail "$png is only $(stat -c %s "$png") bytes"
  /usr/bin/python3 - "$png" "$w" "$h" <<'PY' || fail "$png does not show a coloured body"
import sys
from vtkmodules.vtkIOImage import vtkPNGReader
from vtkmodules.util.numpy_support import vtk_to_numpy
path, w, h = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
r = vtkPNGReader()
r.SetFileName(path)
r.Update()
img = r.GetOutput()
dims = img.GetDimensions()
if (dims[0], dims[1]) != (w, h):
    sys.exit(f"{path}: {dims[0]}x{dims[1]}, expected {w}x{h}")
px = vtk_to_numpy(img.GetPointData().GetScalars()).reshape(h, w, -1)[:, :, :3].astype(int)
colours = len({tuple(p) for p in px.reshape(-1, 3)[::7]})
model = px[: int(0.85 * h), : int(0.8 * w)]          # rows from the bottom; left of the bar
saturated = (model.max(axis=2) - model.min(axis=2) > 60).sum()
print(f"{path}: {colours} colours (sampled), {saturated} saturated pixels in the model area")
if colours < 20 or saturated < 0.005 * model.shape[0] * model.shape[1]:
    sys.exit(1)
PY
}
check_png "$work/last.png" 480 320
# PNGs carry the step of the frame they show, as the series' files do (tiny_000002.vtm ->
# tiny_000002.png).
for vtm in "$work"/out/tiny_*.vtm; do
  png="$work/frames/$(basename "$vtm" .vtm).png"
  [ -f "$png" ] || fail "no $png for $vtm"
done
check_png "$work/frames/tiny_000000.png" 320 240
last_vtm=$(ls "$work"/out/tiny_*.vtm | sort | tail -n 1)
check_png "$work/frames/$(basename "$last_vtm" .vtm).png" 320 240

# An unknown array is an input error: exit code 2 and the available arrays listed.
set +e
msg=$("$render" "$work/out/tiny.pvd" --last --array no_such_array --out "$work/x.png" 2>&1)
rc=$?
set -e
[ "$rc" -eq 2 ] || fail "unknown array: exit code $rc, expected 2"
grep -q "Available: .*displacement" <<<"$msg" || fail "unknown array: message lacks the list: $msg"

echo "render_test.sh: OK"
