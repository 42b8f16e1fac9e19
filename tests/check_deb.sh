#!/usr/bin/env bash
# The .deb (CPack) puts every plugin in Debian's MeshLab plugin folder and depends on this MeshLab.
set -euo pipefail
BUILD="$1"
cd "$BUILD"
rm -f pectus-meshlab_*.deb
cpack -G DEB >/dev/null
deb=$(ls pectus-meshlab_*.deb)
fail=0
listing=$(dpkg -c "$deb")
info=$(dpkg -I "$deb")
for so in plugins/lib*.so; do
  if echo "$listing" | grep -q "./usr/lib/x86_64-linux-gnu/meshlab/plugins/$(basename "$so")$"; then
    echo "ok   $(basename "$so") in the plugin folder of $deb"
  else
    echo "FAIL $(basename "$so") missing from $deb"; fail=1
  fi
done
ver=$(dpkg-query -W -f='${Version}' meshlab | grep -oE '^[0-9]+\.[0-9]+')
if echo "$info" | grep -q "meshlab (>= $ver)"; then echo "ok   depends on meshlab >= $ver"; else echo "FAIL no meshlab dependency"; fail=1; fi
exit $fail
