#!/usr/bin/env bash
# Builds the host code with AddressSanitizer and UndefinedBehaviorSanitizer (CMake option
# CLBDPT_SANITIZE) in build-sanitize/ and runs the whole test suite under them. Any report
# fails the test that triggered it (-fno-sanitize-recover). The kernels run inside PoCL, which
# is not instrumented; leaks inside the OpenCL driver, LLVM and OpenImageIO are suppressed
# (scripts/lsan.supp), leaks in clbdpt are not.
#
#   scripts/sanitize.sh [ctest arguments, e.g. -R Cli]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/${SANITIZE_BUILD_DIR:-build-sanitize}"
"$root/scripts/install-deps.sh"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCLBDPT_SANITIZE=ON -DCLBDPT_BUILD_BENCH=OFF >/dev/null
cmake --build "$build" -j"$(nproc)"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=0"
export LSAN_OPTIONS="suppressions=$root/scripts/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
start=$(date +%s)
cd "$build"
status=0
ctest --output-on-failure -j"${CTEST_JOBS:-$(nproc)}" "$@" || status=$?
echo "sanitize: ctest under ASan+UBSan took $(( $(date +%s) - start )) s, status $status"
exit "$status"
