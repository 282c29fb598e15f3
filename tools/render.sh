#!/usr/bin/env bash
# Render a corocontact result to PNG (and an animation): installs what is missing, then runs
# tools/render.py under xvfb-run with Debian's python3-vtk9. Non-interactive and idempotent.
#
#   tools/render.sh [--with-ffmpeg] INPUT.pvd|.vtm|.vtu [render.py options...]
#   tools/render.sh out/two_spheres/two_spheres.pvd --last --array von_mises --out last.png
#   tools/render.sh --help          # render.py's options
#
# --with-ffmpeg also installs ffmpeg, so a series gets NAME.mp4 (else an animated GIF when
# Pillow is there, else only the PNGs).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

packages=(python3-vtk9 python3-numpy xvfb xauth libgl1-mesa-dri)
args=()
for a in "$@"; do
  if [ "$a" = "--with-ffmpeg" ]; then packages+=(ffmpeg); else args+=("$a"); fi
done

installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q '^install ok installed$'; }
if ! installed python3-vtk9 && installed python3-paraview; then
  # Installing python3-vtk9 would make apt remove ParaView's Python module; leave that choice
  # to the user.
  echo "render.sh: python3-paraview is installed and conflicts with python3-vtk9, which" \
       "render.py needs; remove it (apt-get remove python3-paraview) and run again" >&2
  exit 2
fi

missing=()
for p in "${packages[@]}"; do
  installed "$p" || missing+=("$p")
done

if [ ${#missing[@]} -gt 0 ]; then
  echo "render.sh: installing ${missing[*]}" >&2
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  apt_opts=(-o DPkg::Lock::Timeout=600 -y -q --no-install-recommends)
  # A fresh machine has empty package lists; update once, then install. apt's chatter goes to
  # stderr so that stdout keeps render.py's report.
  "${sudo_cmd[@]}" apt-get -o DPkg::Lock::Timeout=600 update -q >&2
  "${sudo_cmd[@]}" apt-get "${apt_opts[@]}" install "${missing[@]}" >&2
fi

# A 24-bit screen (xvfb-run's default is 8-bit); off-screen rendering draws into a framebuffer
# object, so pictures may be larger than the screen.
exec xvfb-run -a -s "-screen 0 1920x1080x24 -nolisten tcp" \
  env CORO_RENDER_NO_XVFB=1 /usr/bin/python3 "$root/tools/render.py" ${args[@]+"${args[@]}"}
