#!/usr/bin/env bash
# Opens filter dialogs in the real MeshLab GUI under Xvfb, on a screen 1,000 px tall, through MeshLab's filter
# search (Ctrl+F, the filter's name, Enter). For each filter it prints one line
#   dialog <width>x<height> <filter name>
# and saves OUTDIR/dialog_<n>.png (the screen with the dialog) and dialog_<n>_window.png (the dialog alone); with --help, the dialog is measured and shot
# again with every parameter's help shown (the dialog's Help button), as dialog_<n>_help.png.
# With --menu, it first saves OUTDIR/menu.png: Filters > Quality Measure and Computations, opened.
#   scripts/screenshot_dialogs.sh [--host 2025.07] [--help] [--menu] OUTDIR MESH [MESH...] -- "Filter name" [...]
# MESH: the layers to load first (the filters need a current layer to be enabled). Needs xvfb, xdotool and
# imagemagick (setup.sh installs them) and a built prefix (2020.09) or build-2025.07 (scripts/host.sh 2025.07).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
HOST=2020.09 HELP=0 MENU=0
while [[ "${1:-}" =~ ^--(host|help|menu)$ ]]; do
  case "$1" in
    --host) HOST="$2"; shift 2 ;;
    --help) HELP=1; shift ;;
    --menu) MENU=1; shift ;;
  esac
done
OUT="$1"; shift; mkdir -p "$OUT"; OUT="$(readlink -f "$OUT")"
MESHES=()
while [ "$#" -gt 0 ] && [ "$1" != -- ]; do MESHES+=("$(readlink -f "$1")"); shift; done
shift
command -v xdotool >/dev/null || apt-get install -y -q xdotool >/dev/null
command -v import >/dev/null || apt-get install -y -q imagemagick >/dev/null

SCREEN_W=1400 SCREEN_H=1000
export DISPLAY=":$((90 + RANDOM % 400))"
Xvfb "$DISPLAY" -screen 0 ${SCREEN_W}x${SCREEN_H}x24 -nolisten tcp >/dev/null 2>&1 & XPID=$!
home="$(mktemp -d /tmp/pectus-dialogs-home.XXXX)"
cleanup() {
  kill "${MPID:-}" 2>/dev/null || true
  [ "$HOST" = 2020.09 ] || pkill -f "meshlab .*$home" 2>/dev/null || true
  kill "$XPID" 2>/dev/null || true
  rm -rf "$home"
}
trap cleanup EXIT
sleep 2
if [ "$HOST" = 2020.09 ]; then
  HOME="$home" "$ROOT/build/prefix/bin/meshlab" "${MESHES[@]}" >/dev/null 2>&1 & MPID=$!
else
  # the forky userland's MeshLab (which sees this /tmp) loads build-2025.07's plugins from a fresh per-user
  # extra-plugins folder
  . "$ROOT/scripts/gui_plugins.sh"
  gui_plugins "$HOST" "$home"
  for m in "${MESHES[@]}"; do cp "$m" "$home/"; done
  inside=""; for m in "${MESHES[@]}"; do inside+=" '$home/$(basename "$m")'"; done
  "$ROOT/scripts/host.sh" "$HOST" run bash -c "mountpoint -q /proc || mount -t proc proc /proc; \
    HOME='$home' DISPLAY=$DISPLAY exec meshlab $inside" >/dev/null 2>&1 & MPID=$!
fi

main=""
for _ in $(seq 60); do
  main="$(xdotool search --name "^MeshLab [0-9]" 2>/dev/null | head -1 || true)"
  [ -n "$main" ] && break
  sleep 1
done
[ -n "$main" ] || { echo "MeshLab did not start" >&2; exit 1; }
sleep 4
xdotool windowmove "$main" 0 0 windowsize "$main" "$SCREEN_W" "$SCREEN_H"; sleep 1

# the dialog of `name`: MeshLab 2020.09 opens it as a floating window with the filter's name as title;
# 2021.05 and later dock it in the main window, so the dock is found by its title among the main window's children
shoot() {  # shoot FILE: the whole screen
  import -window root "$1"
}
if [ "$MENU" = 1 ]; then
  # Filters, then its Quality Measure and Computations entry (the menu's 9th row on both releases)
  xdotool mousemove 118 10 click 1; sleep 1.2
  row=$([ "$HOST" = 2020.09 ] && echo 261 || echo 240)
  xdotool mousemove 230 "$row" sleep 0.3 mousemove 250 "$row"; sleep 1.5
  shoot "$OUT/menu.png"
  xdotool key Escape Escape; sleep 0.5
fi
close_dialog() {  # close_dialog WINDOW: its Close button, the left one of the bottom row
  eval "$(xdotool getwindowgeometry --shell "$1")"
  xdotool mousemove $((X + WIDTH / 4)) $((Y + HEIGHT - 20)) click 1; sleep 1
}
n=0
for name in "$@"; do
  n=$((n + 1))
  # the search lists the best matches first; the words after 'Pectus: ' tell the filters apart, and when
  # the first match is another filter the next ones are tried
  pattern="^$(printf '%s' "$name" | sed 's/[][()\.^$*+?{}|]/\\&/g')\$"
  win=""
  for k in 1 2 3 4 5; do
    xdotool windowfocus --sync "$main" 2>/dev/null || true
    xdotool key ctrl+f; sleep 0.8
    xdotool type --delay 20 "${name#Pectus: }"; sleep 1.2
    for _ in $(seq "$k"); do xdotool key Down; done
    xdotool key Return; sleep 2.5
    win="$(xdotool search --onlyvisible --name "$pattern" 2>/dev/null | tail -1 || true)"
    [ -n "$win" ] && break
    other="$(xdotool search --onlyvisible --name "^Pectus: " 2>/dev/null | tail -1 || true)"
    if [ -n "$other" ]; then close_dialog "$other"; fi
  done
  if [ -z "$win" ]; then echo "dialog not-found $name"; shoot "$OUT/dialog_$n.png"; continue; fi
  eval "$(xdotool getwindowgeometry --shell "$win")"
  echo "dialog ${WIDTH}x${HEIGHT} $name"
  shoot "$OUT/dialog_$n.png"
  import -window "$win" "$OUT/dialog_${n}_window.png"
  if [ "$HELP" = 1 ]; then
    # the Help button: the right one of the first row of buttons, two button rows above the dialog's bottom
    xdotool mousemove $((X + WIDTH * 3 / 4)) $((Y + HEIGHT - 50)) click 1; sleep 1.5
    eval "$(xdotool getwindowgeometry --shell "$win")"
    echo "dialog-help ${WIDTH}x${HEIGHT} $name"
    shoot "$OUT/dialog_${n}_help.png"
  fi
  close_dialog "$win"
done
