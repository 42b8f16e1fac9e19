#!/usr/bin/env bash
# Sets everything up on a fresh machine (as root), builds, and runs the main job through the real
# meshlabserver; prints what it found and names the output folder.
#   scripts/run_main.sh [output-folder]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh" >"${TMPDIR:-/tmp}/pectus-setup.log" 2>&1 || { cat "${TMPDIR:-/tmp}/pectus-setup.log"; exit 1; }
export PECTUS_PREFIX="$ROOT/build/prefix"
exec /usr/bin/python3 "$ROOT/python/run_main.py" "$@"
