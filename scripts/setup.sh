#!/usr/bin/env bash
# Sets up a Debian 12 machine for lamina: system packages (only those missing), the cached
# shaderc build (about 10 minutes, once per machine), and a build of lamina itself.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"

packages=(
  mesa-vulkan-drivers libvulkan1 libvulkan-dev vulkan-validationlayers vulkan-tools
  cmake ninja-build python3 git g++ valgrind
  xvfb libxkbcommon-x11-0 libx11-xcb1 libxcursor1 libxrandr2 libxi6
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
  echo "== installing: ${missing[*]}"
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "== system packages: all present"
fi

if ! command -v cargo >/dev/null; then
  echo "error: cargo not found; install Rust stable (https://rustup.rs) first" >&2
  exit 1
fi

source "$root/scripts/env.sh"
if [ -z "${SHADERC_LIB_DIR:-}" ]; then
  echo "== building shaderc from source once into $LAMINA_SHADERC_DIR (about 10 minutes)"
  build_dir="$LAMINA_CACHE/shaderc-build"
  # An empty SHADERC_LIB_DIR makes shaderc-sys find no library and build its own sources,
  # even where Debian's (unusable) libshaderc is installed.
  mkdir -p "$build_dir/no-library"
  SHADERC_LIB_DIR="$build_dir/no-library" \
    cargo build --locked -p shaderc-sys --target-dir "$build_dir"
  lib="$(find "$build_dir" -path '*/out/lib/libshaderc_combined.a' -print -quit)"
  if [ -z "$lib" ]; then
    echo "error: the shaderc build produced no libshaderc_combined.a under $build_dir" >&2
    exit 1
  fi
  mkdir -p "$LAMINA_SHADERC_DIR"
  cp "$lib" "$LAMINA_SHADERC_DIR/libshaderc_combined.a.tmp"
  mv "$LAMINA_SHADERC_DIR/libshaderc_combined.a.tmp" "$LAMINA_SHADERC_DIR/libshaderc_combined.a"
  rm -rf "$build_dir"
  export SHADERC_LIB_DIR="$LAMINA_SHADERC_DIR"
else
  echo "== shaderc: cached in $SHADERC_LIB_DIR"
fi

echo "== building lamina"
cargo build --locked --all-targets
