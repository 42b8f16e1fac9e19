#!/usr/bin/env bash
# Screenshots of the real MeshLab GUI under Xvfb, for the docs: the Filters menu with our filter,
# and a mesh after running it from the GUI. Needs: xvfb xdotool imagemagick (installed by setup.sh
# when SCREENSHOT_DEPS=1) and a built prefix.
#   scripts/screenshot_gui.sh MESH.ply OUTDIR
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
MESH="$1"; OUT="$2"; mkdir -p "$OUT"
command -v xdotool >/dev/null || apt-get install -y -q xdotool >/dev/null
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
