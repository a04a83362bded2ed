#!/usr/bin/env bash
# Packs this build into a folder that runs on another x86-64 Linux machine whose OpenCL driver
# is a GPU's and which has none of clbdpt's libraries (a lent GPU machine: nothing can be
# installed there), for scripts/device_bench.sh to run there.
#   scripts/device_bundle.sh [DIR=.gpu] [OLD_BINARY]
# DIR/bin/clbdpt        this build (and DIR/bin/clbdpt_old: OLD_BINARY, to compare in one run)
# DIR/bin/libclbdpt_image_io.so
#                       a stand-in image module that reads and writes PFM whatever the file's
#                       name (OpenImageIO's 260 libraries would not fit); the renders' images
#                       come back as PFM
# DIR/libs.tar.xz       the shared libraries clbdpt links beyond glibc and libstdc++, the
#                       OpenCL ICD loader among them (about 7 MB)
# DIR/sky/              the sky scene with its environment map as PFM
# Add DIR to .git/info/exclude; the benchmark unpacks the libraries and points the ICD loader
# at the driver's libnvidia-opencl.so.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
dir="${1:-$root/.gpu}"
build="$root/${BUILD_DIR:-build}"
mkdir -p "$dir/bin" "$dir/sky"
cp "$build/clbdpt" "$dir/bin/clbdpt"
if [ -n "${2:-}" ]; then cp "$2" "$dir/bin/clbdpt_old"; fi
g++ -std=c++17 -O2 -shared -fPIC -I"$root/host" "$root/scripts/device_bundle/pfm_image_io.cpp" \
  -o "$dir/bin/libclbdpt_image_io.so"
libs=$(mktemp -d)
trap 'rm -rf "$libs"' EXIT
ldd "$build/clbdpt" | awk '/=>/ {print $1, $3}' | grep -v -E '^(libc|libm|libstdc\+\+|libgcc_s)\.so' |
  while read -r name path; do cp -L "$path" "$libs/$name"; done
tar -cJf "$dir/libs.tar.xz" -C "$libs" .
cp "$root/scenes/sky/sky.obj" "$root/scenes/sky/sky.mtl" "$dir/sky/"
sed 's/sky\.exr/sky.pfm/' "$root/scenes/sky/sky.json" >"$dir/sky/sky.json"
/usr/bin/python3 - "$root/scenes/sky/sky.exr" "$dir/sky/sky.pfm" <<'PY'
import sys, numpy as np, OpenImageIO as oiio
pixels = oiio.ImageInput.open(sys.argv[1]).read_image("float")[:, :, :3]
h, w, _ = pixels.shape
with open(sys.argv[2], "wb") as f:
    f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
    f.write(np.ascontiguousarray(pixels[::-1]).astype("<f4").tobytes())
PY
du -sh "$dir"
