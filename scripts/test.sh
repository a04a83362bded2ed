#!/usr/bin/env bash
# The README's second command: install dependencies, build everything, run the whole test suite
# (GoogleTest through CTest) on PoCL.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh"
cd "$root/${BUILD_DIR:-build}"
ctest --output-on-failure -j"${CTEST_JOBS:-$(nproc)}"
