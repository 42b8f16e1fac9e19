#!/usr/bin/env bash
# The README's pictures of the GUI, from scripts/screenshot_dialogs.sh on a screen 1,000 px tall:
#   OUTDIR/meshlab_menu_2020.png, meshlab_menu_2025.png  Filters > Quality Measure and Computations
#   OUTDIR/meshlab_dialogs.png  the Nuss FE, slice volume and pectus index dialogs, 2020.09 above 2025.07
#   scripts/docs_gui_images.sh CAGE.ply LANDMARKS.ply [OUTDIR]   (OUTDIR: docs/img)
# CAGE.ply, LANDMARKS.ply: e.g. ribcage_smoothed.ply and ribcage_landmarks.ply of a main-job run.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
CAGE="$1" LANDMARKS="$2" OUT="${3:-$ROOT/docs/img}"
mkdir -p "$OUT"
work="$(mktemp -d /tmp/pectus-gui-images.XXXX)"
trap 'rm -rf "$work"' EXIT
rows=()
for host in 2020.09 2025.07; do
  "$ROOT/scripts/screenshot_dialogs.sh" --host "$host" --menu "$work/$host" "$CAGE" "$LANDMARKS" -- \
    "Pectus: Nuss Procedure FE Analysis" "Pectus: Thoracic Volume (Slice Method)" "Pectus: Pectus Index"
  convert "$work/$host/menu.png" -crop 980x1000+0+0 +repage -resize 70% "$OUT/meshlab_menu_${host%%.*}.png"
  # the three dialogs side by side, top-aligned, on the screen's height
  convert "$work/$host"/dialog_{1,2,3}_window.png -bordercolor white -border 6 -background white -gravity north \
    +append "$work/$host-row.png"
  rows+=("$work/$host-row.png")
done
convert "${rows[@]}" -background white -gravity west -append -resize 1400x\> "$OUT/meshlab_dialogs.png"
echo "pictures in $OUT"
