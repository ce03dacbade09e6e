# Sourced by lamina's scripts: where the shaderc build is cached, and the variables Vulkan and
# the build need. Safe to source from any directory.

lamina_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export LAMINA_CACHE="${LAMINA_CACHE:-$HOME/.cache/lamina}"

# The shaderc-sys version pinned in Cargo.lock names the cached static library, so a version
# bump builds a fresh one instead of linking a stale one.
lamina_shaderc_version="$(awk '/^name = "shaderc-sys"$/ { getline; gsub(/"/, "", $3); print $3 }' \
  "$lamina_root/Cargo.lock")"
export LAMINA_SHADERC_DIR="$LAMINA_CACHE/shaderc-sys-$lamina_shaderc_version-$(uname -m)"
if [ -f "$LAMINA_SHADERC_DIR/libshaderc_combined.a" ]; then
  export SHADERC_LIB_DIR="$LAMINA_SHADERC_DIR"
fi

# The Vulkan loader and winit want a private runtime directory.
if [ -z "${XDG_RUNTIME_DIR:-}" ] || [ ! -d "$XDG_RUNTIME_DIR" ]; then
  export XDG_RUNTIME_DIR="/tmp/lamina-runtime-$(id -u)"
  mkdir -p "$XDG_RUNTIME_DIR"
  chmod 700 "$XDG_RUNTIME_DIR"
fi
