#!/usr/bin/env bash
# The README's first command: install dependencies, build, and render the bundled Cornell box to
# ./cornell-box.png in the directory you run it from.
set -euo pipefail
here=$(pwd)
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh" clbdpt
cd "$here"
"$root/${BUILD_DIR:-build}/clbdpt" render "$root/scenes/cornell-box/cornell-box.json" -o cornell-box.png "$@"
