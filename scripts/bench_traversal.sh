#!/usr/bin/env bash
# Builds traversal_bench in Release (Embree is linked in when libembree-dev is installed) and runs
# it. Arguments go to the benchmark, e.g.:
#   scripts/bench_traversal.sh --triangles 100000 --rays 500000 --repeats 7
#   scripts/bench_traversal.sh --scene spheres --only random --no-embree
# BUILD_DIR (default build-release) picks the build directory; extra CMake arguments can be
# passed in CMAKE_ARGS.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$root/build-release}"

# shellcheck disable=SC2086  # CMAKE_ARGS is a list of arguments
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCLBDPT_BUILD_BENCH=ON ${CMAKE_ARGS:-} > /dev/null
cmake --build "$build" --target traversal_bench -j "$(nproc)"
exec "$build/traversal_bench" "$@"
