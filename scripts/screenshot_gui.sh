#!/usr/bin/env bash
# Screenshots of the real MeshLab GUI under Xvfb, for the docs: the Filters menu with our filter,
# and a mesh after running it from the GUI. Needs: xvfb xdotool imagemagick (installed by setup.sh
# when SCREENSHOT_DEPS=1) and a built prefix.
#   scripts/screenshot_gui.sh MESH.ply OUTDIR
#   scripts/screenshot_gui.sh --host 2025.07 MESH.ply OUTDIR   # forky's MeshLab 2025.07 (scripts/host.sh 2025.07)
# With --host 2025.07, MeshLab runs in the forky userland on this machine's Xvfb and loads the plugins of
# build-2025.07/ from its per-user extra-plugins folder (a fresh HOME under /tmp): one picture of the
# Filters > Quality Measure and Computations menu with this project's filters beside the mesh in the viewer.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
HOST=2020.09
if [ "${1:-}" = --host ]; then HOST="$2"; shift 2; fi
MESH="$(readlink -f "$1")"; OUT="$2"; mkdir -p "$OUT"
command -v xdotool >/dev/null || apt-get install -y -q xdotool >/dev/null
if [ "$HOST" = 2025.07 ]; then
  home="$(mktemp -d /tmp/pectus-meshlab-home.XXXX)"
  . "$ROOT/scripts/gui_plugins.sh"
  gui_plugins 2025.07 "$home"
  export DISPLAY=:94
  Xvfb $DISPLAY -screen 0 1280x860x24 >/dev/null 2>&1 & XPID=$!
  "$ROOT/scripts/host.sh" 2025.07 run bash -c "mount -t proc proc /proc && HOME='$home' DISPLAY=$DISPLAY exec meshlab '$MESH'" \
    >/dev/null 2>&1 & MPID=$!
  trap 'pkill -x meshlab || true; kill $XPID 2>/dev/null || true; rm -rf "$home"' EXIT
  sleep 12
  W=$(xdotool search --name "MeshLab" | tail -1)
  xdotool windowmove "$W" 0 0 windowsize "$W" 1280 860; sleep 1
  # turn the cage to face the viewer, then the menu
  xdotool mousemove 420 250 mousedown 1 sleep 0.2 mousemove 420 350 sleep 0.2 mousemove 420 420 sleep 0.2 mouseup 1; sleep 1
  import -window root "$home/result.png"
  xdotool mousemove 116 10 click 1; sleep 1.5
  xdotool mousemove 200 240 sleep 0.3 mousemove 220 240; sleep 1.5
  import -window root "$home/menu.png"
  convert "$home/menu.png" -crop 960x860+0+0 +repage "$home/m.png"
  convert "$home/result.png" -crop 840x830+0+0 +repage "$home/r.png"
  convert "$home/m.png" "$home/r.png" -resize x560 +append -resize 1400x +repage "$OUT/meshlab_2025_menu_result.png"
  echo "screenshot: $OUT/meshlab_2025_menu_result.png"
  exit 0
fi
export DISPLAY=:93
Xvfb $DISPLAY -screen 0 1280x860x24 >/dev/null 2>&1 & XPID=$!
trap 'kill $MPID $XPID 2>/dev/null || true' EXIT
sleep 2
"$ROOT/build/prefix/bin/meshlab" "$MESH" >/dev/null 2>&1 & MPID=$!
sleep 8
W=$(xdotool search --name "MeshLab" | tail -1)
xdotool windowmove "$W" 0 0 windowsize "$W" 1280 860; sleep 1
# Filters > Quality Measure and Computations > Compute Element Quality ...
xdotool mousemove 120 10 click 1; sleep 1
xdotool mousemove 230 262 sleep 0.3 mousemove 240 261 click 1; sleep 1.5
import -window root "$OUT/meshlab_filter_menu.png"
xdotool mousemove 600 347 sleep 0.3 mousemove 717 347 click 1; sleep 2
import -window root "$OUT/meshlab_filter_dialog.png"
xdotool mousemove 319 397 click 1; sleep 2      # Apply
xdotool mousemove 111 397 click 1; sleep 1.5    # Close
import -window root "$OUT/meshlab_quality.png"
echo "screenshots in $OUT"
