#!/usr/bin/env bash
# Fuzzes the scene loaders (JSON, OBJ, MTL, textures, OpenVDB grids, and the device scene built
# from them) with
# libFuzzer under AddressSanitizer and UndefinedBehaviorSanitizer for a bounded time.
#
#   scripts/fuzz.sh [SECONDS] [JOBS]     (default 600 s, 1 job)
#
# Builds tests/fuzz/scene_loader_fuzz with clang in build-fuzz/, seeds a corpus from the bundled
# scenes and tests/data (build-fuzz/corpus, kept between runs, so runs add up), and leaves each
# crashing input in build-fuzz/crashes/. A crash found becomes a regression test by copying the
# input into tests/data/fuzz/ (FuzzRegression.* replays every file there). Prints the executions,
# corpus size and crashes at the end.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
seconds="${1:-600}"
jobs="${2:-1}"
build="$root/${FUZZ_BUILD_DIR:-build-fuzz}"

"$root/scripts/install-deps.sh"
if ! command -v clang++ >/dev/null || ! ls /usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a >/dev/null 2>&1; then
  SUDO=""; [ "$(id -u)" != 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends clang libclang-rt-dev >/dev/null
fi
CXX=clang++ cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCLBDPT_FUZZ=ON \
  -DCLBDPT_BUILD_TESTS=OFF -DCLBDPT_BUILD_BENCH=OFF >/dev/null
cmake --build "$build" --target scene_loader_fuzz -j"$(nproc)" >/dev/null

# Seeds in the target's format (tests/fuzz/fuzz_scene_files.h): scene, a.obj, a.mtl, a.png,
# a.vdb, separated by lines "@@@"; file names rewritten to those. Large meshes are cut to their first
# lines (the fuzzer's inputs stay small and fast).
seeds="$build/seeds"
rm -rf "$seeds"; mkdir -p "$seeds" "$build/corpus" "$build/crashes"
python3 - "$root" "$seeds" <<'PY'
import glob, os, re, sys
root, out = sys.argv[1], sys.argv[2]
def head(path, lines=200):
    with open(path, 'rb') as f:
        return b''.join(f.readlines()[:lines])
def mtl_of(obj_path, text):
    m = re.search(rb'^mtllib\s+(\S+)', text, re.M)
    p = os.path.join(os.path.dirname(obj_path), m.group(1).decode()) if m else None
    return head(p) if p and os.path.exists(p) else b''
def as_fuzz_obj(text):
    return re.sub(rb'^mtllib\s+\S+', b'mtllib a.mtl', text, flags=re.M)
n = 0
def emit(parts):
    global n
    with open(os.path.join(out, 'seed%03d' % n), 'wb') as f:
        f.write(b'\n@@@\n'.join(parts))
    n += 1
for obj in sorted(glob.glob(root + '/scenes/*/*.obj') + glob.glob(root + '/tests/data/*.obj')):
    text = head(obj)
    emit([as_fuzz_obj(text), b'', mtl_of(obj, text)])
for js in sorted(glob.glob(root + '/scenes/*/*.json') + glob.glob(root + '/tests/data/*.json')):
    with open(js, 'rb') as f:
        scene = f.read()
    objs = re.findall(rb'"([^"]+\.obj)"', scene)
    obj = os.path.join(os.path.dirname(js), objs[0].decode()) if objs else None
    mesh = head(obj) if obj and os.path.exists(obj) else b''
    scene = re.sub(rb'"[^"]+\.obj"', b'"a.obj"', scene)
    emit([scene, as_fuzz_obj(mesh), mtl_of(obj, mesh) if obj and os.path.exists(obj) else b''])
# Textures and density grids: a textured quad (colour, normal and cut-out maps from one
# image) and a smoke box whose medium reads a small OpenVDB grid (tests/fuzz/seeds/).
seed_dir = root + '/tests/fuzz/seeds'
png = open(seed_dir + '/texture.png', 'rb').read()
vdb = open(seed_dir + '/density.vdb', 'rb').read()
quad = (b'mtllib a.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n'
        b'vn 0 0 1\nusemtl m\nf 1/1/1 2/2/1 3/3/1 4/4/1\n')
emit([quad, b'', b'newmtl m\nKd 1 1 1\nmap_Kd a.png\nnorm a.png\nmap_d a.png\nbump -bm 2 a.png\n', png])
with open(root + '/scenes/smoke/smoke-box.obj', 'rb') as f:
    box = f.read()
with open(root + '/scenes/smoke/smoke-box.mtl', 'rb') as f:
    box_mtl = f.read()
smoke = (b'{"meshes": ["a.obj"], "media": {"smoke": {"sigma_a": [0.1, 0.1, 0.1], "sigma_s": [1, 1, 1], '
         b'"density": {"file": "a.vdb", "grid": "density"}}}, '
         b'"materials": {"smoke_boundary": {"interface": true, "interior": "smoke"}}}')
emit([smoke, as_fuzz_obj(box), box_mtl, b'', vdb])
print('fuzz: %d seed inputs' % n)
PY

# libFuzzer writes its job logs (fuzz-N.log) into the working directory.
rm -rf "$build/logs"; mkdir -p "$build/logs"; cd "$build/logs"
log="$build/fuzz.log"
# Leaks inside the image and grid libraries' error paths (libpng's longjmp skips OpenImageIO's
# destructors) are theirs, suppressed by scripts/lsan.supp; matching them needs whole stacks
# (libstdc++ has no frame pointers), hence the slow unwinder.
export ASAN_OPTIONS="fast_unwind_on_malloc=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export LSAN_OPTIONS="suppressions=$root/scripts/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
set +e
"$build/scene_loader_fuzz" "$build/corpus" "$seeds" -max_total_time="$seconds" -max_len=65536 -timeout=20 \
  -rss_limit_mb=4096 -jobs="$jobs" -workers="$jobs" -print_final_stats=1 -artifact_prefix="$build/crashes/" \
  >"$log" 2>&1
status=$?
set -e
# With -jobs, each job's statistics are in its own log (and repeated in the main one).
stat_logs=$(ls "$build"/logs/fuzz-*.log 2>/dev/null || echo "$log")
execs=$(cat $stat_logs | grep -o 'stat::number_of_executed_units: *[0-9]*' | awk '{s += $2} END {print s + 0}')
echo "fuzz: $seconds s x $jobs job(s): $execs executions; corpus $(ls "$build/corpus" | wc -l) inputs;" \
  "crashes: $(ls "$build/crashes" | wc -l) (in $build/crashes); logs $log, $build/logs"
exit "$status"
