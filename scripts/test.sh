#!/usr/bin/env bash
# Runs lamina's tests (lavapipe or any Vulkan device, validation layer on).
set -euo pipefail
source "$(dirname "$0")/env.sh"
cd "$lamina_root"
exec cargo test --locked "$@"
