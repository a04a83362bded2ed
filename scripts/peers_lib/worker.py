"""One peer render in a fresh process, run by the Python that has the peer installed (pyenv's
python3 after `pip install mitsuba==3.9.1 pyluxcore==2.11.2`). Standard library plus the peer.

    python3 worker.py probe mitsuba|luxcore [VARIANT]   -> one JSON line: version (and variant)
    python3 worker.py render JOB.json                   -> writes job["out"] (.npy, float32 HxWx3)
                                                           and job["out"] + ".json" (timing)

The timed span ("seconds") starts before the scene is built (Mitsuba: load_dict; LuxCore: Scene
and RenderConfig from properties) and ends when the image is in host memory: scene load,
acceleration structures, kernel compilation or kernel-cache load, rendering. Interpreter
start-up and module import are outside it; the caller also records the whole process.

The job (written by scripts/peers): {"peer", "desc" (convert.py's scene.json), "spp", "seed",
"out", "variant" (Mitsuba), "threads", "engine" (LuxCore: PATHCPU or BIDIRCPU)}.

LuxCore quirks handled here: pyluxcore 2.11 aborts while listing PoCL's OpenCL devices (it is
shown none), its halt conditions are only checked by UpdateStats (polled), its film rows run
bottom-up, its default screen window spans the fov across the longer axis and its camera maps
film rows one pixel off (luxcore_screen_window), and its point light divides by 4 pi.
"""
import array
import json
import math
import os
import sys
import time

# Largest number of Mitsuba wavefront lanes (pixels x samples) in one mi.render call: an LLVM
# wavefront keeps the path state of every lane in memory at once, so larger sample counts are
# rendered as several passes with distinct seeds and averaged.
MAX_LANES = 1 << 22


class NotFaithful(Exception):
    """The peer has no faithful equivalent of something the scene uses."""


def write_npy(path, data, height, width):
    """float32 HxWx3 .npy without numpy (format version 1.0)."""
    header = "{'descr': '<f4', 'fortran_order': False, 'shape': (%d, %d, 3), }" % (height, width)
    header += " " * ((64 - (10 + len(header) + 1) % 64) % 64) + "\n"
    with open(path + ".tmp", "wb") as f:
        f.write(b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode("latin1"))
        data.tofile(f)
    os.replace(path + ".tmp", path)


def _sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def _norm(a):
    n = math.sqrt(sum(x * x for x in a))
    return [x / n for x in a]


def _any_perpendicular(d):
    return [0.0, 0.0, 1.0] if abs(d[1]) > 0.9 else [0.0, 1.0, 0.0]


def _scene_scale(desc):
    lo, hi = desc["bounds"]
    return max(1e-6, math.dist(lo, hi), math.dist(desc["camera"]["eye"], [(a + b) / 2 for a, b in zip(lo, hi)]))


# ---- Mitsuba 3 -------------------------------------------------------------------------------


def mitsuba_bsdf(m):
    def rgb(v):
        return {"type": "rgb", "value": [float(x) for x in v]}

    kind = m["kind"]
    if kind == "glass":
        # clbdpt's dielectric has air (index 1) outside, not Mitsuba's default 1.000277
        return {"type": "dielectric", "int_ior": float(m["ior"]), "ext_ior": 1.0}
    if kind == "mirror":
        inner = {"type": "conductor", "material": "none", "specular_reflectance": rgb(m["ks"])}
    elif kind == "diffuse":
        inner = {"type": "diffuse", "reflectance": rgb(m["kd"])}
    else:
        # f = kd/pi + ks*GGX with Fresnel 1 (conductor "none": eta 0, k 1), written as Mitsuba's
        # convex blend (1-w)*A + w*B with A = diffuse(kd/(1-w)), B = roughconductor(ks/w).
        # w: clbdpt's lobe-selection probability lum(ks)/(lum(kd)+lum(ks)), moved into
        # [max(ks), 1 - max(kd)] where Mitsuba's reflectances must stay <= 1 (non-empty since
        # the loader keeps kd + ks <= 1 per channel... per channel only: else not converted).
        lum = lambda c: 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]  # noqa: E731
        ld, ls = lum(m["kd"]), lum(m["ks"])
        spec = {"type": "roughconductor", "material": "none", "distribution": "ggx",
                "alpha": float(m["alpha"]), "sample_visible": True}
        if ld <= 0:
            spec["specular_reflectance"] = rgb(m["ks"])
            inner = spec
        else:
            lo, hi = max(m["ks"]), 1.0 - max(m["kd"])
            if lo > hi:
                raise NotFaithful(f"material '{m.get('name')}': max(Kd) + max(Ks) > 1 has no Mitsuba blend")
            w = min(max(ls / (ld + ls), lo), hi)
            spec["specular_reflectance"] = rgb([x / w for x in m["ks"]])
            inner = {"type": "blendbsdf", "weight": w,
                     "diffuse": {"type": "diffuse", "reflectance": rgb([x / (1 - w) for x in m["kd"]])},
                     "glossy": spec}
    return {"type": "twosided", "bsdf": inner}  # clbdpt reflects on both faces


def mitsuba_grid(mi, grid, sigma_t):
    """A clbdpt density grid times sigma_t (3 channels) as a Mitsuba gridvolume. Mitsuba's grid
    fills the unit cube with voxel centres at (i + 0.5) / n, clamped at its faces, as clbdpt's;
    to_world takes it to where clbdpt's world_to_grid puts the voxels."""
    import numpy as np
    nx, ny, nz = grid["size"]
    density = np.fromfile(grid["voxels"], dtype="<f4").reshape(nz, ny, nx)
    data = np.stack([density * c for c in sigma_t], axis=-1).astype(np.float32)
    a = np.array([row[:3] for row in grid["world_to_grid"]], dtype=np.float64)
    b = np.array([row[3] for row in grid["world_to_grid"]], dtype=np.float64)
    a_inv = np.linalg.inv(a)
    m = np.eye(4)
    m[:3, :3] = a_inv @ np.diag([nx, ny, nz])  # unit cube -> voxel coordinates -> scene
    m[:3, 3] = a_inv @ (-0.5 - b)
    return {"type": "gridvolume", "grid": mi.VolumeGrid(data), "filter_type": "trilinear",
            "to_world": mi.ScalarTransform4f(m.tolist())}


def mitsuba_scene(mi, desc, spp, seed, max_depth_offset=1, russian_roulette=False):
    c = desc["camera"]
    scale = _scene_scale(desc)
    sensor = {"type": "thinlens" if c["lens_radius"] > 0 else "perspective",
              "fov": float(c["fov"]), "fov_axis": "smaller",
              "near_clip": 1e-5 * scale, "far_clip": 1e3 * scale,
              "to_world": mi.ScalarTransform4f().look_at(origin=c["eye"], target=c["target"], up=c["up"]),
              "sampler": {"type": "multijitter", "sample_count": int(spp), "seed": int(seed)},
              "film": {"type": "hdrfilm", "width": desc["width"], "height": desc["height"],
                       "pixel_format": "rgb", "component_format": "float32",
                       "rfilter": {"type": "box"}}}  # box of radius 0.5: one pixel, as clbdpt
    if c["lens_radius"] > 0:
        sensor["aperture_radius"] = float(c["lens_radius"])
        sensor["focus_distance"] = float(c["focus_distance"])
    depth = desc["max_depth"] + max_depth_offset  # Mitsuba counts the emitter vertex too
    media = desc.get("media") or {}
    # Without Russian roulette, rr_depth past max_depth never triggers; with it, Mitsuba's own
    # default (rr_depth 5: from the 5th vertex on, the emitter's counted).
    integrator = {"type": "volpath" if media else "path", "max_depth": depth}
    if not russian_roulette:
        integrator["rr_depth"] = depth + 1
    scene = {"type": "scene", "sensor": sensor, "integrator": integrator}
    for name, m in media.items():
        sigma_t = [a + b for a, b in zip(m["sigma_a"], m["sigma_s"])]
        albedo = [b / t if t > 0 else 0.0 for b, t in zip(m["sigma_s"], sigma_t)]
        scene["medium_" + name] = {"type": "homogeneous", "scale": 1.0,
                                   "sigma_t": {"type": "rgb", "value": sigma_t},
                                   "albedo": {"type": "rgb", "value": albedo},
                                   "phase": {"type": "hg", "g": float(m["g"])}}
        if m.get("grid"):
            scene["medium_" + name].update({"type": "heterogeneous", "sigma_t": mitsuba_grid(mi, m["grid"], sigma_t)})
    if desc.get("medium"):
        # clbdpt finds the camera's medium with a probe ray; the peers' scenes keep the camera
        # in the scene-wide medium.
        sensor["medium"] = {"type": "ref", "id": "medium_" + desc["medium"]}
    for s in desc["shapes"]:
        shape = {"type": "ply", "filename": s["ply"], "face_normals": not s["normals"],
                 "bsdf": {"type": "null"} if s.get("interface") else mitsuba_bsdf(s["material"])}
        for side in ("interior", "exterior"):
            if s.get(side):
                shape[side] = {"type": "ref", "id": "medium_" + s[side]}
        if s["emission"]:
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": s["emission"]}}
        scene[s["name"]] = shape
    for i, light in enumerate(desc["lights"]):
        t = light["type"]
        if t == "point":
            scene[f"light{i}"] = {"type": "point", "position": light["position"],
                                  "intensity": {"type": "rgb", "value": light["intensity"]}}
        elif t == "spot":
            d = _norm(_sub(light["target"], light["position"]))
            # Mitsuba's falloff is linear in angle; clbdpt's is pbrt's quartic in cos. The
            # profile comes from a texture instead (convert.spot_profile), Mitsuba's own
            # falloff pushed into the last 1e-4 degrees of the cone.
            scene[f"light{i}"] = {
                "type": "spot", "intensity": {"type": "rgb", "value": light["intensity"]},
                "cutoff_angle": float(light["cone_angle"]), "beam_width": float(light["cone_angle"]) - 1e-4,
                "to_world": mi.ScalarTransform4f().look_at(origin=light["position"], target=light["target"],
                                                           up=_any_perpendicular(d)),
                "texture": {"type": "bitmap", "filename": light["profile"], "raw": True,
                            "filter_type": "bilinear", "wrap_mode": "clamp"}}
        elif t == "directional":
            scene[f"light{i}"] = {"type": "directional", "direction": light["direction"],
                                  "irradiance": {"type": "rgb", "value": light["radiance"]}}
        elif t == "environment":
            if light["map"]:
                # Mitsuba: u = atan2(x, -z)/2pi, v = acos(y)/pi in the emitter's frame; clbdpt:
                # u = atan2(z, x)/2pi, v = acos(y)/pi. to_world maps local (x,y,z) to world (-z,y,x).
                rot = mi.ScalarTransform4f([[0, 0, -1, 0], [0, 1, 0, 0], [1, 0, 0, 0], [0, 0, 0, 1]])
                scene[f"light{i}"] = {"type": "envmap", "filename": light["map_scaled"], "to_world": rot}
            else:
                scene[f"light{i}"] = {"type": "constant", "radiance": {"type": "rgb", "value": light["radiance"]}}
    return scene


def render_mitsuba(job, desc):
    import mitsuba as mi
    mi.set_variant(job["variant"])
    import drjit as dr
    w, h, spp = desc["width"], desc["height"], int(job["spp"])
    per_pass = max(1, MAX_LANES // (w * h)) if job["variant"].startswith("llvm") else spp
    passes = []
    left = spp
    while left > 0:
        n = min(per_pass, left)
        passes.append(n)
        left -= n
    t0 = time.perf_counter()
    scene = mi.load_dict(mitsuba_scene(mi, desc, passes[0], job["seed"],
                                       russian_roulette=bool(job.get("russian_roulette"))))
    t_load = time.perf_counter() - t0
    acc, done = None, 0
    for k, n in enumerate(passes):
        sampler = scene.sensors()[0].sampler()
        sampler.set_sample_count(n)
        n = sampler.sample_count()  # multijitter may round to its grid
        img = mi.render(scene, spp=n, seed=int(job["seed"]) * 1000 + k)
        acc = img * n if acc is None else acc + img * n
        dr.eval(acc)  # one kernel per pass, not one graph of all passes
        done += n
    acc = acc / done
    dr.eval(acc)
    dr.sync_thread()
    out = array.array("f", acc.array)
    seconds = time.perf_counter() - t0
    return out, {"seconds": seconds, "load_seconds": t_load, "spp": done, "passes": len(passes),
                 "variant": job["variant"], "version": mi.__version__}


# ---- LuxCore ---------------------------------------------------------------------------------


def luxcore_screen_window(width, height):
    """LuxCore's screen window (x0 x1 y0 y1) for clbdpt's framing. Its default spans the fov
    across the longer axis (clbdpt: the shorter), and PerspectiveCamera::InitRay maps film row
    filmY to raster y = height - filmY - 1, one pixel off a pixel-centred film: the window is
    moved down by one pixel to undo that."""
    if width >= height:
        x, y = width / height, 1.0
    else:
        x, y = 1.0, height / width
    dy = 2.0 * y / height
    return [-x, x, -y - dy, y - dy]


def luxcore_props(desc, spp, seed, threads, depth_offset=1, engine="PATHCPU"):
    def v3(x):
        return " ".join(f"{float(a):.9g}" for a in x)

    c = desc["camera"]
    depth = desc["max_depth"] + depth_offset
    cfg = [f'renderengine.type = "{engine}"',
           'sampler.type = "SOBOL"',
           f"batch.haltspp = {int(spp)}",
           "batch.haltthreshold = -1",
           f"film.width = {desc['width']}", f"film.height = {desc['height']}",
           'film.filter.type = "BOX"', "film.filter.width = 0.5",  # one pixel, as clbdpt
           f"path.pathdepth.total = {depth}", f"path.pathdepth.diffuse = {depth}",
           f"path.pathdepth.glossy = {depth}", f"path.pathdepth.specular = {depth}",
           # no Russian roulette, as clbdpt (it starts at this depth)
           f"path.russianroulette.depth = {depth + 64}",
           "path.clamping.variance.maxvalue = 0",
           f"renderengine.seed = {int(seed) + 1}",
           # BIDIRCPU limits each subpath (eye, light) rather than the whole path
           f"path.maxdepth = {depth}", f"light.maxdepth = {depth}",
           "film.imagepipelines.0.0.type = NOP",
           f"native.threads.count = {int(threads)}"]
    scn = ['scene.camera.type = "perspective"',
           f"scene.camera.lookat.orig = {v3(c['eye'])}",
           f"scene.camera.lookat.target = {v3(c['target'])}",
           f"scene.camera.up = {v3(c['up'])}",
           f"scene.camera.fieldofview = {float(c['fov']):.9g}",
           f"scene.camera.cliphither = {1e-5 * _scene_scale(desc):.9g}",
           f"scene.camera.clipyon = {1e3 * _scene_scale(desc):.9g}",
           f"scene.camera.screenwindow = {v3(luxcore_screen_window(desc['width'], desc['height']))}"]
    if c["lens_radius"] > 0:
        scn += [f"scene.camera.lensradius = {c['lens_radius']:.9g}",
                f"scene.camera.focaldistance = {c['focus_distance']:.9g}"]
    for s in desc["shapes"]:
        m, name = s["material"], s["name"]
        p = f"scene.materials.{name}"
        kind = m["kind"]
        if kind == "diffuse":
            scn += [f'{p}.type = "matte"', f"{p}.kd = {v3(m['kd'])}"]
        elif kind == "mirror":
            scn += [f'{p}.type = "mirror"', f"{p}.kr = {v3(m['ks'])}"]
        elif kind == "glass":
            scn += [f'{p}.type = "glass"', f"{p}.kr = 1 1 1", f"{p}.kt = 1 1 1",
                    f"{p}.interiorior = {m['ior']:.9g}", f"{p}.exteriorior = 1"]
        else:
            # kd/pi + ks*GGX without Fresnel: mix(matte kd/(1-ks), metal2 with Fresnel 1) at amount
            # ks per channel. metal2's D is GGX with roughness u*v = alpha^2; its G is Schlick's
            # separable approximation (clbdpt: height-correlated Smith) -- let the mean check judge.
            ks = m["ks"]
            kd = [m["kd"][i] / (1.0 - ks[i]) if ks[i] < 1.0 else 0.0 for i in range(3)]
            scn += [f'scene.textures.{name}_fresnel.type = "fresnelconst"',
                    f"scene.textures.{name}_fresnel.n = 1e-4 1e-4 1e-4", f"scene.textures.{name}_fresnel.k = 1 1 1",
                    f'scene.materials.{name}_d.type = "matte"', f"scene.materials.{name}_d.kd = {v3(kd)}",
                    f'scene.materials.{name}_s.type = "metal2"', f'scene.materials.{name}_s.fresnel = "{name}_fresnel"',
                    f"scene.materials.{name}_s.uroughness = {m['alpha']:.9g}",
                    f"scene.materials.{name}_s.vroughness = {m['alpha']:.9g}",
                    f'{p}.type = "mix"', f'{p}.material1 = "{name}_d"', f'{p}.material2 = "{name}_s"',
                    f"{p}.amount = {v3(ks)}"]
        if s["emission"]:
            scn += [f"{p}.emission = {v3(s['emission'])}", f"{p}.emission.gain = 1 1 1",
                    f"{p}.emission.power = 0", f"{p}.emission.efficiency = 0"]
        scn += [f'scene.shapes.{name}.type = "mesh"', f'scene.shapes.{name}.ply = "{s["ply"]}"',
                f'scene.objects.{name}.shape = "{name}"', f'scene.objects.{name}.material = "{name}"']
    for i, light in enumerate(desc["lights"]):
        p = f"scene.lights.light{i}"
        t = light["type"]
        if t == "point":
            # LuxCore's point light emits color * gain / (4 pi) per steradian
            g = 4.0 * math.pi
            scn += [f'{p}.type = "point"', f"{p}.position = {v3(light['position'])}",
                    f"{p}.color = {v3(light['intensity'])}", f"{p}.gain = {g:.9g} {g:.9g} {g:.9g}",
                    f"{p}.power = 0", f"{p}.efficiency = 0"]
        elif t == "spot":
            # LuxCore's spot falloff is pbrt's (delta^4 in cos), as clbdpt's, but its intensity
            # has an extra 1/cos(theta) off the axis (SpotLight::Illuminate): not faithful.
            scn += [f'{p}.type = "spot"', f"{p}.position = {v3(light['position'])}",
                    f"{p}.target = {v3(light['target'])}", f"{p}.color = {v3(light['intensity'])}",
                    f"{p}.gain = 1 1 1", f"{p}.power = 0", f"{p}.efficiency = 0",
                    f"{p}.coneangle = {light['cone_angle']:.9g}", f"{p}.conedeltaangle = {light['cone_delta']:.9g}"]
        elif t == "directional":
            scn += [f'{p}.type = "distant"', f"{p}.direction = {v3(light['direction'])}",
                    f"{p}.color = {v3(light['radiance'])}", f"{p}.gain = 1 1 1", f"{p}.theta = 0"]
        elif t == "environment":
            if light["map"]:
                # LuxCore: u = atan2(y, x)/2pi, v = acos(z)/pi in the light's frame; clbdpt: u =
                # atan2(z, x)/2pi, v = acos(y)/pi. The light-to-world matrix swaps y and z.
                scn += [f'{p}.type = "infinite"', f'{p}.file = "{light["map"]}"',
                        f"{p}.gain = {v3(light['radiance'])}", f"{p}.gamma = 1",
                        f'{p}.storage = "float"', f'{p}.filter = "nearest"',
                        f"{p}.transformation = 1 0 0 0  0 0 1 0  0 1 0 0  0 0 0 1"]
            else:
                scn += [f'{p}.type = "constantinfinite"', f"{p}.color = {v3(light['radiance'])}",
                        f"{p}.gain = 1 1 1"]
    return "\n".join(cfg), "\n".join(scn)


def _quiet(msg):
    pass


def import_luxcore():
    import contextlib
    import io
    import tempfile
    # PATHCPU needs no OpenCL, and pyluxcore 2.11 aborts ("double free") while listing PoCL's
    # devices: show it an empty OpenCL ICD folder.
    os.environ["OCL_ICD_VENDORS"] = tempfile.mkdtemp(prefix="no-opencl-")
    with contextlib.redirect_stdout(io.StringIO()):  # its import lists the libraries it loads
        import pyluxcore
    pyluxcore.Init(_quiet)
    return pyluxcore


def render_luxcore(job, desc):
    pyluxcore = import_luxcore()
    w, h = desc["width"], desc["height"]
    cfg_text, scn_text = luxcore_props(desc, job["spp"], job["seed"], job["threads"],
                                       engine=job.get("engine", "PATHCPU"))
    t0 = time.perf_counter()
    scene = pyluxcore.Scene()
    scene.Parse(pyluxcore.Properties().SetFromString(scn_text))
    config = pyluxcore.RenderConfig(pyluxcore.Properties().SetFromString(cfg_text), scene)
    session = pyluxcore.RenderSession(config)
    t_load = time.perf_counter() - t0
    session.Start()
    while not session.HasDone():  # the halt condition (batch.haltspp) is checked by UpdateStats
        time.sleep(0.005)
        session.UpdateStats()
    session.Stop()
    film = session.GetFilm()
    buf = array.array("f", [0.0]) * (w * h * 3)
    film.GetOutputFloat(pyluxcore.FilmOutputType.RGB, buf)
    seconds = time.perf_counter() - t0
    stats = session.GetStats()
    samples = stats.Get("stats.renderengine.total.samplecount").GetFloat()
    # LuxCore's film rows run bottom-up
    out = array.array("f", [0.0]) * (w * h * 3)
    for y in range(h):
        src = (h - 1 - y) * w * 3
        out[y * w * 3:(y + 1) * w * 3] = buf[src:src + w * 3]
    return out, {"seconds": seconds, "load_seconds": t_load, "spp": samples / (w * h),
                 "version": pyluxcore.Version()}


# ---- entry -----------------------------------------------------------------------------------


def probe(peer, variant=None):
    if peer == "mitsuba":
        import mitsuba as mi
        info = {"version": mi.__version__, "variants": mi.variants()}
        if variant:
            mi.set_variant(variant)
            scene = mi.load_dict({"type": "scene", "integrator": {"type": "path"},
                                  "sensor": {"type": "perspective", "film": {"type": "hdrfilm", "width": 8, "height": 8},
                                             "sampler": {"type": "multijitter", "sample_count": 4}},
                                  "s": {"type": "sphere", "bsdf": {"type": "twosided", "bsdf": {
                                      "type": "blendbsdf", "weight": 0.5, "a": {"type": "diffuse"},
                                      "b": {"type": "roughconductor", "material": "none"}}}},
                                  "e": {"type": "constant"}})
            import drjit as dr
            img = mi.render(scene)
            dr.eval(img)
            info["variant"] = variant
            info["probe_mean"] = float(sum(array.array("f", img.array)) / (8 * 8 * 3))
        return info
    if peer == "luxcore":
        return {"version": import_luxcore().Version()}
    raise SystemExit(f"unknown peer {peer}")


def main():
    if sys.argv[1] == "probe":
        print(json.dumps(probe(sys.argv[2], sys.argv[3] if len(sys.argv) > 3 else None)), flush=True)
        os._exit(0)
    with open(sys.argv[2]) as f:
        job = json.load(f)
    with open(job["desc"]) as f:
        desc = json.load(f)
    renderer = {"mitsuba": render_mitsuba, "luxcore": render_luxcore}[job["peer"]]
    try:
        pixels, info = renderer(job, desc)
    except NotFaithful as e:
        print(f"not faithful: {e}", file=sys.stderr, flush=True)
        os._exit(3)
    write_npy(job["out"], pixels, desc["height"], desc["width"])
    with open(job["out"] + ".json", "w") as f:
        json.dump(info, f)
    sys.stdout.flush()
    sys.stderr.flush()
    # pyluxcore's log callback and render threads crash the interpreter's finalisation
    os._exit(0)


if __name__ == "__main__":
    sys.exit(main())
