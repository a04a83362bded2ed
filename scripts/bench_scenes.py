#!/usr/bin/env python3
"""Throughput of clbdpt per bundled scene: samples/s and Mrays/s of the per-scene specialised
kernel and of the build with every feature enabled (--all-features), the median of several
runs each, interleaved so that machine load hits both alike, and their ratio.

    python3 scripts/bench_scenes.py [--scenes a,b] [--runs 3] [--spp 8] [--size 128] [--sampler sobol]

Kernels are built (and cached) by one warm-up render per variant before timing. The figures are
the renderer's own: the time of the passes, excluding start-up, scene loading and kernel builds.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = ["cornell-box", "cornell-specular", "lamp-ceiling", "veach-mis", "point-spot", "sky"]


def render(binary, scene, args, stats_path):
    cmd = [binary, "render", os.path.join(ROOT, "scenes", scene, scene + ".json"),
           "-o", stats_path + ".exr", "--stats", stats_path] + args
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(stats_path) as f:
        return json.load(f)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", default=os.path.join(ROOT, "build", "clbdpt"))
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--spp", type=int, default=8)
    ap.add_argument("--size", type=int, default=128, help="film width; height keeps the scene's aspect")
    ap.add_argument("--integrator", default="bdpt")
    ap.add_argument("--sampler", default="independent")
    a = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for scene in a.scenes.split(","):
            common = ["--spp", str(a.spp), "--width", str(a.size), "--integrator", a.integrator,
                      "--sampler", a.sampler]
            with open(os.path.join(ROOT, "scenes", scene, scene + ".json")) as f:
                film = json.load(f).get("film", {})
            height = round(a.size * film.get("height", 256) / film.get("width", 256))
            common += ["--height", str(height)]
            variants = {"specialised": common, "all features": common + ["--all-features"]}
            results = {k: [] for k in variants}
            for k, args in variants.items():  # warm-up: build and cache the kernel
                render(a.binary, scene, args[:1] + ["1"] + args[2:], os.path.join(tmp, "warm.json"))
            for run in range(a.runs):
                for k, args in variants.items():
                    results[k].append(render(a.binary, scene, args, os.path.join(tmp, "s.json")))
            med = {k: (statistics.median(r["samples_per_second"] for r in v),
                       statistics.median(r["rays_per_second"] for r in v)) for k, v in results.items()}
            rows.append((scene, med["specialised"], med["all features"],
                         med["specialised"][0] / med["all features"][0]))
            print(f"{scene:18s} specialised {med['specialised'][0] / 1e3:8.1f} k samples/s "
                  f"{med['specialised'][1] / 1e6:6.2f} Mrays/s | all features "
                  f"{med['all features'][0] / 1e3:8.1f} k samples/s {med['all features'][1] / 1e6:6.2f} Mrays/s"
                  f" | ratio {rows[-1][3]:.3f}", flush=True)
    print()
    print(f"| scene | specialised k samples/s | Mrays/s | all-features k samples/s | Mrays/s | ratio |")
    print("|---|---:|---:|---:|---:|---:|")
    for scene, spec, allf, ratio in rows:
        print(f"| {scene} | {spec[0] / 1e3:.1f} | {spec[1] / 1e6:.2f} | {allf[0] / 1e3:.1f} | {allf[1] / 1e6:.2f} | {ratio:.3f} |")
    print(f"\n(median of {a.runs} interleaved runs, {a.spp} spp at width {a.size}, {a.integrator}, "
          f"{a.sampler} sampler; load average at the end: {os.getloadavg()[0]:.2f})")


if __name__ == "__main__":
    sys.exit(main())
