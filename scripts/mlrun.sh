#!/usr/bin/env bash
# Runs a MeshLab filter script with this project's plugins, headless, on either MeshLab host, with
# meshlabserver's arguments:
#   scripts/mlrun.sh [--host 2020.09|2022.02|2025.07] [-i in]... [-s script.mlx] [-o out [-l N] [-m vc fq ...]]...
# 2020.09 (default): bookworm's meshlabserver from build/prefix, under xvfb-run.
# 2025.07: pectus-mlrun in the Debian forky userland (.hosts/forky, build-2025.07/), through chroot;
# 2022.02: the same in the Debian trixie userland (.hosts/trixie, build-2022.02/). On first use it makes
#   the userland and the build with scripts/host.sh (about 10 min) and says so;
#   PECTUS_MLRUN_NO_SETUP=1 refuses instead. The repository, /tmp, the current folder and the folders of
#   the files named by -i, -o and -s and of $PECTUS_RESULTS_FILE appear inside the userland at their own paths
#   (bind mounts in a private mount namespace, gone when the command ends), so paths mean the same on both hosts.
# $PECTUS_RESULTS_FILE: the file each filter's results are appended to, one JSON line per filter (on 2020.09 the
#   plugins write it, on the newer releases pectus-mlrun from the filters' return values).
# Run as root (chroot, mount namespaces).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
HOST=2020.09
if [ "${1:-}" = --host ]; then
  [ $# -ge 2 ] || { echo "mlrun: --host needs 2020.09, 2022.02 or 2025.07" >&2; exit 2; }
  HOST="$2"; shift 2
fi

case "$HOST" in
  2020.09)
    EXE="${PECTUS_PREFIX:-$ROOT/build/prefix}/bin/meshlabserver"
    if [ ! -x "$EXE" ]; then
      echo "mlrun: $EXE is missing: build the bookworm host first (scripts/setup.sh)" >&2; exit 2
    fi
    exec xvfb-run -a -s "-screen 0 1024x768x24" "$EXE" "$@"
    ;;
  *)  # the release's Debian suite (scripts/meshlab_hosts.txt)
    SUITE="$(awk -v r="$HOST" '$1 == r {print $2}' "$ROOT/scripts/meshlab_hosts.txt")"
    if [ -z "$SUITE" ]; then
      echo "mlrun: unknown host '$HOST' (2020.09$(awk '!/^#/ && NF {printf ", %s", $1}' "$ROOT/scripts/meshlab_hosts.txt"))" >&2; exit 2
    fi
    ;;
esac

HOSTDIR="${PECTUS_HOST_DIR:-$ROOT/.hosts/$SUITE}"
BUILD="$ROOT/build-$HOST"
EXE="$BUILD/bin/pectus-mlrun"
if [ ! -f "$HOSTDIR/.complete-pkgs" ] || [ ! -x "$EXE" ]; then
  if [ "${PECTUS_MLRUN_NO_SETUP:-0}" = 1 ]; then
    echo "mlrun: the MeshLab $HOST userland or build is missing ($HOSTDIR, $EXE): make them with scripts/host.sh $HOST" >&2
    exit 2
  fi
  echo "mlrun: first use of MeshLab $HOST: making the $SUITE userland and the build with scripts/host.sh $HOST" >&2
  "$ROOT/scripts/host.sh" "$HOST" >&2
fi
if [ "$(id -u)" != 0 ]; then
  echo "mlrun: --host $HOST runs pectus-mlrun through chroot: run as root" >&2; exit 2
fi

# folders to show inside the userland at their own paths
binds=("$ROOT" /tmp "$PWD")
prev=""
for a in "$@"; do
  case "$prev" in
    -i|-o|-s)
      f="$(readlink -m -- "$a")"
      binds+=("$(dirname "$f")")
      ;;
  esac
  prev="$a"
done
if [ -n "${PECTUS_RESULTS_FILE:-}" ]; then
  binds+=("$(dirname "$(readlink -m -- "$PECTUS_RESULTS_FILE")")")
fi
uniq=()
for d in "${binds[@]}"; do
  [ -d "$d" ] || continue
  d="$(readlink -f "$d")"
  skip=0
  for u in "${uniq[@]}"; do case "$d/" in "$u"/*) skip=1;; esac; done
  [ $skip = 1 ] || uniq+=("$d")
done

# the environment the runner sees: a clean one, plus the variables that steer the filters
envs=(PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root LANG=C.UTF-8)
for v in OMP_NUM_THREADS OMP_WAIT_POLICY PECTUS_MLRUN_PLUGINS PECTUS_MLRUN_VERBOSE PECTUS_RESULTS_FILE; do
  [ -n "${!v:-}" ] && envs+=("$v=${!v}")
done

exec unshare --mount --propagation private bash -c '
  set -e; root=$1; n=$2; shift 2
  for ((i = 0; i < n; i++)); do mkdir -p "$root$1"; mount --bind "$1" "$root$1"; shift; done
  cwd=$1; ne=$2; shift 2
  envs=("${@:1:ne}"); shift "$ne"
  exec chroot "$root" /usr/bin/env -i "${envs[@]}" /bin/sh -c "cd \"\$0\" && exec \"\$@\"" "$cwd" "$@"' \
  bash "$HOSTDIR" "${#uniq[@]}" "${uniq[@]}" "$PWD" "${#envs[@]}" "${envs[@]}" "$EXE" "$@"
