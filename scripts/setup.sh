#!/usr/bin/env bash
# Installs everything pectus-meshlab needs on a fresh Debian bookworm machine (run as root),
# fetches MeshLab's headers from Debian's source package of the installed MeshLab version,
# and configures + builds the project into build/.
#   scripts/setup.sh            # install deps, fetch headers, build
#   SKIP_BUILD=1 scripts/setup.sh
# The headers and the compiler cache are kept outside the clone (scripts/cache.sh).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
. "$ROOT/scripts/cache.sh"   # ccache and the headers outside the clone
THIRD="$ROOT/third_party"
export DEBIAN_FRONTEND=noninteractive

SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi

PKGS=(meshlab qtbase5-dev libqt5opengl5-dev libglew-dev libeigen3-dev
      libtet1.5-dev libsuitesparse-dev libomp-dev libgtest-dev
      xvfb xauth cmake g++ make dpkg-dev python3 python3-numpy
      python3-matplotlib python3-scipy imagemagick libcgal-dev calculix-ccx libopenblas0-pthread
      liblemon-dev gmsh libcgal-demo parallel libopenmesh-apps libnifti2-dev ccache debootstrap universal-ctags
      chromium)
# chromium (22 packages without recommends, 122 MB): tests/e2e/test_report.py shows the main job's report.html in
# headless Chromium and checks the screenshot

missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

# The deb-src counterpart of this machine's `deb` entry for the Debian archive (the entry whose suites
# include the release's codename and whose components include main), as deb822 on stdout: the same URIs,
# suites, components and Signed-By. Read from the deb822 files /etc/apt/sources.list.d/*.sources and the
# one-line files /etc/apt/sources.list and sources.list.d/*.list (there, every `deb` line of a URI that
# carries the codename's main). Prints nothing if there is no such entry.
#   debsrc_entry [APT_DIR [CODENAME]]   defaults: /etc/apt, VERSION_CODENAME of /etc/os-release
debsrc_entry() {
  local etc="${1:-/etc/apt}" codename="${2:-}"
  if [ -z "$codename" ]; then codename="$(. /etc/os-release 2>/dev/null && echo "${VERSION_CODENAME:-}")"; fi
  [ -n "$codename" ] || return 0
  local deb822=() oneline=() f
  for f in "$etc"/sources.list.d/*.sources; do [ -f "$f" ] && deb822+=("$f"); done
  for f in "$etc"/sources.list "$etc"/sources.list.d/*.list; do [ -f "$f" ] && oneline+=("$f"); done
  local out=""
  if [ ${#deb822[@]} -gt 0 ]; then
    # paragraph mode: one stanza per record; continuation lines (a leading blank) belong to the field above
    out+="$(awk -v cn="$codename" 'BEGIN { RS = ""; FS = "\n" }
      function has(list, word,   n, w, i) { n = split(list, w, /[ \t]+/); for (i = 1; i <= n; i++) if (w[i] == word) return 1; return 0 }
      {
        split("", f); key = ""
        for (i = 1; i <= NF; i++) {
          line = $i
          if (line ~ /^#/) continue
          if (line ~ /^[ \t]/) { if (key != "") f[key] = f[key] "\n" line; continue }
          p = index(line, ":"); if (!p) { key = ""; continue }
          key = tolower(substr(line, 1, p - 1)); v = substr(line, p + 1)
          sub(/^[ \t]+/, "", v); sub(/[ \t]+$/, "", v); f[key] = v
        }
        if (tolower(f["enabled"]) == "no" || !has(f["types"], "deb") || !has(f["suites"], cn) || !has(f["components"], "main")) next
        if (n++) print ""
        print "Types: deb-src"; print "URIs: " f["uris"]; print "Suites: " f["suites"]; print "Components: " f["components"]
        if ("signed-by" in f) print "Signed-By:" (f["signed-by"] ~ /^\n/ ? "" : " ") f["signed-by"]
      }' "${deb822[@]}")"
  fi
  if [ ${#oneline[@]} -gt 0 ]; then
    local lines
    lines="$(awk -v cn="$codename" '
      { sub(/#.*/, "") }
      $1 == "deb" {
        opts = ""; i = 2
        if ($2 ~ /^\[/) { for (; i <= NF; i++) { opts = opts " " $i; if ($i ~ /\]$/) { i++; break } } }
        if (i + 1 > NF) next
        uri = $i; suite = $(i + 1); comps = ""
        for (j = i + 2; j <= NF; j++) comps = comps (comps == "" ? "" : " ") $j
        gsub(/[][]/, " ", opts); key = ""; nopt = split(opts, o, /[ \t]+/)
        for (j = 1; j <= nopt; j++) if (tolower(o[j]) ~ /^signed-by=/) key = substr(o[j], 11)
        n++; U[n] = uri; S[n] = suite; C[n] = comps; K[n] = key
        if (suite == cn && (" " comps " ") ~ / main /) main[uri] = 1
      }
      END {
        for (j = 1; j <= n; j++) {
          if (!(U[j] in main)) continue
          if (m++) print ""
          print "Types: deb-src"; print "URIs: " U[j]; print "Suites: " S[j]; print "Components: " C[j]
          if (K[j] != "") print "Signed-By: " K[j]
        }
      }' "${oneline[@]}")"
    if [ -n "$lines" ]; then out+="${out:+$'\n\n'}$lines"; fi
  fi
  [ -z "$out" ] || printf '%s\n' "$out"
}

# deb-src for MeshLab's source package (its headers, below), from the machine's own apt sources
SRCLIST=/etc/apt/sources.list.d/pectus-debsrc.sources
need_update=0
if [ ! -f "$SRCLIST" ]; then
  entry="$(debsrc_entry)"
  if [ -z "$entry" ]; then
    echo "[setup] no deb entry for the Debian archive (this release's suite, component main) in /etc/apt: add one"
    exit 1
  fi
  printf '%s\n' "$entry" | $SUDO tee "$SRCLIST" >/dev/null
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
  ORIG="$(ls "$THIRD"/dl/meshlab_*.orig.tar.* | sed -n 1p)"
  tmp="$(mktemp -d)"
  tar -xf "$ORIG" -C "$tmp"
  top="$(ls "$tmp")"
  # patches of the Debian package (headers may be patched)
  DEB="$(ls "$THIRD"/dl/meshlab_*.debian.tar.* | sed -n 1p)"
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
