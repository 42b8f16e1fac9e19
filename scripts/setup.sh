#!/usr/bin/env bash
# Installs everything pectus-meshlab needs on a fresh Debian bookworm machine (run as root),
# fetches MeshLab's headers from Debian's source package of the installed MeshLab version,
# and configures + builds the project into build/.
#   scripts/setup.sh            # install deps, fetch headers, build
#   SKIP_BUILD=1 scripts/setup.sh
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
THIRD="$ROOT/third_party"
export DEBIAN_FRONTEND=noninteractive

SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi

PKGS=(meshlab qtbase5-dev libqt5opengl5-dev libglew-dev libeigen3-dev
      libtet1.5-dev libsuitesparse-dev libomp-dev libgtest-dev
      xvfb xauth cmake g++ make dpkg-dev python3 python3-numpy
      python3-matplotlib python3-scipy imagemagick libcgal-dev calculix-ccx libopenblas0-pthread
      liblemon-dev gmsh libcgal-demo parallel libopenmesh-apps)

missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

# deb-src entry for bookworm main, same URI and keyring as the deb entry
SRCLIST=/etc/apt/sources.list.d/pectus-debsrc.sources
need_update=0
if [ ! -f "$SRCLIST" ]; then
  $SUDO tee "$SRCLIST" >/dev/null <<'SRC'
Types: deb-src
URIs: http://deb.debian.org/debian
Suites: bookworm bookworm-updates
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
SRC
  need_update=1
fi
if [ ${#missing[@]} -gt 0 ] || [ $need_update = 1 ]; then
  echo "[setup] apt-get update"
  $SUDO apt-get update -q
fi
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] installing: ${missing[*]}"
  $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# MeshLab headers (src/common + vcglib) from the source package of the installed version
MLVER="$(dpkg-query -W -f='${Version}' meshlab)"
HDR="$THIRD/meshlab-$MLVER"
if [ ! -f "$HDR/.complete" ]; then
  echo "[setup] fetching MeshLab $MLVER source package for headers"
  rm -rf "$HDR" && mkdir -p "$HDR" "$THIRD/dl"
  ( cd "$THIRD/dl" && apt-get source --download-only "meshlab=$MLVER" >/dev/null )
  ORIG="$(ls "$THIRD"/dl/meshlab_*.orig.tar.* | head -n1)"
  tmp="$(mktemp -d)"
  tar -xf "$ORIG" -C "$tmp"
  top="$(ls "$tmp")"
  # patches of the Debian package (headers may be patched)
  DEB="$(ls "$THIRD"/dl/meshlab_*.debian.tar.* | head -n1)"
  tar -xf "$DEB" -C "$tmp/$top"
  if [ -f "$tmp/$top/debian/patches/series" ]; then
    ( cd "$tmp/$top" && while read -r p; do
        case "$p" in ''|\#*) continue;; esac
        patch -p1 -s --forward < "debian/patches/$p" >/dev/null || echo "[setup] note: patch $p did not apply cleanly";
      done < debian/patches/series )
  fi
  src="$tmp/$top"
  [ -d "$src/src/common" ] || { echo "[setup] no src/common in $ORIG"; exit 1; }
  mkdir -p "$HDR/src"
  cp -r "$src/src/common" "$HDR/src/common"
  if [ -d "$src/src/vcglib" ]; then cp -r "$src/src/vcglib" "$HDR/vcglib";
  elif [ -d "$src/vcglib" ]; then cp -r "$src/vcglib" "$HDR/vcglib";
  else echo "[setup] vcglib not found in the source package"; exit 1; fi
  rm -rf "$tmp" "$THIRD/dl"
  touch "$HDR/.complete"
fi
ln -sfn "meshlab-$MLVER" "$THIRD/meshlab"

if [ "${SKIP_BUILD:-0}" != 1 ]; then
  echo "[setup] configuring and building"
  cmake -S "$ROOT" -B "$ROOT/build" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$ROOT/build" -j"$(nproc)"
fi
echo "[setup] done"
