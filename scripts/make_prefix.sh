#!/usr/bin/env bash
# make_prefix.sh PREFIX PLUGIN_BUILD_DIR plugin...
# A private MeshLab: copies of Debian's meshlab/meshlabserver in PREFIX/bin (Debian's MeshLab loads
# plugins only from <binary>/../lib/x86_64-linux-gnu/meshlab/plugins), libmeshlab-common and the
# system plugins linked, this project's plugins linked from the build tree.
set -euo pipefail
mkdir -p "$1"
PREFIX="$(cd "$1" && pwd)"; BUILT="$(cd "$2" && pwd)"; shift 2
SYSLIB=/usr/lib/x86_64-linux-gnu/meshlab
mkdir -p "$PREFIX/bin" "$PREFIX/lib/x86_64-linux-gnu/meshlab/plugins"
for b in meshlab meshlabserver; do
  if [ ! -x "$PREFIX/bin/$b" ] || ! cmp -s "/usr/bin/$b" "$PREFIX/bin/$b"; then
    cp -f "/usr/bin/$b" "$PREFIX/bin/$b"
  fi
done
ln -sfn "$SYSLIB/libmeshlab-common.so" "$PREFIX/lib/x86_64-linux-gnu/meshlab/libmeshlab-common.so"
PD="$PREFIX/lib/x86_64-linux-gnu/meshlab/plugins"
# drop every link, then link the plugins anew (no stale link to a plugin the build does not have)
find "$PD" -maxdepth 1 -type l -delete
for p in "$SYSLIB"/plugins/*.so; do ln -sfn "$p" "$PD/$(basename "$p")"; done
# Debian's MeshLab resources (shaders etc.) are found relative to the binary too
[ -e "$PREFIX/share" ] || ln -sfn /usr/share "$PREFIX/share"
for name in "$@"; do
  ln -sfn "$BUILT/lib$name.so" "$PD/lib$name.so"
done
