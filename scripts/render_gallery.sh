#!/usr/bin/env bash
# Renders every bundled scene into docs/images/<scene>.png (the pictures in the README).
# Usage: scripts/render_gallery.sh [SPP=128] [extra clbdpt options...]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
spp=${1:-128}
shift || true
bin="$root/${BUILD_DIR:-build}/clbdpt"
mkdir -p "$root/docs/images"
for scene in cornell-box cornell-specular lamp-ceiling veach-mis point-spot sky fog-spot cornell-fog smoke; do
  "$bin" render "$root/scenes/$scene/$scene.json" --spp "$spp" --sampler sobol \
    -o "$root/docs/images/$scene.png" --stats "$root/docs/images/$scene.json" "$@"
done
