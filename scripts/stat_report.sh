#!/usr/bin/env bash
# Runs the statistical whole-image tests (furnace, scene agreement, hard cases) longer than the
# test suite does and prints one row per comparison: the test, its statistic (the worst
# |difference| in standard errors over the regions and the image mean, or an exact quantity
# that must be 0), the threshold, and pass/fail.
#
#   bash scripts/stat_report.sh [SCALE] [BUILD_DIR]
#
# SCALE (default 8) becomes CLBDPT_TEST_SCALE, which multiplies every pass count: thresholds
# stay in standard errors, so a longer run is a sharper test of the same claims. BUILD_DIR
# (default build/ in the repository) is configured and clbdpt_tests built there if needed.
# Extra environment: STAT_FILTER overrides the gtest filter; the full test log is kept in
# BUILD_DIR/stat_report.log. Exit status: 0 if every comparison passed, 1 if one failed, 2 if
# the build failed.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
scale="${1:-8}"
build="${2:-$repo/build}"
filter="${STAT_FILTER:-*FurnaceTest*:*SceneAgreementTest*:SceneAgreement.*:HardCases.*:*SceneScaleTest*:Textures.*}"

if ! [[ "$scale" =~ ^[1-9][0-9]*$ ]]; then
    echo "stat_report: SCALE must be a positive integer, got '$scale'" >&2
    exit 2
fi

# Configure and build quietly; on failure show the build's output and stop.
mkdir -p "$build"
build_log="$build/stat_report_build.log"
if ! { [[ -f "$build/CMakeCache.txt" ]] || cmake -S "$repo" -B "$build" -DCLBDPT_BUILD_BENCH=OFF; } >"$build_log" 2>&1 ||
   ! cmake --build "$build" -j"$(nproc)" --target clbdpt_tests >>"$build_log" 2>&1; then
    tail -40 "$build_log" >&2
    echo "stat_report: build failed (full log: $build_log)" >&2
    exit 2
fi

log="$build/stat_report.log"
start=$(date +%s)
set +e
CLBDPT_TEST_SCALE="$scale" "$build/clbdpt_tests" --gtest_filter="$filter" >"$log" 2>&1
status=$?
set -e
seconds=$(($(date +%s) - start))

awk -v scale="$scale" -v seconds="$seconds" '
    /^STAT / {
        n++; test[n] = $2; stat[n] = $3; thr[n] = $4; res[n] = $5
        if (length($2) > w) w = length($2)
        if ($5 != "pass") failed++
    }
    END {
        if (w < 4) w = 4
        printf "%-" w "s  %10s  %9s  %s\n", "test", "statistic", "threshold", "result"
        for (i = 1; i <= n; i++) printf "%-" w "s  %10s  %9s  %s\n", test[i], stat[i], thr[i], res[i]
        printf "\n%d comparisons, %d failed; CLBDPT_TEST_SCALE=%s; %d s\n", n, failed, scale, seconds
    }' "$log"

# A test can fail without a STAT line (a render that threw, a crash): gtest's own verdict counts.
if [[ $status -ne 0 ]]; then
    echo "stat_report: clbdpt_tests exited with status $status; failures (see $log):" >&2
    grep -E '^\[  FAILED  \]|Failure|error' "$log" | head -40 >&2 || true
    exit 1
fi
if grep -q '^STAT .* fail$' "$log"; then exit 1; fi
exit 0
