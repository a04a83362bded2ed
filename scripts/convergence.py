#!/usr/bin/python3
"""Speed-vs-error study of clbdpt's three strategy sets (bdpt, pt, lt).

For each scene the script
  1. gets a reference image: either --reference FILE, or a long render cached under
     --cache (default ~/.cache/clbdpt/references/) with a JSON sidecar of the settings that made
     it (scene files' SHA-256, integrator, spp, max depth, film size, binary version and SHA-256).
     The reference is rendered as --ref-chunks independent renders with distinct seeds and
     averaged, so its own noise (MSE of the reference, "ref_mse") can be estimated from the
     spread of the chunks;
  2. renders every integrator (--integrators, default bdpt,pt,lt) with every sampler
     (--samplers, default independent; clbdpt --sampler independent|sobol) at every time budget
     (--budgets, default 1,2,4,...,64 s) with --seeds seeds each; every run gets its own seed
     (seed-base + 100*budget_index + seed_index + 10000*sampler_index), so all runs are
     statistically independent
     (runs of one seed at growing budgets would otherwise share their first samples); the
     (budget, seed) pairs run in a shuffled order (--order) with the integrators and samplers
     interleaved,
     so a drift of the machine's load does not tilt one integrator or the fitted slopes;
  3. measures, against the reference, for each run: RMSE (all pixels and channels, linear),
     relMSE = mean((x-ref)^2 / (ref^2 + 0.01)), per-channel mean bias mean(x - ref), and
     efficiency 1 / (MSE * seconds), with seconds = the "seconds" the render's stats JSON
     reports (not the requested budget: renders stop after whole passes and overshoot);
  4. writes <out>/<scene>_runs.csv (one row per run), <out>/<scene>.png (log-log RMSE vs
     seconds and efficiency vs seconds, one line per integrator and sampler, sobol dashed),
     <out>/summary.csv and <out>/summary.md (per scene, integrator and sampler: samples/s,
     Mrays/s, RMSE at 10 s interpolated in log-log -- or at the largest budget when the runs
     do not reach 10 s --, fitted slopes of log RMSE over log seconds and over log spp, pooled
     per-channel bias with standard error, and the QMC gain RMSE(independent) / RMSE(sobol)
     at equal time), and prints the markdown to stdout.

The QMC gain compares the two samplers at equal render time: both per-budget curves
(seed-averaged MSE vs geometric-mean seconds) are interpolated piecewise-linearly in log-log
at T = 10 s, or at the largest time both curves reach if that is under 10 s, and the gain is
RMSE_independent(T) / RMSE_sobol(T) (> 1: Sobol is better; its square is the equal-time MSE
ratio). It is given raw and with the reference's own MSE subtracted from both.

An unbiased, consistent estimator gives a slope of about -0.5; a flatter slope means bias
(error that does not shrink with time) or a noisy reference (the measured MSE is the true MSE
plus the reference's MSE; the slope fitted after subtracting ref_mse is reported too).

Timings are wall-clock seconds on whatever machine runs this; on a small shared machine
(e.g. 2 cores with builds running beside it) they are noisy. The load average before each run
is recorded in the CSV.

Before the ladder, one tiny warm-up render per integrator makes sure the compiled kernel is in
clbdpt's kernel cache, so the first timed render does not include a (PoCL) kernel compile.
The binary is copied to a private snapshot at start, so a concurrent rebuild of the build
folder cannot change the renderer in the middle of a study.

Examples:
  /usr/bin/python3 scripts/convergence.py cornell-box --quick          # smoke test, < 2 min
  /usr/bin/python3 scripts/convergence.py cornell-box --budgets 1,2,4,8,16 --seeds 2 \\
      --ref-spp 1024
  /usr/bin/python3 scripts/convergence.py all                          # every bundled scene
  /usr/bin/python3 scripts/convergence.py scenes/sky/sky.json --reference my_ref.exr
  /usr/bin/python3 scripts/convergence.py all --samplers independent,sobol --film-scale 0.5 \\
      --budgets 1,2,4 --seeds 2 --ref-time 100
"""

import argparse
import csv
import datetime
import hashlib
import json
import math
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

from scene_files import scene_hash, sha256_file

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUNDLED = ["cornell-box", "cornell-specular", "lamp-ceiling", "veach-mis", "point-spot", "sky"]
INTEGRATORS = ["bdpt", "pt", "lt"]
SAMPLERS = ["independent", "sobol"]
LINESTYLES = {"independent": "-", "sobol": "--"}
MARKERS = {"independent": "o", "sobol": "s"}
COLORS = {"bdpt": "tab:blue", "pt": "tab:orange", "lt": "tab:green"}
REF_SEED_BASE = 1_000_000  # reference chunks never share a seed with a measured run
NOISE_NOTE = ("Timings are wall-clock on a shared machine (load average recorded per run); "
              "treat samples/s, Mrays/s and RMSE-at-time as noisy, the slopes as more robust.")


def log(msg):
    print(msg, file=sys.stderr, flush=True)


# ----------------------------------------------------------------------------------------------
# helpers: hashing, images, running the renderer




def read_exr(path):
    import OpenImageIO as oiio
    buf = oiio.ImageBuf(path)
    if buf.has_error:
        raise RuntimeError(f"cannot read {path}: {buf.geterror()}")
    px = buf.get_pixels(oiio.FLOAT)
    if px is None or px.size == 0:
        raise RuntimeError(f"cannot read pixels of {path}: {buf.geterror()}")
    px = np.asarray(px, dtype=np.float64)
    if px.ndim == 2:
        px = px[:, :, None]
    return px[:, :, :3]


def write_exr(path, pixels, attribs):
    import OpenImageIO as oiio
    h, w, c = pixels.shape
    spec = oiio.ImageSpec(w, h, c, oiio.FLOAT)
    spec.channelnames = ("R", "G", "B")[:c]
    for k, v in attribs.items():
        spec.attribute(k, str(v))
    tmp = path + ".tmp.exr"
    out = oiio.ImageOutput.create(tmp)
    if out is None or not out.open(tmp, spec):
        raise RuntimeError(f"cannot write {path}: {oiio.geterror()}")
    out.write_image(pixels.astype(np.float32))
    out.close()
    os.replace(tmp, path)


class Renderer:
    def __init__(self, binary, device=None, width=None, height=None, max_depth=None,
                 snapshot_dir=None):
        if not os.path.isfile(binary):
            raise SystemExit(f"convergence: renderer binary not found: {binary} "
                             f"(build it, or pass --binary)")
        self.original = os.path.abspath(binary)
        if snapshot_dir:
            snap = os.path.join(snapshot_dir, "clbdpt")
            shutil.copy2(binary, snap)
            binary = snap
        self.binary = binary
        self.sha256 = sha256_file(binary)
        try:
            self.version = subprocess.run([binary, "--version"], capture_output=True, text=True,
                                          timeout=30).stdout.strip()
        except Exception:  # noqa: BLE001
            self.version = "unknown"
        self.device, self.width, self.height, self.max_depth = device, width, height, max_depth

    def render(self, scene, integrator, out_exr, seed, spp=None, seconds=None, sampler=None):
        stats = out_exr[:-4] + ".json"
        cmd = [self.binary, "render", scene, "--integrator", integrator, "--seed", str(seed),
               "-o", out_exr, "--stats", stats]
        if sampler is not None:
            cmd += ["--sampler", sampler]
        if seconds is not None:
            cmd += ["--time", repr(float(seconds))]
        else:
            cmd += ["--spp", str(int(spp))]
        if self.device is not None:
            cmd += ["--device", str(self.device)]
        if self.width:
            cmd += ["--width", str(self.width)]
        if self.height:
            cmd += ["--height", str(self.height)]
        if self.max_depth is not None:
            cmd += ["--max-depth", str(self.max_depth)]
        load = os.getloadavg()[0]
        t0 = time.monotonic()
        p = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.monotonic() - t0
        if p.returncode != 0:
            raise RuntimeError(f"render failed ({' '.join(cmd)}):\n{p.stderr.strip()}")
        with open(stats) as f:
            st = json.load(f)
        st["_wall_seconds"] = wall
        st["_load_before"] = load
        with open(stats, "w") as f:
            json.dump(st, f, indent=1, sort_keys=True)
        return st


# ----------------------------------------------------------------------------------------------
# reference


def reference_settings(args, renderer, scene):
    settings = {
        "scene": os.path.abspath(scene),
        "scene_sha256": scene_hash(scene),
        "integrator": args.ref_integrator,
        "spp_requested": None if args.ref_time else args.ref_spp,
        "time_requested": args.ref_time,
        "chunks": args.ref_chunks,
        "max_depth_override": args.max_depth,
        "width_override": args.width,
        "height_override": args.height,
        "device": args.device,
    }
    if args.ref_sampler != "independent":       # keeps the cache keys of older references
        settings["sampler"] = args.ref_sampler
    return settings


def get_reference(args, renderer, scene, name):
    """Returns (pixels, info dict with ref_mse and the per-channel SE of the reference mean)."""
    if args.reference:
        px = read_exr(args.reference)
        info = {"source": os.path.abspath(args.reference), "ref_mse": 0.0,
                "mean_se": [0.0] * px.shape[2], "note": "user reference; its noise is unknown"}
        side = os.path.splitext(args.reference)[0] + ".json"
        if os.path.exists(side):
            info["sidecar"] = side
        return px, info

    settings = reference_settings(args, renderer, scene)
    key = hashlib.sha256(json.dumps(settings, sort_keys=True).encode()).hexdigest()[:16]
    folder = os.path.join(args.cache, "references")
    os.makedirs(folder, exist_ok=True)
    ref_exr = os.path.join(folder, f"{name}-{settings['integrator']}-{key}.exr")
    sidecar = ref_exr[:-4] + ".json"
    chunk_dir = ref_exr[:-4] + ".chunks"

    if os.path.exists(ref_exr) and os.path.exists(sidecar) and not args.rerender_reference:
        with open(sidecar) as f:
            info = json.load(f)
        if info.get("binary_sha256") != renderer.sha256:
            msg = (f"reference {ref_exr} was rendered by another binary "
                   f"({info.get('binary_sha256', '?')[:12]} vs {renderer.sha256[:12]})")
            if args.strict_reference:
                log(f"{msg}; re-rendering (--strict-reference)")
            else:
                log(f"warning: {msg}; reusing it (pass --strict-reference to re-render)")
                info["warning"] = msg
                return read_exr(ref_exr), info
        else:
            log(f"[{name}] reusing reference {ref_exr} ({info['spp']} spp)")
            return read_exr(ref_exr), info

    os.makedirs(chunk_dir, exist_ok=True)
    k = args.ref_chunks
    chunks, stats = [], []
    for i in range(k):
        out = os.path.join(chunk_dir, f"chunk{i}.exr")
        log(f"[{name}] reference chunk {i + 1}/{k}: {settings['integrator']} "
            + (f"{args.ref_time / k:.0f} s" if args.ref_time else f"{args.ref_spp // k} spp"))
        if args.ref_time:
            st = renderer.render(scene, settings["integrator"], out, REF_SEED_BASE + i,
                                 seconds=args.ref_time / k, sampler=args.ref_sampler)
        else:
            st = renderer.render(scene, settings["integrator"], out, REF_SEED_BASE + i,
                                 spp=max(1, args.ref_spp // k), sampler=args.ref_sampler)
        chunks.append(read_exr(out))
        stats.append(st)
    spp = np.array([s["spp"] for s in stats], dtype=np.float64)
    stack = np.stack(chunks)                       # k, h, w, c
    w = (spp / spp.sum())[:, None, None, None]
    ref = (stack * w).sum(axis=0)                  # spp-weighted mean = one render of sum(spp)
    ref_mse, mean_se = reference_noise(stack, spp)
    info = dict(settings)
    info.update({
        "spp": int(spp.sum()),
        "sampler": args.ref_sampler,
        "chunk_spp": [int(s) for s in spp],
        "chunk_seeds": [REF_SEED_BASE + i for i in range(k)],
        "seconds": float(sum(s["seconds"] for s in stats)),
        "max_depth": stats[0].get("max_depth"),
        "width": stats[0].get("width"),
        "height": stats[0].get("height"),
        "device_name": stats[0].get("device"),
        "binary": renderer.original,
        "binary_version": renderer.version,
        "binary_sha256": renderer.sha256,
        "repo_head": git_head(),
        "created": datetime.datetime.now().isoformat(timespec="seconds"),
        "ref_mse": ref_mse,
        "mean_se": mean_se,
        "source": ref_exr,
        "key": key,
    })
    write_exr(ref_exr, ref.astype(np.float32), {"clbdpt:reference": json.dumps(info)})
    with open(sidecar + ".tmp", "w") as f:
        json.dump(info, f, indent=1, sort_keys=True)
    os.replace(sidecar + ".tmp", sidecar)
    shutil.rmtree(chunk_dir, ignore_errors=True)
    log(f"[{name}] reference {ref_exr}: {info['spp']} spp in {info['seconds']:.0f} s, "
        f"its RMSE ~ {math.sqrt(ref_mse):.3g}")
    return read_exr(ref_exr), info


def reference_noise(stack, spp):
    """MSE of the spp-weighted mean of k independent chunks, and SE of its channel means.

    Chunk i has per-pixel variance s2/spp_i; the pooled estimate of s2 (per pixel) is
    sum spp_i (x_i - mean)^2 / (k - 1), and the weighted mean has variance s2 / sum(spp).
    """
    k = stack.shape[0]
    if k < 2:
        return float("nan"), [float("nan")] * stack.shape[3]
    w = spp / spp.sum()
    mean = (stack * w[:, None, None, None]).sum(axis=0)
    d = stack - mean
    s2 = (spp[:, None, None, None] * d * d).sum(axis=0) / (k - 1)
    ref_mse = float(s2.mean() / spp.sum())
    cm = stack.mean(axis=(1, 2))                   # k, c: channel means of each chunk
    cmean = (cm * w[:, None]).sum(axis=0)
    cs2 = (spp[:, None] * (cm - cmean) ** 2).sum(axis=0) / (k - 1)
    mean_se = [float(math.sqrt(v / spp.sum())) for v in cs2]
    return ref_mse, mean_se


def git_head():
    try:
        head = subprocess.run(["git", "-C", REPO, "rev-parse", "HEAD"], capture_output=True,
                              text=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", REPO, "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
        return head + ("+dirty" if dirty else "")
    except Exception:  # noqa: BLE001
        return "unknown"


# ----------------------------------------------------------------------------------------------
# metrics and fits


def metrics(img, ref):
    if img.shape != ref.shape:
        raise RuntimeError(f"image {img.shape} and reference {ref.shape} differ in size")
    d = img - ref
    mse = float(np.mean(d * d))
    rel = float(np.mean(d * d / (ref * ref + 0.01)))
    bias = [float(v) for v in d.mean(axis=(0, 1))]
    return mse, rel, bias


def fit_slope(x, y):
    """Least-squares slope and its standard error of log y over log x."""
    x, y = np.log(np.asarray(x, float)), np.log(np.asarray(y, float))
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    if len(x) < 2 or np.ptp(x) == 0:
        return float("nan"), float("nan"), float("nan")
    A = np.vstack([x, np.ones_like(x)]).T
    (b, a), res, *_ = np.linalg.lstsq(A, y, rcond=None)
    if len(x) > 2:
        r = y - (a + b * x)
        se = math.sqrt((r @ r) / (len(x) - 2) / ((x - x.mean()) @ (x - x.mean())))
    else:
        se = float("nan")
    return float(b), float(se), float(a)


def aggregate(rows):
    """Per budget: geometric-mean seconds and sqrt(mean MSE) over seeds."""
    by = {}
    for r in rows:
        by.setdefault(r["budget"], []).append(r)
    pts = []
    for b in sorted(by):
        rs = by[b]
        pts.append((float(np.exp(np.mean([math.log(r["seconds"]) for r in rs]))),
                    float(math.sqrt(np.mean([r["mse"] for r in rs]))),
                    float(np.mean([r["mse"] * r["seconds"] for r in rs]))))
    return pts


def at_time(pts, t, value=lambda p: p[1]):
    """value(point) at t seconds, piecewise-linear in log-log between the per-budget points;
    nan outside their range."""
    xs = np.array([p[0] for p in pts], float)
    ys = np.array([value(p) for p in pts], float)
    ok = np.isfinite(ys) & (ys > 0)
    xs, ys = xs[ok], ys[ok]
    if not len(xs) or not (xs.min() <= t <= xs.max()):
        return float("nan")
    o = np.argsort(xs)
    return float(np.exp(np.interp(math.log(t), np.log(xs[o]), np.log(ys[o]))))


def qmc_gain(pts_ind, pts_sob, ref_mse, t=10.0):
    """Equal-time RMSE ratio independent / sobol at t seconds, or at the largest time both
    per-budget curves reach when that is below t. Returns (gain, gain with the reference's MSE
    subtracted from both, the time used)."""
    if not pts_ind or not pts_sob:
        return float("nan"), float("nan"), float("nan")
    lo = max(min(p[0] for p in pts_ind), min(p[0] for p in pts_sob))
    hi = min(max(p[0] for p in pts_ind), max(p[0] for p in pts_sob))
    if hi < lo:
        return float("nan"), float("nan"), float("nan")
    tt = min(t, hi) if t >= lo else lo
    raw = at_time(pts_ind, tt) / at_time(pts_sob, tt)

    def sub(p):
        m = p[1] ** 2 - ref_mse
        return math.sqrt(m) if m > 0 else float("nan")
    corr = at_time(pts_ind, tt, sub) / at_time(pts_sob, tt, sub)
    return raw, corr, tt


def rmse_at(pts, t, slope, intercept):
    """RMSE at t seconds: piecewise-linear in log-log between the per-budget points; outside
    their range, the fitted line (flagged as extrapolated)."""
    xs = [p[0] for p in pts]
    ys = [p[1] for p in pts]
    if xs and min(xs) <= t <= max(xs):
        order = np.argsort(xs)
        lx = np.log(np.array(xs)[order])
        ly = np.log(np.array(ys)[order])
        return float(np.exp(np.interp(math.log(t), lx, ly))), False
    if math.isfinite(slope):
        return float(math.exp(intercept + slope * math.log(t))), True
    return float("nan"), True


def pooled_bias(rows, ref_se):
    """Per-channel bias pooled over all runs of one integrator (runs are independent; the
    variance of a run's channel mean scales as 1/spp, so weights are spp), with its standard
    error from the scatter of the runs, combined with the reference's own SE."""
    b = np.array([r["bias"] for r in rows])          # n, c
    w = np.array([r["spp"] for r in rows], float)
    n = len(rows)
    mean = (b * w[:, None]).sum(axis=0) / w.sum()
    if n > 1:
        s2 = (w[:, None] * (b - mean) ** 2).sum(axis=0) / (n - 1)
        se = np.sqrt(s2 / w.sum())
    else:
        se = np.full(b.shape[1], np.nan)
    se = np.sqrt(se ** 2 + np.asarray(ref_se) ** 2)
    return mean, se


def per_budget_bias(rows, ref_se):
    """Per budget: mean over seeds and SE across seeds (plus the reference's SE)."""
    by = {}
    for r in rows:
        by.setdefault(r["budget"], []).append(r["bias"])
    out = {}
    for bud, bs in sorted(by.items()):
        bs = np.array(bs)
        m = bs.mean(axis=0)
        se = bs.std(axis=0, ddof=1) / math.sqrt(len(bs)) if len(bs) > 1 else np.full(len(m), np.nan)
        out[bud] = (m, np.sqrt(se ** 2 + np.asarray(ref_se) ** 2), len(bs))
    return out


# ----------------------------------------------------------------------------------------------
# one scene


def resolve_scene(s):
    if s in BUNDLED or (not os.path.exists(s) and os.path.isdir(os.path.join(REPO, "scenes", s))):
        return os.path.join(REPO, "scenes", s, s + ".json"), s
    if not os.path.exists(s):
        raise SystemExit(f"convergence: no such scene: {s}")
    return os.path.abspath(s), os.path.splitext(os.path.basename(s))[0]


def film_size(scene):
    try:
        with open(scene) as f:
            film = json.load(f).get("film", {})
        return int(film["width"]), int(film["height"])
    except Exception:  # noqa: BLE001
        return None


def run_scene(args, renderer, scene, name, work):
    if args.film_scale:
        wh = film_size(scene)
        if wh is None:
            raise RuntimeError(f"--film-scale: cannot read the film size of {scene}")
        args.width = renderer.width = max(1, round(wh[0] * args.film_scale))
        args.height = renderer.height = max(1, round(wh[1] * args.film_scale))
        log(f"[{name}] film {wh[0]}x{wh[1]} scaled to {args.width}x{args.height}")
    ref, ref_info = get_reference(args, renderer, scene, name)
    ref_mse = ref_info.get("ref_mse", 0.0)
    ref_mse = 0.0 if not math.isfinite(ref_mse) else ref_mse
    ref_se = [v if math.isfinite(v) else 0.0 for v in ref_info.get("mean_se", [0.0] * 3)]
    if args.reference_only:
        return None

    run_dir = os.path.join(work, name)
    os.makedirs(run_dir, exist_ok=True)
    for integ in args.integrators:                 # warm-up: kernel build into the cache
        for smp in args.samplers:
            st = renderer.render(scene, integ,
                                 os.path.join(run_dir, f"warmup-{integ}-{smp}.exr"), 0, spp=1,
                                 sampler=smp)
            log(f"[{name}] warm-up {integ}/{smp}: kernel "
                f"{'cached' if st.get('kernel_from_cache') else 'built'} "
                f"{st.get('kernel_build_seconds', float('nan')):.2f} s")

    rows = []
    budgets = args.scene_budgets.get(name, args.budgets)
    n_total = len(args.integrators) * len(args.samplers) * len(budgets) * args.seeds
    k = 0
    # Interleave integrators inside each (budget, seed) so that slow phases of the machine
    # (someone else's build) hit all integrators alike rather than one of them, and (by
    # default) visit the (budget, seed) pairs in a shuffled order so that a drift of the
    # machine's load during the study does not correlate with the budget (which would tilt the
    # fitted slopes over seconds).
    tasks = [(bi, budget, j) for bi, budget in enumerate(budgets) for j in range(args.seeds)]
    if args.order == "shuffled":
        random.Random(args.seed_base).shuffle(tasks)
    combos = [(integ, si, smp) for integ in args.integrators
              for si, smp in enumerate(args.samplers)]
    for ti, (bi, budget, j) in enumerate(tasks):
        # alternate which sampler goes first, so neither always runs right after the other
        order = combos if ti % 2 == 0 else [c for c in combos[::-1]]
        for integ, si, smp in order:
            seed = args.seed_base + 100 * bi + j + 10000 * si
            k += 1
            out = os.path.join(run_dir, f"{integ}-{smp}-t{budget:g}-s{seed}.exr")
            st = renderer.render(scene, integ, out, seed, seconds=budget, sampler=smp)
            img = read_exr(out)
            mse, rel, bias = metrics(img, ref)
            row = {"scene": name, "integrator": integ, "sampler": smp, "budget": budget,
                   "seed": seed,
                   "spp": st["spp"], "seconds": st["seconds"],
                   "wall_seconds": st["_wall_seconds"], "load_before": st["_load_before"],
                   "samples_per_second": st["samples_per_second"],
                   "rays_per_second": st["rays_per_second"],
                   "rays": st.get("rays"), "samples": st.get("samples"),
                   "kernel_build_seconds": st.get("kernel_build_seconds"),
                   "mse": mse, "rmse": math.sqrt(mse),
                   "rmse_minus_ref": math.sqrt(max(mse - ref_mse, 0.0)),
                   "relmse": rel, "efficiency": 1.0 / (mse * st["seconds"]) if mse > 0 else
                   float("inf"), "bias": bias}
            rows.append(row)
            log(f"[{name}] {k}/{n_total} {integ:4s} {smp:11s} budget {budget:g}s seed {seed}: "
                f"{st['spp']} spp in {st['seconds']:.2f} s, RMSE {row['rmse']:.4g}, "
                f"relMSE {rel:.4g} (load {row['load_before']:.1f})")
            if not args.keep_images:
                os.remove(out)

    write_runs_csv(os.path.join(args.out_dir, f"{name}_runs.csv"), rows)
    summary = summarize(args, name, rows, ref_info, ref_mse, ref_se)
    write_bias_csv(os.path.join(args.out_dir, f"{name}_bias.csv"), name, summary)
    plot(os.path.join(args.out_dir, f"{name}.png"), name, rows, summary, ref_info, ref_mse)
    return summary


def write_runs_csv(path, rows):
    cols = ["scene", "integrator", "sampler", "budget", "seed", "spp", "seconds", "wall_seconds",
            "load_before", "samples_per_second", "rays_per_second", "kernel_build_seconds",
            "rmse", "rmse_minus_ref", "mse", "relmse", "efficiency",
            "bias_r", "bias_g", "bias_b"]
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        for r in rows:
            rr = dict(r)
            rr["bias_r"], rr["bias_g"], rr["bias_b"] = (r["bias"] + [float("nan")] * 3)[:3]
            w.writerow([fmt(rr[c]) for c in cols])
    log(f"wrote {path}")


def write_bias_csv(path, name, summary):
    """Per integrator and budget: channel mean bias over seeds, its SE across seeds (combined
    with the reference's), z = bias / SE, and the seed count (SE has seeds - 1 dof)."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["scene", "integrator", "sampler", "budget", "seeds", "bias_r", "bias_g", "bias_b",
                    "se_r", "se_g", "se_b", "z_r", "z_g", "z_b"])
        for integ, d in summary["integrators"].items():
            w.writerow([name, d["integrator"], d["sampler"], "pooled", d["runs"]] + [fmt(v) for v in d["bias"]] +
                       [fmt(v) for v in d["bias_se"]] + [fmt(v) for v in d["bias_z"]])
            for b, (m, se, n) in d["per_budget_bias"].items():
                z = [mm / ss if ss > 0 else float("nan") for mm, ss in zip(m, se)]
                w.writerow([name, d["integrator"], d["sampler"], b, n] + [fmt(v) for v in m] + [fmt(v) for v in se] +
                           [fmt(v) for v in z])
    log(f"wrote {path}")


_trapezoid = getattr(np, "trapezoid", None) or getattr(np, "trapz")


def t_tail(t, dof):
    """P(|T| > t) for Student's t with dof degrees of freedom (numerical integration)."""
    if dof <= 0:
        return float("nan")
    c = math.exp(math.lgamma((dof + 1) / 2) - math.lgamma(dof / 2)) / math.sqrt(dof * math.pi)
    x = np.linspace(0.0, t, 20001)
    pdf = c * (1 + x * x / dof) ** (-(dof + 1) / 2)
    return float(max(0.0, 1.0 - 2.0 * _trapezoid(pdf, x)))


def fmt(v):
    if isinstance(v, float):
        return f"{v:.6g}"
    return "" if v is None else str(v)


def summarize(args, name, rows, ref_info, ref_mse, ref_se):
    out = {"scene": name, "ref": ref_info, "ref_mse": ref_mse, "integrators": {},
           "width": args.width, "height": args.height,
           "loads": [r["load_before"] for r in rows]}
    for integ, smp in [(i, m) for i in args.integrators for m in args.samplers]:
        rs = [r for r in rows if r["integrator"] == integ and r["sampler"] == smp]
        if not rs:
            continue
        secs = [r["seconds"] for r in rs]
        slope, slope_se, icpt = fit_slope(secs, [r["rmse"] for r in rs])
        corr = [(r["seconds"], math.sqrt(r["mse"] - ref_mse)) for r in rs if r["mse"] > ref_mse]
        slope_c, slope_c_se, _ = fit_slope([c[0] for c in corr], [c[1] for c in corr]) \
            if ref_mse > 0 else (slope, slope_se, icpt)
        slope_spp, slope_spp_se, _ = fit_slope([r["spp"] for r in rs], [r["rmse"] for r in rs])
        corr_spp = [(r["spp"], math.sqrt(r["mse"] - ref_mse)) for r in rs if r["mse"] > ref_mse]
        slope_spp_c, slope_spp_c_se, _ = fit_slope([c[0] for c in corr_spp],
                                                   [c[1] for c in corr_spp])
        pts = aggregate(rs)
        r10, extrap = rmse_at(pts, 10.0, slope, icpt)
        # the value reported in the table: interpolated at 10 s, or (10 s not reached) the
        # per-budget point of the largest budget, never an extrapolation
        if not extrap:
            r_rep, t_rep = r10, 10.0
        else:
            last = max(pts, key=lambda p: p[0])
            r_rep, t_rep = last[1], last[0]
        bmean, bse = pooled_bias(rs, ref_se)
        out["integrators"][f"{integ}/{smp}"] = {
            "integrator": integ, "sampler": smp,
            "rmse_report": r_rep, "rmse_report_seconds": t_rep,
            "qmc_gain": float("nan"), "qmc_gain_minus_ref": float("nan"),
            "qmc_gain_seconds": float("nan"),
            "samples_per_second": sum(r["samples"] or r["samples_per_second"] * r["seconds"]
                                      for r in rs) / sum(secs),
            "rays_per_second": sum(r["rays"] or r["rays_per_second"] * r["seconds"]
                                   for r in rs) / sum(secs),
            "slope": slope, "slope_se": slope_se, "intercept": icpt,
            "slope_minus_ref": slope_c, "slope_minus_ref_se": slope_c_se,
            "slope_spp": slope_spp, "slope_spp_se": slope_spp_se,
            "slope_spp_minus_ref": slope_spp_c, "slope_spp_minus_ref_se": slope_spp_c_se,
            "rmse_10s": r10, "rmse_10s_extrapolated": extrap,
            "relmse_last": float(np.mean([r["relmse"] for r in rs
                                          if r["budget"] == max(x["budget"] for x in rs)])),
            "points": pts,
            "bias": [float(v) for v in bmean], "bias_se": [float(v) for v in bse],
            "bias_z": [float(m / s) if s > 0 else float("nan") for m, s in zip(bmean, bse)],
            "per_budget_bias": {str(b): ([float(x) for x in m], [float(x) for x in s], n)
                                for b, (m, s, n) in per_budget_bias(rs, ref_se).items()},
            "runs": len(rs),
        }
    for integ in args.integrators:
        ind = out["integrators"].get(f"{integ}/independent")
        sob = out["integrators"].get(f"{integ}/sobol")
        if ind and sob:
            g, gc, tg = qmc_gain(ind["points"], sob["points"], ref_mse)
            for d in (ind, sob):
                d["qmc_gain"], d["qmc_gain_minus_ref"], d["qmc_gain_seconds"] = g, gc, tg
    return out


def plot(path, name, rows, summary, ref_info, ref_mse):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(13, 5.5))
    for key, s in summary["integrators"].items():
        integ, smp = s["integrator"], s["sampler"]
        rs = [r for r in rows if r["integrator"] == integ and r["sampler"] == smp]
        c = COLORS.get(integ)
        ls, mk = LINESTYLES.get(smp, ":"), MARKERS.get(smp, "^")
        ax1.scatter([r["seconds"] for r in rs], [r["rmse"] for r in rs], s=12, color=c,
                    alpha=0.5, marker=mk)
        pts = s["points"]
        ax1.plot([p[0] for p in pts], [p[1] for p in pts], ls, marker=mk, color=c, ms=4,
                 label=f"{key}: slope {s['slope']:+.3f} (vs spp, ref noise "
                       f"subtracted {s['slope_spp_minus_ref']:+.3f})")
        ax2.scatter([r["seconds"] for r in rs], [r["efficiency"] for r in rs], s=12, color=c,
                    alpha=0.5, marker=mk)
        ax2.plot([p[0] for p in pts], [1.0 / p[2] for p in pts], ls, marker=mk, color=c, ms=4,
                 label=key + (f" (QMC gain {s['qmc_gain']:.2f} at {s['qmc_gain_seconds']:.1f} s)"
                              if smp == "sobol" and math.isfinite(s["qmc_gain"]) else ""))
    xs = [r["seconds"] for r in rows]
    if xs:
        x0, x1 = min(xs), max(xs)
        # guide through the geometric centre of all runs, shifted up so it does not hide data
        lx = np.mean([math.log(r["seconds"]) for r in rows])
        ly = np.mean([math.log(r["rmse"]) for r in rows])
        y0 = 1.6 * math.exp(ly - 0.5 * (math.log(x0) - lx))
        ax1.plot([x0, x1], [y0, y0 * (x1 / x0) ** -0.5], "k--", lw=0.8, label="slope -0.5")
    if ref_mse > 0:
        ax1.axhline(math.sqrt(ref_mse), color="gray", ls=":", lw=1,
                    label=f"reference noise ({ref_info.get('spp', '?')} spp)")
    for ax in (ax1, ax2):
        ax.set_xscale("log")
        ax.set_xlabel("render seconds (as reported by clbdpt --stats)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    ax1.set_yscale("log")
    ax2.set_yscale("log")
    ax1.set_ylabel("RMSE vs reference (linear RGB)")
    ax2.set_ylabel("efficiency 1 / (MSE · seconds)")
    ax1.set_title(f"{name} ({summary.get('width')}x{summary.get('height')}): RMSE vs time "
                  "(sobol dashed)")
    ax2.set_title(f"{name}: efficiency (higher is better)")
    fig.text(0.5, 0.005, "Timings noisy: small shared machine (load avg "
             f"{min(r['load_before'] for r in rows):.1f}–{max(r['load_before'] for r in rows):.1f}"
             f"). Reference: {ref_info.get('integrator', 'user')} "
             f"{ref_info.get('spp', '?')} spp.", ha="center", fontsize=8, color="gray")
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    log(f"wrote {path}")


# ----------------------------------------------------------------------------------------------
# reports


def markdown(args, summaries, renderer):
    L = []
    L.append("# clbdpt convergence: RMSE vs render time")
    L.append("")
    L.append(f"Generated {datetime.datetime.now().isoformat(timespec='seconds')} by "
             f"`scripts/convergence.py {' '.join(args.argv)}`; binary {renderer.version} "
             f"sha256 {renderer.sha256[:12]} (repo {git_head()[:12]}"
             f"{'+dirty' if git_head().endswith('+dirty') else ''}), "
             f"{os.cpu_count()} CPU cores.")
    over = "".join(f" ({n}: {', '.join(f'{b:g}' for b in v)} s)"
                   for n, v in args.scene_budgets.items())
    L.append(f"Budgets {', '.join(f'{b:g}' for b in args.budgets)} s{over} × {args.seeds} seeds × "
             f"samplers {', '.join(args.samplers)}; x values are the seconds each render "
             "reports. Film: " + ", ".join(f"{s['scene']} {s.get('width') or 'scene'}x"
                                           f"{s.get('height') or 'scene'}" for s in summaries)
             + ".")
    loads = [v for s in summaries for v in s.get("loads", [])]
    if loads:
        L.append(f"Machine load (1-min load average before each run): median "
                 f"{float(np.median(loads)):.2f}, range {min(loads):.2f}–{max(loads):.2f} "
                 f"on {os.cpu_count()} cores.")
    L.append("")
    L.append(f"**{NOISE_NOTE}**")
    L.append("")
    L.append("| scene | integrator | sampler | k samples/s | Mrays/s | RMSE at 10 s | "
             "slope over log time (ref noise subtracted) | slope over log spp (ref noise "
             "subtracted) | QMC gain (ref noise subtracted) |")
    L.append("|---|---|---|---:|---:|---:|---:|---:|---:|")
    for s in summaries:
        for key, d in s["integrators"].items():
            if d["rmse_report_seconds"] == 10.0:
                r10 = f"{d['rmse_report']:.4g}"
            else:
                r10 = f"{d['rmse_report']:.4g} (at {d['rmse_report_seconds']:.1f} s)†"
            if d["sampler"] == "sobol" and math.isfinite(d["qmc_gain"]):
                g = (f"{d['qmc_gain']:.2f} ({d['qmc_gain_minus_ref']:.2f})"
                     + ("" if d["qmc_gain_seconds"] == 10.0 else
                        f" at {d['qmc_gain_seconds']:.1f} s"))
            else:
                g = ""
            L.append(f"| {s['scene']} | {d['integrator']} | {d['sampler']} | "
                     f"{d['samples_per_second'] / 1e3:.1f} | "
                     f"{d['rays_per_second'] / 1e6:.3g} | {r10} | "
                     f"{d['slope']:+.3f} ± {d['slope_se']:.3f} ({d['slope_minus_ref']:+.3f}) | "
                     f"{d['slope_spp']:+.3f} ± {d['slope_spp_se']:.3f} "
                     f"({d['slope_spp_minus_ref']:+.3f}) | {g} |")
    L.append("")
    L.append("k samples/s = thousand camera samples (one per pixel per pass) per second; Mrays/s "
             "from clbdpt's counters; both pooled over all runs (total / total seconds). "
             "RMSE at 10 s: seed-averaged MSE per budget, interpolated piecewise-linearly in "
             "log-log; † = the runs do not reach 10 s, so the value is the largest budget's "
             "point at the stated (mean reported) seconds — not an extrapolation. "
             "QMC gain = RMSE(independent) / RMSE(sobol) at equal render time, both curves "
             "interpolated in log-log at 10 s or, where stated, at the largest time both reach "
             "(> 1: Sobol better; gain² = equal-time MSE ratio); in parentheses with the "
             "reference's MSE subtracted from both, which the raw ratio pulls towards 1. "
             "Slope ± its least-squares standard error over all runs (each seed a point). "
             "'Reference noise subtracted': fitted to sqrt(MSE − reference MSE), since the "
             "measured MSE is the run's MSE plus the reference's own (estimated from its "
             "chunks), which flattens the raw slope at long budgets. "
             "An unbiased estimator gives ≈ −0.5. The slope over log spp does not depend on "
             "timing noise (throughput changes with the machine's load) and is the cleaner "
             "bias test; the slope over seconds also contains per-render overheads.")
    L.append("")
    L.append("## Reference and bias")
    L.append("")
    for s in summaries:
        ri = s["ref"]
        L.append(f"**{s['scene']}**: reference `{ri.get('source')}` — "
                 f"{ri.get('integrator', 'user-supplied')} "
                 f"({ri.get('sampler', 'independent')} sampler), {ri.get('spp', '?')} spp "
                 f"({ri.get('chunks', '?')} independent chunks), max depth "
                 f"{ri.get('max_depth', '?')}, {ri.get('seconds', float('nan')):.0f} s; "
                 f"estimated reference RMSE {math.sqrt(s['ref_mse']):.3g} "
                 f"(adds {s['ref_mse']:.3g} to every run's MSE)."
                 + (f" **{ri['warning']}**" if ri.get("warning") else ""))
        L.append("")
        for key, d in s["integrators"].items():
            cells = [f"{ch} {m:+.2e} ± {e:.1e}" for ch, m, e in zip("RGB", d["bias"],
                                                                    d["bias_se"])]
            z = max(abs(v) for v in d["bias_z"])
            flag = " **(>3 SE)**" if z > 3 else ""
            L.append(f"- {key} ({d['runs']} runs): mean bias " + ", ".join(cells) +
                     f"; max |z| {z:.2f}{flag}; relMSE at the largest budget "
                     f"{d['relmse_last']:.3g}")
        L.append("")
        L.append("Bias = mean over pixels of (image − reference) per channel, pooled over all "
                 "runs of the integrator and sampler with weights spp (each run has its own seed); SE from "
                 "the scatter of the runs combined with the reference's own SE. Per budget "
                 "(mean over seeds, SE across seeds) in <scene>_bias.csv next to this file.")
        L.append("")
    return "\n".join(L) + "\n"


def suspicious(summaries, tol=0.15):
    notes = []
    for s in summaries:
        for integ, d in s["integrators"].items():
            spp_ok = abs(d["slope_spp_minus_ref"] + 0.5) <= tol
            why = (f"slope over spp (reference noise subtracted) "
                   f"{d['slope_spp_minus_ref']:+.3f} ± {d['slope_spp_minus_ref_se']:.3f}")
            if math.isfinite(d["slope"]) and abs(d["slope"] + 0.5) > tol:
                cause = ("the reference's own noise" if abs(d["slope_minus_ref"] + 0.5) <= tol
                         else "timing (throughput changes, per-render overhead)")
                notes.append(f"{s['scene']}/{integ}: raw slope over seconds {d['slope']:+.3f} ± "
                             f"{d['slope_se']:.3f} is far from -0.5 (reference noise "
                             f"subtracted: {d['slope_minus_ref']:+.3f}); {why}"
                             + (f" is fine, so this is {cause}, not bias" if spp_ok else
                                " is far from -0.5 too: possible bias"))
            elif math.isfinite(d["slope_spp_minus_ref"]) and not spp_ok:
                notes.append(f"{s['scene']}/{integ}: {why} is far from -0.5")
            for ch, z, m, e in zip("RGB", d["bias_z"], d["bias"], d["bias_se"]):
                if math.isfinite(z) and abs(z) > 3:
                    notes.append(f"{s['scene']}/{integ}: channel {ch} pooled mean bias "
                                 f"{m:+.3e} ± {e:.1e} (z = {z:+.1f}) exceeds 3 SE")
            cells, hits, n = 0, [], 0
            for b, (m, se, n) in d["per_budget_bias"].items():
                for ch, mm, ss in zip("RGB", m, se):
                    if ss > 0 and math.isfinite(ss):
                        cells += 1
                        if abs(mm / ss) > 3:
                            hits.append(f"{b} s {ch}: {mm:+.2e} ± {ss:.1e} (z {mm / ss:+.1f})")
            if hits:
                notes.append(f"{s['scene']}/{integ}: {len(hits)} of {cells} (budget, channel) "
                             f"cells have |bias| > 3 SE across seeds: " + "; ".join(hits) +
                             f". With {n} seeds the SE has {n - 1} dof, so each cell exceeds "
                             f"3 SE by chance with probability {t_tail(3.0, n - 1):.2f} "
                             "(the pooled test above is the meaningful one)")
    return notes


# ----------------------------------------------------------------------------------------------


def parse_budgets(text):
    try:
        vals = [float(v) for v in text.replace(" ", "").split(",") if v]
    except ValueError:
        raise argparse.ArgumentTypeError(f"budgets: comma-separated seconds, got {text!r}")
    if not vals or any(v <= 0 for v in vals):
        raise argparse.ArgumentTypeError("budgets must be positive")
    return sorted(set(vals))


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0],
        epilog=__doc__.split("\n", 1)[1], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*", default=["cornell-box"],
                    help="bundled scene names (" + ", ".join(BUNDLED) + "), 'all' for every "
                         "bundled scene, or paths to scene files (default: cornell-box)")
    ap.add_argument("--binary", default=os.path.join(REPO, "build", "clbdpt"),
                    help="clbdpt binary (default: build/clbdpt in the repo root)")
    ap.add_argument("--no-snapshot", action="store_true",
                    help="run the binary in place instead of a private copy made at start")
    ap.add_argument("--cache", default=os.path.join(os.path.expanduser("~"), ".cache", "clbdpt"),
                    help="cache folder; references go to CACHE/references/ "
                         "(default ~/.cache/clbdpt)")
    ap.add_argument("--reference", metavar="EXR",
                    help="use this reference image instead of rendering one (one scene only)")
    ap.add_argument("--ref-integrator", default="bdpt", choices=INTEGRATORS,
                    help="integrator of the rendered reference (default bdpt)")
    ap.add_argument("--ref-spp", type=int, default=1024,
                    help="samples per pixel of the rendered reference, split over the chunks "
                         "(default 1024)")
    ap.add_argument("--ref-time", type=float, default=None,
                    help="render the reference for this many seconds in total instead of "
                         "--ref-spp")
    ap.add_argument("--ref-chunks", type=int, default=4,
                    help="independent renders (distinct seeds) averaged into the reference; "
                         ">= 2 lets the script estimate the reference's own noise (default 4)")
    ap.add_argument("--rerender-reference", action="store_true",
                    help="ignore a cached reference and render it again")
    ap.add_argument("--strict-reference", action="store_true",
                    help="re-render a cached reference made by a different binary "
                         "(default: reuse it with a warning)")
    ap.add_argument("--reference-only", action="store_true",
                    help="only make sure the reference exists, then stop")
    ap.add_argument("--integrators", default=",".join(INTEGRATORS),
                    help="comma-separated strategy sets to measure (default bdpt,pt,lt)")
    ap.add_argument("--samplers", default="independent",
                    help="comma-separated clbdpt samplers (independent, sobol); every "
                         "(integrator, budget, seed) run is repeated for each (default "
                         "independent). With both, the summary gives the QMC gain "
                         "RMSE(independent) / RMSE(sobol) at equal time")
    ap.add_argument("--ref-sampler", default="independent", choices=SAMPLERS,
                    help="sampler of the rendered reference (default independent)")
    ap.add_argument("--budgets", type=parse_budgets, default=None,
                    help="comma-separated time budgets in seconds "
                         "(default 1,2,4,8,16,32,64; --quick: 0.5,1,2)")
    ap.add_argument("--scene-budgets", action="append", default=[], metavar="SCENE=LIST",
                    help="budgets for one scene (by name), replacing --budgets there, e.g. "
                         "cornell-box=1,2,4,8,16; repeatable")
    ap.add_argument("--seeds", type=int, default=None,
                    help="renders per integrator and budget, each with its own seed "
                         "(default 3; --quick: 2)")
    ap.add_argument("--seed-base", type=int, default=1,
                    help="run seeds are SEED_BASE + 100*budget_index + seed_index (default 1)")
    ap.add_argument("--order", choices=["shuffled", "ascending"], default="shuffled",
                    help="order of the (budget, seed) runs: shuffled (default; decorrelates "
                         "load drift from budget) or ascending budgets")
    ap.add_argument("--max-depth", type=int, default=None,
                    help="pass --max-depth to every render (default: the scene's)")
    ap.add_argument("--film-scale", type=float, default=None,
                    help="scale each scene's own film size (its JSON 'film') by this factor, "
                         "keeping the aspect (e.g. 0.5: 256x256 -> 128x128, 384x256 -> "
                         "192x128); overrides --width/--height")
    ap.add_argument("--width", type=int, default=None, help="film width override")
    ap.add_argument("--height", type=int, default=None, help="film height override")
    ap.add_argument("--device", default=None, help="clbdpt --device SPEC")
    ap.add_argument("--out-dir", default=None,
                    help="where the CSVs, PNGs and summary.md go (default docs/convergence; "
                         "--quick: CACHE/convergence-quick)")
    ap.add_argument("--work-dir", default=None,
                    help="where the run images go (default: a temporary folder, removed "
                         "afterwards unless --keep-images)")
    ap.add_argument("--keep-images", action="store_true",
                    help="keep every run's EXR and stats JSON in the work folder")
    ap.add_argument("--quick", action="store_true",
                    help="smoke test: 128x128 film, budgets 0.5,1,2 s, 2 seeds, 64 spp "
                         "reference in 2 chunks (under ~2 minutes per scene)")
    args = ap.parse_args(argv)
    args.argv = argv

    if args.quick:
        args.budgets = args.budgets or [0.5, 1.0, 2.0]
        args.seeds = args.seeds or 2
        args.width = args.width or 128
        args.height = args.height or 128
        if "--ref-spp" not in " ".join(argv):
            args.ref_spp = 64
        if "--ref-chunks" not in " ".join(argv):
            args.ref_chunks = 2
        args.out_dir = args.out_dir or os.path.join(args.cache, "convergence-quick")
    args.budgets = args.budgets or [1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0]
    args.seeds = args.seeds or 3
    args.out_dir = args.out_dir or os.path.join(REPO, "docs", "convergence")
    args.integrators = [i.strip() for i in args.integrators.split(",") if i.strip()]
    for i in args.integrators:
        if i not in INTEGRATORS:
            ap.error(f"unknown integrator {i!r}")
    sb = {}
    for item in args.scene_budgets:
        if "=" not in item:
            ap.error(f"--scene-budgets wants SCENE=LIST, got {item!r}")
        n, v = item.split("=", 1)
        try:
            sb[n.strip()] = parse_budgets(v)
        except argparse.ArgumentTypeError as e:
            ap.error(str(e))
    args.scene_budgets = sb
    args.samplers = [m.strip() for m in args.samplers.split(",") if m.strip()]
    if not args.samplers:
        ap.error("--samplers is empty")
    for m in args.samplers:
        if m not in SAMPLERS:
            ap.error(f"unknown sampler {m!r} (choose from {', '.join(SAMPLERS)})")
    if args.film_scale is not None and args.film_scale <= 0:
        ap.error("--film-scale must be positive")
    if args.ref_chunks < 1:
        ap.error("--ref-chunks must be >= 1")
    if args.seeds < 1:
        ap.error("--seeds must be >= 1")
    if args.seeds > 100:
        ap.error("--seeds must be <= 100")
    names = []
    for s in args.scenes:
        names += BUNDLED if s == "all" else [s]
    scenes = [resolve_scene(s) for s in names]
    if args.reference and len(scenes) != 1:
        ap.error("--reference needs exactly one scene")

    os.makedirs(args.out_dir, exist_ok=True)
    os.makedirs(args.cache, exist_ok=True)
    snap = tempfile.mkdtemp(prefix="clbdpt-conv-bin-")
    work = args.work_dir or tempfile.mkdtemp(prefix="clbdpt-conv-runs-")
    try:
        renderer = Renderer(args.binary, args.device, args.width, args.height, args.max_depth,
                            None if args.no_snapshot else snap)
        log(f"binary {renderer.original} ({renderer.version}, sha256 {renderer.sha256[:12]}"
            f"{', snapshot ' + renderer.binary if not args.no_snapshot else ''})")
        summaries, failures = [], []
        for path, name in scenes:
            try:
                s = run_scene(args, renderer, path, name, work)
                if s:
                    summaries.append(s)
            except Exception as e:  # noqa: BLE001 - one broken scene must not stop 'all'
                failures.append((name, str(e)))
                log(f"[{name}] FAILED: {e}")
        if summaries:
            md = markdown(args, summaries, renderer)
            notes = suspicious(summaries)
            md += "## Flags\n\n" + ("\n".join(f"- {n}" for n in notes) if notes else
                                     "- none (all slopes within 0.15 of -0.5, all |z| ≤ 3)")
            md += "\n"
            if failures:
                md += "\n## Failed scenes\n\n" + "\n".join(f"- {n}: {e.splitlines()[-1]}"
                                                           for n, e in failures) + "\n"
            with open(os.path.join(args.out_dir, "summary.md"), "w") as f:
                f.write(md)
            with open(os.path.join(args.out_dir, "summary.json"), "w") as f:
                json.dump(summaries, f, indent=1, default=float)
            write_summary_csv(os.path.join(args.out_dir, "summary.csv"), summaries)
            print(md)
            print("slopes (log RMSE over log seconds; unbiased ≈ -0.5):")
            for s in summaries:
                for integ, d in s["integrators"].items():
                    print(f"  {s['scene']:18s} {integ:16s} {d['slope']:+.3f} ± "
                          f"{d['slope_se']:.3f}   (reference noise subtracted: "
                          f"{d['slope_minus_ref']:+.3f}; over log spp, subtracted: "
                          f"{d['slope_spp_minus_ref']:+.3f})")
            print(f"({NOISE_NOTE})")
            log(f"wrote {os.path.join(args.out_dir, 'summary.md')}")
        return 1 if failures else 0
    finally:
        shutil.rmtree(snap, ignore_errors=True)
        if not args.work_dir and not args.keep_images:
            shutil.rmtree(work, ignore_errors=True)
        elif not args.work_dir:
            log(f"run images kept in {work}")


def write_summary_csv(path, summaries):
    cols = ["scene", "integrator", "sampler", "samples_per_second", "mrays_per_second",
            "rmse_10s", "rmse_10s_extrapolated", "rmse_report", "rmse_report_seconds",
            "qmc_gain", "qmc_gain_minus_ref", "qmc_gain_seconds", "slope", "slope_se", "slope_minus_ref", "slope_spp",
            "slope_spp_minus_ref", "bias_r", "bias_g",
            "bias_b", "bias_se_r", "bias_se_g", "bias_se_b", "ref_spp", "ref_rmse"]
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        for s in summaries:
            for integ, d in s["integrators"].items():
                w.writerow([s["scene"], d["integrator"], d["sampler"],
                            fmt(d["samples_per_second"]),
                            fmt(d["rays_per_second"] / 1e6), fmt(d["rmse_10s"]),
                            d["rmse_10s_extrapolated"], fmt(d["rmse_report"]),
                            fmt(d["rmse_report_seconds"]), fmt(d["qmc_gain"]),
                            fmt(d["qmc_gain_minus_ref"]), fmt(d["qmc_gain_seconds"]),
                            fmt(d["slope"]), fmt(d["slope_se"]),
                            fmt(d["slope_minus_ref"]), fmt(d["slope_spp"]),
                            fmt(d["slope_spp_minus_ref"])] + [fmt(v) for v in d["bias"]] +
                           [fmt(v) for v in d["bias_se"]] +
                           [s["ref"].get("spp", ""), fmt(math.sqrt(s["ref_mse"]))])
    log(f"wrote {path}")


if __name__ == "__main__":
    sys.exit(main())
