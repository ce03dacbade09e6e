#!/usr/bin/env bash
# Sets up a Debian 12 machine for lamina: system packages (only those missing), one static
# shaderc archive, and a build of the lamina binary. The test command (scripts/test.sh) builds
# the tests.
#
# shaderc: Debian 12's libshaderc-dev (shaderc 2023.2) ships libshaderc_combined.a without the
# glslang and SPIRV-Tools objects it calls; those come as static archives in glslang-dev and
# spirv-tools. Merged into one archive they link like shaderc's own combined build, in seconds
# (the test suite compiles every entry point with it). Where they are missing, shaderc is built
# from source once (about 15 minutes on two cores). Either way the archive is cached under
# $LAMINA_SHADERC_DIR, with a SOURCE file saying which it is.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"

packages=(
  mesa-vulkan-drivers libvulkan1 libvulkan-dev vulkan-validationlayers vulkan-tools
  libshaderc-dev glslang-dev spirv-tools
  librenderdoc python3-renderdoc renderdoccmd
  cmake ninja-build python3 git g++ valgrind
  xvfb xauth libxkbcommon-x11-0 libx11-xcb1 libxcursor1 libxrandr2 libxi6
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

# The system archives merged into $LAMINA_SHADERC_DIR/libshaderc_combined.a; false when one of
# them is missing.
merge_system_shaderc() {
  local multiarch libdir
  multiarch="$(dpkg-architecture -qDEB_HOST_MULTIARCH 2>/dev/null || echo "$(uname -m)-linux-gnu")"
  libdir="/usr/lib/$multiarch"
  local archives=(
    libshaderc_combined.a libglslang.a libMachineIndependent.a libGenericCodeGen.a
    libOSDependent.a libOGLCompiler.a libSPIRV.a libSPIRV-Tools-opt.a libSPIRV-Tools.a
  )
  local a
  for a in "${archives[@]}"; do
    [ -f "$libdir/$a" ] || return 1
  done
  mkdir -p "$LAMINA_SHADERC_DIR"
  local out="$LAMINA_SHADERC_DIR/libshaderc_combined.a"
  {
    echo "create $out.tmp"
    for a in "${archives[@]}"; do echo "addlib $libdir/$a"; done
    echo "save"
    echo "end"
  } | ar -M
  mv "$out.tmp" "$out"
  # shaderc-sys bundles the archive into its rlib and re-runs only when SHADERC_LIB_DIR changes.
  cargo clean --locked -p shaderc-sys >/dev/null 2>&1 || true
  dpkg-query -W -f='${Package} ${Version}\n' libshaderc-dev glslang-dev spirv-tools \
    | sed 's/^/debian: /' > "$LAMINA_SHADERC_DIR/SOURCE"
}

if [ -n "${SHADERC_LIB_DIR:-}" ]; then
  echo "== shaderc: $SHADERC_LIB_DIR ($(cat "$SHADERC_LIB_DIR/SOURCE" 2>/dev/null | paste -sd, || echo 'given'))"
elif merge_system_shaderc; then
  export SHADERC_LIB_DIR="$LAMINA_SHADERC_DIR"
  echo "== shaderc: Debian's static archives merged into $SHADERC_LIB_DIR"
else
  echo "== building shaderc from source once into $LAMINA_SHADERC_DIR (about 15 minutes)"
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
  echo "source: shaderc-sys $lamina_shaderc_version built from its sources" > "$LAMINA_SHADERC_DIR/SOURCE"
  rm -rf "$build_dir"
  export SHADERC_LIB_DIR="$LAMINA_SHADERC_DIR"
fi

echo "== building lamina"
cargo build --locked
