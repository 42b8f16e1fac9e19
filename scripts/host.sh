#!/usr/bin/env bash
# Builds the plugins for a newer MeshLab on a Debian bookworm machine (run as root): MeshLab 2025.07 from
# Debian forky, or MeshLab 2022.02 from Debian trixie.
#  1. a userland of that suite in .hosts/<suite> (debootstrap --variant=minbase with the sid script), from
#     the Debian mirror this machine's apt sources name;
#  2. the suite's meshlab and the build dependencies installed there;
#  3. MeshLab's headers (src/common + vcglib) from that version's orig tarball, taken from the mirror's pool
#     (the matching .dsc is not always published, so `apt-get source` is not used), into
#     .hosts/meshlab-<version>; and the source of the TetGen that bookworm installs (1.5.0, checked by its
#     sha256) into .hosts/tetgen-1.5.0, built into every release's plugins so that one surface gives one
#     tet mesh on every release (forky's own TetGen is 1.6, which meshes differently);
#  4. the plugins, pectus-mlrun and the unit tests configured and built in build-<release>/ by the
#     userland's compiler, the repository appearing there at its own path.
# Every step is skipped when its result already exists; each step says what it does. .hosts is a link into
# the machine's cache folder (scripts/cache.sh), so the userland outlives the clone; the build uses ccache there.
#   scripts/host.sh 2025.07            # userland + headers + build (2022.02 likewise)
#   scripts/host.sh 2025.07 userland   # only steps 1-3
#   scripts/host.sh 2025.07 shell      # a shell inside the userland, in the repository
#   scripts/host.sh 2025.07 run CMD... # one command there (e.g. ctest --test-dir build-2025.07 -L unit)
# Environment: PECTUS_HOST_DIR (default .hosts/<suite>), PECTUS_JOBS (default: the core count).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
. "$ROOT/scripts/cache.sh"   # .hosts and ccache outside the clone
MLVER_WANT="${1:-}"
# the release's Debian suite (scripts/meshlab_hosts.txt)
read -r SUITE < <(awk -v r="$MLVER_WANT" '$1 == r {print $2}' "$ROOT/scripts/meshlab_hosts.txt") || true
# the TetGen every release is built with: the source of bookworm's libtet1.5-dev
TETGEN_ORIG=tetgen_1.5.0.orig.tar.gz
TETGEN_SHA256=4d114861d5ef2063afd06ef38885ec46822e90e7b4ea38c864f76493451f9cf3
if [ -z "${MLVER_WANT}" ] || [ -z "${SUITE:-}" ]; then
  echo "host: which MeshLab? scripts/host.sh $(awk '!/^#/ && NF {printf "%s%s", s, $1; s="|"}' "$ROOT/scripts/meshlab_hosts.txt") [userland|shell|run CMD...]" >&2
  exit 2
fi
shift
HOSTDIR="${PECTUS_HOST_DIR:-$ROOT/.hosts/$SUITE}"
# the userland's own ccache objects (its ccache and compiler differ from bookworm's)
export CCACHE_DIR="$PECTUS_CACHE/ccache-$SUITE"
mkdir -p "$CCACHE_DIR"
BUILD="build-$MLVER_WANT"
JOBS="${PECTUS_JOBS:-$(nproc)}"
export DEBIAN_FRONTEND=noninteractive
say() { echo "[host-$MLVER_WANT] $*"; }

SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi

# The Debian archive's URI from this machine's apt sources: the first `deb` entry whose suites include
# this release's codename and whose components include main (deb822 .sources or one-line .list files).
debian_mirror() {
  local codename f
  codename="$(. /etc/os-release 2>/dev/null && echo "${VERSION_CODENAME:-}")"
  for f in /etc/apt/sources.list.d/*.sources; do
    [ -f "$f" ] || continue
    awk -v cn="$codename" 'BEGIN { RS = ""; FS = "\n" }
      function has(list, word,   n, w, i) { n = split(list, w, /[ \t]+/); for (i = 1; i <= n; i++) if (w[i] == word) return 1; return 0 }
      { split("", f)
        for (i = 1; i <= NF; i++) { line = $i; if (line ~ /^[#\t ]/) continue
          p = index(line, ":"); if (!p) continue
          k = tolower(substr(line, 1, p - 1)); v = substr(line, p + 1); gsub(/^[ \t]+|[ \t]+$/, "", v); f[k] = v }
        if (tolower(f["enabled"]) != "no" && has(f["types"], "deb") && has(f["suites"], cn) && has(f["components"], "main")) {
          split(f["uris"], u, /[ \t]+/); print u[1]; exit } }' "$f"
  done
  for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
    [ -f "$f" ] || continue
    awk -v cn="$codename" '{ sub(/#.*/, "") } $1 == "deb" { i = 2
        if ($2 ~ /^\[/) { for (; i <= NF; i++) if ($i ~ /\]$/) { i++; break } }
        if ($(i + 1) == cn && (" " $0 " ") ~ / main /) { print $i; exit } }' "$f"
  done
}

MIRROR="$(debian_mirror | sed -n 1p)"
MIRROR="${MIRROR%/}"
if [ -z "$MIRROR" ]; then
  say "no deb entry for the Debian archive (this release's suite, component main) in /etc/apt: add one"
  exit 1
fi

# Runs a command inside the userland. apt, g++ and the runner need no mounts; /proc is mounted only
# for the call that asks for it (MeshLab's own binary resolves $ORIGIN through /proc) and unmounted after.
in_root() { $SUDO chroot "$HOSTDIR" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root LANG=C.UTF-8 \
                DEBIAN_FRONTEND=noninteractive "$@"; }

# 1. the userland
if [ ! -f "$HOSTDIR/.complete-base" ]; then
  if ! command -v debootstrap >/dev/null; then
    say "installing debootstrap on this machine"
    $SUDO apt-get install -y -q --no-install-recommends debootstrap >/dev/null
  fi
  SCRIPT=/usr/share/debootstrap/scripts/sid   # bookworm's debootstrap has no forky script; sid's makes either suite
  say "making a Debian $SUITE userland (minbase) in $HOSTDIR from $MIRROR (about 1-2 min, 220 MB)"
  t=$(date +%s)
  $SUDO rm -rf "$HOSTDIR"
  mkdir -p "$(dirname "$HOSTDIR")"
  $SUDO debootstrap --variant=minbase "$SUITE" "$HOSTDIR" "$MIRROR" "$SCRIPT" > "$(dirname "$HOSTDIR")/debootstrap-$SUITE.log" 2>&1 || {
    say "debootstrap failed; the last lines of $(dirname "$HOSTDIR")/debootstrap-$SUITE.log:"; tail -n 20 "$(dirname "$HOSTDIR")/debootstrap-$SUITE.log"; exit 1; }
  # the suite's Release file may be past its Valid-Until on a mirror snapshot
  echo 'Acquire::Check-Valid-Until "false";' | $SUDO tee "$HOSTDIR/etc/apt/apt.conf.d/99pectus-valid-until" >/dev/null
  printf 'Types: deb\nURIs: %s\nSuites: %s\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' \
    "$MIRROR" "$SUITE" | $SUDO tee "$HOSTDIR/etc/apt/sources.list.d/debian.sources" >/dev/null
  $SUDO rm -f "$HOSTDIR/etc/apt/sources.list"
  $SUDO touch "$HOSTDIR/.complete-base"
  say "userland made in $(( $(date +%s) - t )) s"
fi

# 2. MeshLab and the build dependencies (the same list as scripts/setup.sh's, less what only the
#    bookworm benchmarks and docs need)
PKGS=(meshlab g++ make cmake qtbase5-dev libqt5opengl5-dev libglew-dev libeigen3-dev
      libsuitesparse-dev libomp-dev libgtest-dev libcgal-dev liblemon-dev libnifti2-dev zlib1g-dev
      python3 xvfb xauth dpkg-dev file ccache)
if [ ! -f "$HOSTDIR/.complete-pkgs" ] || ! in_root dpkg-query -W "${PKGS[@]}" >/dev/null 2>&1; then
  t=$(date +%s)
  say "installing $SUITE's meshlab and the build dependencies in the userland (about 2 min, +1.3 GB)"
  in_root apt-get update -q >/dev/null
  in_root apt-get install -y -q --no-install-recommends "${PKGS[@]}" > "$(dirname "$HOSTDIR")/apt-$SUITE.log" 2>&1 || {
    say "apt-get install failed; the last lines of $(dirname "$HOSTDIR")/apt-$SUITE.log:"; tail -n 20 "$(dirname "$HOSTDIR")/apt-$SUITE.log"; exit 1; }
  in_root apt-get clean
  $SUDO touch "$HOSTDIR/.complete-pkgs"
  say "packages installed in $(( $(date +%s) - t )) s"
fi
MLVER="$(in_root dpkg-query -W -f='${Version}' meshlab)"
case "$MLVER" in
  "$MLVER_WANT"*) ;;
  *) say "the userland's meshlab is $MLVER, not $MLVER_WANT: this script and the compat layer expect $MLVER_WANT"; exit 1;;
esac

# 3. headers from the orig tarball of that version (upstream version = Debian version less the revision)
UPVER="${MLVER%-*}"
HDR="$(dirname "$HOSTDIR")/meshlab-$MLVER"
if [ ! -f "$HDR/.complete" ]; then
  mkdir -p "$(dirname "$HOSTDIR")/dl"
  TARBALL="meshlab_${UPVER}.orig.tar.xz"
  URL="$MIRROR/pool/main/m/meshlab/$(printf '%s' "$TARBALL" | sed 's/~/%7E/g; s/+/%2B/g')"
  say "fetching MeshLab $UPVER's orig tarball from the mirror's pool for the headers"
  if command -v curl >/dev/null; then curl -fsSL -o "$(dirname "$HOSTDIR")/dl/$TARBALL" "$URL"
  else wget -q -O "$(dirname "$HOSTDIR")/dl/$TARBALL" "$URL"; fi
  tmp="$(mktemp -d)"
  tar -xf "$(dirname "$HOSTDIR")/dl/$TARBALL" -C "$tmp"
  top="$(ls "$tmp")"
  src="$tmp/$top"
  [ -d "$src/src/common" ] || { say "no src/common in $TARBALL"; exit 1; }
  rm -rf "$HDR"; mkdir -p "$HDR/src"
  cp -r "$src/src/common" "$HDR/src/common"
  if [ -d "$src/src/vcglib" ]; then cp -r "$src/src/vcglib" "$HDR/vcglib"
  elif [ -d "$src/vcglib" ]; then cp -r "$src/vcglib" "$HDR/vcglib"
  else say "vcglib not found in $TARBALL"; exit 1; fi
  rm -rf "$tmp" "$(dirname "$HOSTDIR")/dl/$TARBALL"
  touch "$HDR/.complete"
fi

# 3b. TetGen's source (the orig tarball: Debian's patches only add a CMake file and a main())
TET="$(dirname "$HOSTDIR")/tetgen-1.5.0"
if [ ! -f "$TET/.complete" ]; then
  mkdir -p "$(dirname "$HOSTDIR")/dl"
  say "fetching TetGen 1.5.0's source from the mirror's pool"
  dl="$(dirname "$HOSTDIR")/dl/$TETGEN_ORIG"
  if command -v curl >/dev/null; then curl -fsSL -o "$dl" "$MIRROR/pool/main/t/tetgen/$TETGEN_ORIG"
  else wget -q -O "$dl" "$MIRROR/pool/main/t/tetgen/$TETGEN_ORIG"; fi
  echo "$TETGEN_SHA256  $dl" | sha256sum -c --quiet - || { say "$TETGEN_ORIG: not the expected sha256"; exit 1; }
  tmp="$(mktemp -d)"
  tar -xf "$dl" -C "$tmp"
  [ -f "$tmp"/*/tetgen.cxx ] || { say "no tetgen.cxx in $TETGEN_ORIG"; exit 1; }
  rm -rf "$TET"; mv "$tmp"/* "$TET"; rm -rf "$tmp" "$dl"
  touch "$TET/.complete"
fi

[ "${1:-}" = userland ] && { say "userland ready: $HOSTDIR (meshlab $MLVER)"; exit 0; }

# Inside the userland the repository, the headers and /tmp appear at their own paths (bind mounts in a
# private mount namespace: they vanish with the command, nothing to unmount, parallel runs do not meet).
BINDS=("$ROOT" "$(readlink -f "$HDR")" "$(readlink -f "$TET")" /tmp "$CCACHE_DIR")
in_ns() {
  $SUDO unshare --mount --propagation private bash -c '
    set -e; root=$1; n=$2; shift 2
    for ((i = 0; i < n; i++)); do mkdir -p "$root$1"; mount --bind "$1" "$root$1"; shift; done
    exec chroot "$root" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root LANG=C.UTF-8 "$@"' \
    bash "$HOSTDIR" "${#BINDS[@]}" "${BINDS[@]}" \
    CCACHE_DIR="$CCACHE_DIR" CCACHE_BASEDIR="$CCACHE_BASEDIR" CCACHE_NOHASHDIR="$CCACHE_NOHASHDIR" \
    CCACHE_MAXSIZE="$CCACHE_MAXSIZE" "$@"
}

if [ "${1:-}" = shell ]; then
  in_ns bash -c "cd '$ROOT' && exec bash"
  exit
fi
if [ "${1:-}" = run ]; then
  shift
  in_ns bash -c "cd '$ROOT' && exec \"\$@\"" bash "$@"
  exit
fi

# 4. the build
t=$(date +%s)
say "configuring and building into $BUILD/ (-j$JOBS)"
in_ns bash -c "cd '$ROOT' && cmake -S . -B $BUILD -DCMAKE_BUILD_TYPE=Release \
    -DMESHLAB_SOURCE_DIR='$(readlink -f "$HDR")' -DMESHLAB_VERSION=${UPVER%%[~+]*} \
    -DPECTUS_TETGEN_SOURCE_DIR='$(readlink -f "$TET")' >/dev/null && \
  cmake --build $BUILD -j$JOBS"
say "built in $(( $(date +%s) - t )) s"
