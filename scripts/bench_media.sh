#!/usr/bin/env bash
# Samples per second of scenes with and without participating media (issue: media compile into
# the kernels only where a scene has them, so other scenes keep their speed).
#   scripts/bench_media.sh [REPS=5] [SPP=64]
# With OLD=path/to/other/clbdpt set, every scene without media is also rendered by that binary,
# interleaved with this build's runs, and the ratio of the medians is printed (this build over
# OLD: the "within 2% of before" check). Media scenes are compared with their vacuum twins
# (the same meshes and lights without media) in the same run. INTEGRATORS (default "bdpt pt"),
# VACUUM_SCENES and MEDIA_SCENES choose a subset.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
reps=${1:-5}
spp=${2:-64}
new="$root/${BUILD_DIR:-build}/clbdpt"
old=${OLD:-}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

run() {  # binary scene integrator label
  "$1" render "$root/scenes/$2/$2.json" --integrator "$3" --sampler sobol --spp "$spp" --width 256 --height 256 \
    -o "$out/img.exr" --stats "$out/s.json" >/dev/null 2>&1
  python3 -c "import json,sys; print(sys.argv[1], json.load(open(sys.argv[2]))['samples_per_second'])" "$4" "$out/s.json" \
    >>"$out/runs.txt"
}

for rep in $(seq "$reps"); do
  for integrator in ${INTEGRATORS:-bdpt pt}; do
    for scene in ${VACUUM_SCENES-cornell-box point-spot cornell-specular}; do
      run "$new" "$scene" "$integrator" "$scene/$integrator/new"
      if [ -n "$old" ]; then run "$old" "$scene" "$integrator" "$scene/$integrator/old"; fi
    done
    for scene in ${MEDIA_SCENES-fog-spot cornell-fog smoke}; do run "$new" "$scene" "$integrator" "$scene/$integrator/new"; done
  done
done

python3 - "$out/runs.txt" <<'PY'
import collections, statistics, sys
runs = collections.defaultdict(list)
for line in open(sys.argv[1]):
    key, value = line.split()
    runs[key].append(float(value))
med = {k: statistics.median(v) for k, v in runs.items()}
twin = {"fog-spot": "point-spot", "cornell-fog": "cornell-specular", "smoke": "cornell-box"}
print(f"{'scene':18s} {'integ':5s} {'M samples/s':>12s}  comparison (median of {len(next(iter(runs.values())))} runs)")
for key in sorted(k for k in med if k.endswith("/new")):
    scene, integ, _ = key.split("/")
    line = f"{scene:18s} {integ:5s} {med[key] / 1e6:12.3f}"
    old = f"{scene}/{integ}/old"
    if old in med:
        line += f"  this build / OLD = {med[key] / med[old]:.3f}"
    if scene in twin and f"{twin[scene]}/{integ}/new" in med:
        ref = f"{twin[scene]}/{integ}/new"
        line += f"  / vacuum twin {twin[scene]} = {med[key] / med[ref]:.3f}"
    print(line)
PY
