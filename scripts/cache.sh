# Sourced by scripts/setup.sh, host.sh and sanitize.sh: what set-up keeps outside the clone, so that a
# second clone on the same machine reuses it.
#  - PECTUS_CACHE (default /var/cache/pectus-meshlab when it can be written, else <clone>/.cache):
#      ccache/       ccache's objects for every build tree (bookworm, the newer MeshLab hosts, sanitizers)
#      hosts/        the Debian userlands of the newer MeshLab releases and their MeshLab headers
#      third_party/  MeshLab's headers for the bookworm build
#  - <clone>/.hosts and <clone>/third_party are links into it, unless they are folders of their own already.
# Each item is remade when its inputs change: ccache hashes the compiler, flags and sources; host.sh checks the
# userland's packages; the headers are kept per MeshLab version.
# ROOT must be set (the clone).
if [ -z "${PECTUS_CACHE:-}" ]; then
  if mkdir -p /var/cache/pectus-meshlab 2>/dev/null && [ -w /var/cache/pectus-meshlab ]; then
    PECTUS_CACHE=/var/cache/pectus-meshlab
  else
    PECTUS_CACHE="$ROOT/.cache"
  fi
fi
export PECTUS_CACHE
mkdir -p "$PECTUS_CACHE/ccache" "$PECTUS_CACHE/hosts" "$PECTUS_CACHE/third_party"

# ccache (CMakeLists.txt uses it as the compiler launcher when it is installed). Paths under the clone are
# hashed relative to it, so clones in other folders share the objects.
export CCACHE_DIR="${CCACHE_DIR:-$PECTUS_CACHE/ccache}"
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$ROOT}"
export CCACHE_NOHASHDIR="${CCACHE_NOHASHDIR:-1}"
export CCACHE_MAXSIZE="${CCACHE_MAXSIZE:-8G}"

# cache_link NAME FOLDER: <clone>/NAME -> $PECTUS_CACHE/FOLDER, unless <clone>/NAME is a folder of its own
cache_link() {
  local target="$PECTUS_CACHE/$2"
  if [ -L "$ROOT/$1" ] || [ ! -e "$ROOT/$1" ]; then
    [ "$(readlink "$ROOT/$1" 2>/dev/null)" = "$target" ] || ln -sfn "$target" "$ROOT/$1"
  fi
}
if [ "$PECTUS_CACHE" != "$ROOT/.cache" ]; then
  cache_link .hosts hosts
  cache_link third_party third_party
fi
