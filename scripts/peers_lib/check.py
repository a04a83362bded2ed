"""Is a peer's conversion faithful? Its image against clbdpt's reference: mean and per-channel
means, framing, and per-pixel agreement within the noise (scripts/peers, step 3)."""
import math
import os

import numpy as np

from . import convert

MEAN_TOLERANCE = 0.01   # a conversion is valid when its image mean is within 1% of the reference
MAX_CHECK_SE = 0.005    # ... and each channel's, measured with a standard error below 0.5%
MAX_EXCESS = 4.0        # ... and its MSE against the reference at most 4x what the noise explains
SHIFT_MARGIN = 0.98     # framing is off when a 1-pixel shift or a mirror fits 2% better
CHECK_SEEDS = (2_000_001, 2_000_002)


def framing(img, ref):
    """'ok', or how the image fits the reference better (shifted by a pixel, mirrored)."""
    h, w, _ = ref.shape
    c = (slice(2, h - 2), slice(2, w - 2))

    def err(x):
        return float(np.mean((x[c] - ref[c]) ** 2))

    base = err(img)
    tries = {f"shifted {dx:+d},{dy:+d} px": np.roll(np.roll(img, dy, axis=0), dx, axis=1)
             for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dx or dy}
    tries["mirrored left-right"] = img[:, ::-1]
    tries["mirrored top-bottom"] = img[::-1]
    best = min(tries, key=lambda k: err(tries[k]))
    return best if err(tries[best]) < SHIFT_MARGIN * base else "ok"


def check_conversion(check_spp, renderer, scene, ref, ref_info, tmp, row):
    """Mean and framing of a --check-spp peer render against the reference (also warms caches).
    A renderer without seeds (pbrt-v3) renders once; its own noise is then unknown and only the
    reference's enters the standard error, and the per-pixel test is skipped."""
    seeds = CHECK_SEEDS[:1] if getattr(renderer, "deterministic", False) else CHECK_SEEDS
    halves = []
    for i, seed in enumerate(seeds):
        r = renderer.render(scene, max(1, check_spp // len(seeds)), seed, os.path.join(tmp, f"check{i}"))
        halves.append(r["image"])
    bad = sum(int(np.count_nonzero(~np.isfinite(h))) for h in halves)
    halves = [np.nan_to_num(h, nan=0.0, posinf=0.0, neginf=0.0) for h in halves]
    img = sum(halves) / len(halves)
    diff = (img.mean() - ref.mean()) / ref.mean()
    own = np.mean((halves[0] - halves[1]) ** 2) / 4.0 if len(halves) == 2 else None
    se = math.sqrt((own or 0.0) / img.size + ref_info["mean_se"] ** 2) / ref.mean()
    frame = framing(img, ref)
    # Per-pixel agreement: an unbiased, aligned image differs from the reference by noise only,
    # MSE = its own variance + the reference's (both estimated from independent halves).
    excess = None
    if own is not None:
        noise = own + ref_info["mse"]
        excess = float(np.mean((img - ref) ** 2) / noise) if noise > 0 else float("inf")
    result = {"row": row, "mean_diff": float(diff), "mean_se": float(se), "framing": frame, "excess": excess,
              "rmse": float(np.sqrt(np.mean((img - ref) ** 2))),
              "check_spp": len(seeds) * max(1, check_spp // len(seeds)),
              "channel_diff": [float(x) for x in img.mean(axis=(0, 1)) / ref.mean(axis=(0, 1)) - 1.0],
              "nonfinite": bad}
    worst = max([abs(diff)] + [abs(x) for x in result["channel_diff"]])
    excessive = excess is not None and excess > MAX_EXCESS
    result["valid"] = worst <= MEAN_TOLERANCE and se <= MAX_CHECK_SE and frame == "ok" and not excessive
    if worst > MEAN_TOLERANCE:
        result["why"] = f"mean {100 * diff:+.1f}%" + ("" if abs(diff) == worst else f", a channel {100 * worst:.1f}% off")
    elif se > MAX_CHECK_SE:
        result["why"] = f"check too noisy (+-{100 * se:.1f}%): raise --check-spp"
    elif frame != "ok":
        result["why"] = frame
    elif excessive:
        result["why"] = f"pixels differ beyond noise (MSE {excess:.0f}x the noise)"
    result["notes"] = conversion_notes(row, scene.desc)
    return result


def conversion_notes(row, desc):
    """What a peer reproduces only approximately in this scene (the mean check has the last word)."""
    kinds = {s["material"]["kind"] for s in desc["shapes"]}
    lights = {light["type"] for light in desc["lights"]}
    notes = []
    if "glossy" in kinds:
        notes.append({"Mitsuba": "glossy: Mitsuba's GGX uses separable Smith G (clbdpt: height-correlated)",
                      "LuxCore": "glossy: metal2's Schlick-Smith G (clbdpt: height-correlated Smith), mix with matte",
                      "pbrt-v3": "glossy: mix of matte and metal (Fresnel 1); grey Ks only"}.get(row.split()[0], ""))
    if "spot" in lights and row.startswith("LuxCore"):
        notes.append("spot: LuxCore's intensity carries an extra 1/cos(theta) off the axis")
    if "spot" in lights and row.startswith("Mitsuba"):
        notes.append("spot: falloff given as a texture (Mitsuba's own is linear in angle)")
    if "environment" in lights and row.startswith(("Mitsuba", "pbrt")):
        notes.append(f"environment map upsampled {convert.ENV_UPSAMPLE}x nearest (the peer filters bilinearly)")
    if row.startswith("LuxCore BIDIR"):
        notes.append("BIDIRCPU limits eye and light subpaths separately, not the whole path")
    return [n for n in notes if n]
