#!/usr/bin/env python3
"""Renders every .obj under the given folders as a user would, with no scene file and no
flags but a small sample count, and prints one row per file: exit status, warning lines,
seconds, and how much of the image shows the model (pixels that differ from the image's
border colour) and how bright it is. Ends with a summary line. Run with Debian's python3 (it
reads the images with OpenImageIO):

    /usr/bin/python3 scripts/obj_acceptance.py DIR [DIR ...] [--spp 8] [--size 128] [--out OUTDIR]

A file that fails names its error; files that cannot be a scene (no faces, bad indices, NaN
coordinates) are expected to fail with a one-line error, everything else to exit 0.
"""
import argparse
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def coverage(path):
    """Fraction of pixels that differ from the border colour, and mean pixel value."""
    import numpy as np
    import OpenImageIO as oiio
    img = oiio.ImageBuf(path).get_pixels(oiio.FLOAT)[:, :, :3]
    border = np.concatenate([img[0], img[-1], img[:, 0], img[:, -1]])
    background = np.median(border, axis=0)
    differs = np.abs(img - background).max(axis=2) > 0.1
    return float(differs.mean()), float(img.mean())


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--binary", default=os.path.join(ROOT, "build", "clbdpt"))
    ap.add_argument("--spp", type=int, default=8)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--out", default="obj_acceptance")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    files = sorted((os.path.join(d, f), os.path.relpath(os.path.join(d, f), top)) for top in a.dirs
                   for d, _, fs in os.walk(top) for f in fs if f.lower().endswith(".obj"))
    ok = failed = 0
    print(f"{'file':60} {'exit':>4} {'warn':>4} {'s':>6} {'cover':>6} {'mean':>7}  note")
    for path, shown in files:
        name = shown.replace(os.sep, "_").replace(" ", "_")[:-4]
        image = os.path.join(a.out, name + ".png")
        t0 = time.time()
        r = subprocess.run([a.binary, "render", path, "--spp", str(a.spp), "--width", str(a.size),
                            "--height", str(a.size), "-o", image], capture_output=True, text=True)
        seconds = time.time() - t0
        lines = r.stderr.splitlines()
        warnings = sum(1 for l in lines if l.startswith("clbdpt: warning:"))
        error = next((l for l in lines if l.startswith("clbdpt: error:")), "")
        if r.returncode == 0:
            ok += 1
            cover, mean = coverage(image)
            print(f"{shown[:60]:60} {r.returncode:4} {warnings:4} {seconds:6.2f} {cover:6.2f} {mean:7.3f}")
        else:
            failed += 1
            print(f"{shown[:60]:60} {r.returncode:4} {warnings:4} {seconds:6.2f} {'':6} {'':7}  {error[15:]}")
    print(f"{ok} rendered, {failed} refused, of {len(files)} files")


if __name__ == "__main__":
    sys.exit(main())
