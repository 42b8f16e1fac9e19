# Sourced by the GUI screenshot scripts: gui_plugins HOST HOME readies the GUI of a newer MeshLab release in its
# Debian userland to load this project's plugins of build-HOST from the per-user extra-plugins folder under HOME.
# MeshLab skips the per-user plugins when one of its own fails to load, so the libraries its plugins need that
# the userland's minimal install left out are installed first.
gui_plugins() {
  local host="$1" home="$2" extra
  chroot "$ROOT/.hosts/forky" apt-get install -y -q --no-install-recommends libmuparser2v5 libqhull-r8.0 lib3ds-1-3 \
    libopenctm1 >/dev/null
  extra="$home/.local/share/VCG/MeshLab_64bit_fp/MeshLabExtraPlugins/$host"
  mkdir -p "$extra" && cp "$ROOT"/build-"$host"/plugins/*.so "$extra/"
}
