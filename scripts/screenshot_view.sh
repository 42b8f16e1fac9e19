#!/usr/bin/env bash
# A screenshot of the real MeshLab GUI (under Xvfb) showing one mesh as loaded (vertex colours as saved),
# seen obliquely from the front-left: the mesh is rewritten with (x, z, y) and reversed faces so MeshLab's
# default front view looks along the body's long axis, then the trackball is dragged.
#   scripts/screenshot_view.sh MESH.ply OUT.png
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
MESH="$1"; OUT="$2"
command -v xdotool >/dev/null || apt-get install -y -q xdotool >/dev/null
TMP=$(mktemp -d); trap 'kill ${MPID:-} ${XPID:-} 2>/dev/null || true; rm -rf "$TMP"' EXIT
/usr/bin/python3 -c "
import sys; sys.path[:0] = ['$ROOT/tests/e2e', '$ROOT/python']
import numpy as np, harness as h
m = h.read_ply('$MESH'); V = m['V'][:, [0, 2, 1]]; F = np.asarray(m['F'])[:, ::-1]
vx = m['vertex']
cols = [vx[c] for c in ('red', 'green', 'blue')] if 'red' in vx else None
with open('$TMP/view.ply', 'w') as fh:
    fh.write('ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n' % len(V))
    if cols: fh.write('property uchar red\nproperty uchar green\nproperty uchar blue\n')
    fh.write('element face %d\nproperty list uchar int vertex_indices\nend_header\n' % len(F))
    for i, p in enumerate(V):
        fh.write('%g %g %g' % tuple(p) + ((' %d %d %d' % (cols[0][i], cols[1][i], cols[2][i])) if cols else '') + '\n')
    for f in F: fh.write('3 %d %d %d\n' % tuple(f))
"
export DISPLAY=:94
Xvfb $DISPLAY -screen 0 1280x860x24 >/dev/null 2>&1 & XPID=$!
sleep 2
"$ROOT/build/prefix/bin/meshlab" "$TMP/view.ply" >/dev/null 2>&1 & MPID=$!
sleep 8
W=$(xdotool search --name "MeshLab" | tail -1)
xdotool windowmove "$W" 0 0 windowsize "$W" 1280 860; sleep 1
xdotool mousemove 520 430 mousedown 1 mousemove 560 420 mousemove 600 400 mouseup 1; sleep 1.5
import -window root "$OUT"
echo "screenshot: $OUT"
