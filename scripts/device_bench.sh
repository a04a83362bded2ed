#!/usr/bin/env bash
# Samples/s on a GPU through its vendor's OpenCL, from the bundle scripts/device_bundle.sh made
# (run on the GPU machine, in a copy of the repository that holds the bundle).
#   scripts/device_bench.sh [DIR=.gpu]
# Each bundled scene for each size in SIZES (default "native large": the scene's own size, and
# 1024 px without media, 512 px with), pt and bdpt, whole passes for SECONDS_EACH (default 2)
# each; where DIR/bin/clbdpt_old exists it is run interleaved with DIR/bin/clbdpt and the ratio
# printed, their Cornell box images compared bit for bit, and each bundled scene's default
# render (its own size and spp, the pilot's choice) timed with both. Then --profile of the
# Cornell box, and, where CUDA's ptxas is at hand, the registers and spills of the pt and bdpt
# kernels for sm_90.
# Logs, stats and the Cornell box images (PFM, seed 0, 64 spp, 256 px) go to $OUT (default
# /tmp/device_bench). OPENCL_LIB names the driver's OpenCL library if it is not NVIDIA's usual.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
dir="$(cd "${1:-$root/.gpu}" && pwd)"
out="${OUT:-/tmp/device_bench}"
seconds="${SECONDS_EACH:-2}"
mkdir -p "$out/stats" /tmp/device_bench_icd /tmp/device_bench_libs /tmp/device_bench_cache
lib="${OPENCL_LIB:-/usr/local/nvidia/lib64/libnvidia-opencl.so}"
[ -e "$lib" ] || lib=$(find / -xdev -name 'libnvidia-opencl.so*' 2>/dev/null | head -1)
[ -n "$lib" ] || { echo "device_bench: no GPU OpenCL library found (set OPENCL_LIB)" >&2; exit 2; }
echo "$lib" >/tmp/device_bench_icd/gpu.icd
tar -xJf "$dir/libs.tar.xz" -C /tmp/device_bench_libs
export OCL_ICD_VENDORS=/tmp/device_bench_icd CLBDPT_CACHE_DIR=/tmp/device_bench_cache
export LD_LIBRARY_PATH=/tmp/device_bench_libs${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
bins=clbdpt
[ -x "$dir/bin/clbdpt_old" ] && bins="clbdpt_old clbdpt"
"$dir/bin/clbdpt" devices || exit 3

rate() {  # binary label args...: prints the label and M samples/s
  local bin=$1 label=$2
  shift 2
  timeout 120 "$dir/bin/$bin" render "$@" --stats "$out/stats/$label.json" -o /tmp/device_bench_out.exr \
    >>"$out/log.txt" 2>&1 || { echo "$label failed (see log.txt)"; return; }
  python3 -c "import json,sys; print('%-40s %8.2f' % (sys.argv[1], json.load(open(sys.argv[2]))['samples_per_second'] / 1e6))" \
    "$label" "$out/stats/$label.json"
}

cornell="$root/scenes/cornell-box/cornell-box.json"
for integrator in pt bdpt; do
  rate clbdpt "image_$integrator" "$cornell" --integrator "$integrator" --adaptive off --spp 64 >/dev/null
  cp /tmp/device_bench_out.exr "$out/cornell_$integrator.pfm"
  ls -t /tmp/device_bench_cache/*.bin | head -1 >"/tmp/device_bench_$integrator.bin"
  if [ -x "$dir/bin/clbdpt_old" ]; then
    rate clbdpt_old "image_${integrator}_old" "$cornell" --integrator "$integrator" --adaptive off --spp 64 >/dev/null
    if cmp -s /tmp/device_bench_out.exr "$out/cornell_$integrator.pfm"; then
      echo "cornell-box $integrator 64 spp: old and new images identical bit for bit"
    else
      echo "cornell-box $integrator 64 spp: old and new images DIFFER"
    fi
  fi
done
# Registers and spills, in the background while the rates are measured (CUDA's ptxas, where at
# hand). The driver's program binary is PTX text ending in a NUL, which ptxas reads as garbage.
ptxas=$(command -v ptxas || echo /usr/local/cuda/bin/ptxas)
ptxas_jobs=()
if [ -x "$ptxas" ] && [ -z "${NO_PTXAS:-}" ]; then
  for integrator in pt bdpt; do
    tr -d '\000' <"$(cat "/tmp/device_bench_$integrator.bin")" >"/tmp/device_bench_$integrator.ptx"
    timeout 240 "$ptxas" -arch=sm_90 -v "/tmp/device_bench_$integrator.ptx" -o /dev/null \
      >"$out/ptxas_$integrator.txt" 2>&1 &
    ptxas_jobs+=($!)
  done
fi
scene_file() {
  if [ "$1" = sky ]; then echo "$dir/sky/sky.json"; else echo "$root/scenes/$1/$1.json"; fi
}
scenes="${SCENES:-cornell-box cornell-specular lamp-ceiling point-spot veach-mis sky smoke cornell-fog fog-spot}"
if [ "$bins" != clbdpt ]; then
  # The default render of each bundled scene as a user runs it (pilot, adaptive sampling, image
  # written), wall seconds, old and new interleaved, twice: the first compiles the kernels the
  # pilot tries (the driver's compiler caches them), so the second pair is the one to compare.
  for scene in $scenes; do
    for bin in $bins $bins; do
      start=$(date +%s.%N)
      timeout 120 "$dir/bin/$bin" render "$(scene_file "$scene")" -o /tmp/device_bench_default.exr \
        >>"$out/log.txt" 2>&1 || echo "$scene default $bin failed (see log.txt)"
      python3 -c "import sys,time; print('%-40s %8.3f s' % (sys.argv[1], time.time() - float(sys.argv[2])))" \
        "${scene}_default_$bin" "$start"
    done
  done | tee "$out/default_seconds.txt"
fi
echo "M samples/s, $seconds s each ($(basename "$lib"))"
for size_mode in ${SIZES:-native large}; do
  for scene in $scenes; do
    size=""
    if [ "$size_mode" = large ]; then
      case $scene in smoke | cornell-fog | fog-spot) size="--width 512 --height 512" ;;
        veach-mis) size="--width 1024 --height 684" ;; *) size="--width 1024 --height 1024" ;; esac
    fi
    for integrator in pt bdpt; do
      for bin in $bins; do
        # shellcheck disable=SC2086
        rate "$bin" "${scene}_${size_mode}_${integrator}_$bin" "$(scene_file "$scene")" --integrator "$integrator" \
          $size --time "$seconds"
      done
    done
  done
done | tee "$out/rates.txt"
if [ "$bins" != clbdpt ]; then
  python3 - "$out/rates.txt" <<'PY'
import sys
rows = {}
for line in open(sys.argv[1]):
    parts = line.split()
    if len(parts) == 2:
        rows[parts[0]] = float(parts[1])
for label, new in rows.items():
    if label.endswith("_clbdpt") and label[:-7] + "_clbdpt_old" in rows:
        print("%-32s new / old %.2f" % (label[:-7], new / rows[label[:-7] + "_clbdpt_old"]))
PY
fi
for integrator in pt bdpt; do
  for threads in ${PROFILE_THREADS:-1 auto}; do
    flag=""
    [ "$threads" = 1 ] && flag="--collect-threads 1"
    echo "profile, Cornell box $integrator 1024 px, collect threads $threads:"
    # shellcheck disable=SC2086
    "$dir/bin/clbdpt" render "$cornell" --integrator "$integrator" --width 1024 --height 1024 --time "$seconds" \
      --profile $flag -o /tmp/device_bench_out.exr 2>&1 | grep -E 'profile|samples/s'
  done
done
if [ ${#ptxas_jobs[@]} -gt 0 ]; then
  wait "${ptxas_jobs[@]}"
  for integrator in pt bdpt; do
    echo "ptxas sm_90, $integrator kernel:"
    grep -E 'registers|spill|stack|fatal' "$out/ptxas_$integrator.txt" | head -6
  done
fi
# Few files come back from a lent machine: the stats as one archive.
tar -czf "$out/stats.tgz" -C "$out" stats && rm -rf "$out/stats"
