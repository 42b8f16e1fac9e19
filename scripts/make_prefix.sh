#!/usr/bin/env bash
# make_prefix.sh PREFIX PLUGIN_BUILD_DIR plugin...
# A private MeshLab: copies of Debian's meshlab/meshlabserver in PREFIX/bin (Debian's MeshLab loads
# plugins only from <binary>/../lib/x86_64-linux-gnu/meshlab/plugins), libmeshlab-common and the
# system plugins linked, this project's plugins linked from the build tree.
# Safe to run while a MeshLab from this prefix starts: every file and link is written beside its final name
# and renamed over it (a rename is atomic), and only links that no longer belong are removed, so the plugin
# folder never lacks a plugin it should have.
set -euo pipefail
mkdir -p "$1"
PREFIX="$(cd "$1" && pwd)"; BUILT="$(cd "$2" && pwd)"; shift 2
SYSLIB=/usr/lib/x86_64-linux-gnu/meshlab
PD="$PREFIX/lib/x86_64-linux-gnu/meshlab/plugins"
mkdir -p "$PREFIX/bin" "$PD"

# put_link TARGET LINK: LINK points at TARGET, replaced in one rename
put_link() {
  [ "$(readlink "$2" 2>/dev/null)" = "$1" ] && return 0
  ln -sfn "$1" "$2.new.$$"
  mv -fT "$2.new.$$" "$2"
}

for b in meshlab meshlabserver; do
  if [ ! -x "$PREFIX/bin/$b" ] || ! cmp -s "/usr/bin/$b" "$PREFIX/bin/$b"; then
    cp -f "/usr/bin/$b" "$PREFIX/bin/$b.new.$$"
    mv -fT "$PREFIX/bin/$b.new.$$" "$PREFIX/bin/$b"
  fi
done
put_link "$SYSLIB/libmeshlab-common.so" "$PREFIX/lib/x86_64-linux-gnu/meshlab/libmeshlab-common.so"
# Debian's MeshLab resources (shaders etc.) are found relative to the binary too
[ -e "$PREFIX/share" ] || ln -sfn /usr/share "$PREFIX/share"

declare -A want
for p in "$SYSLIB"/plugins/*.so; do want["$(basename "$p")"]="$p"; done
for name in "$@"; do want["lib$name.so"]="$BUILT/lib$name.so"; done
for f in "${!want[@]}"; do put_link "${want[$f]}" "$PD/$f"; done
# links to plugins that are no longer built or installed (not another run's link in the making)
for l in "$PD"/*; do
  [ -L "$l" ] || continue
  case "$l" in *.new.*) continue;; esac
  [ -n "${want[$(basename "$l")]:-}" ] || rm -f "$l"
done
