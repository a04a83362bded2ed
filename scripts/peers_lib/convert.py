"""clbdpt scene (JSON + OBJ/MTL) -> a renderer-neutral description that worker.py turns into a
Mitsuba 3 or LuxCore scene, and pbrt_scene() into a pbrt-v3 file. Standard library only (runs
under any Python 3); the environment-map copy uses OpenImageIO and numpy.

What clbdpt means by its inputs (host/scene/mtl_materials.cpp, cl/bsdf.h, cl/lights.h):
  illum 5            perfect mirror, reflectance Ks
  illum 7            smooth dielectric, index Ni (1.5 when missing or <= 1), front face outside
  Ks > 0 otherwise   Kd/pi + Ks * GGX(alpha) D*G/(4 cos cos), height-correlated Smith G, no
                     Fresnel; alpha = Pr^2, else sqrt(2/(Ns+2)), clamped to [1e-3, 1]
  otherwise          Lambertian Kd
  Ke                 one-sided area light on the counter-clockwise (front) face, radiance Ke
  kd + ks > 1        both scaled so the channel sums to 1 (glass excepted)
Reflection is two-sided. Missing MTL keys take tinyobj's defaults (Kd 0, Ns 1); faces without a
material get the grey default (Kd 0.5).

The OBJ is split by material into binary PLY files (one shape, one BSDF), triangulated as a fan
with the winding kept, vertex normals kept where every face of the material has them. Emitter
shapes drop their vertex normals: clbdpt decides an emitter's side by the geometric normal, and
Mitsuba by the shading normal.
"""
import json
import math
import os
import struct

from scene_files import scene_files, scene_hash, sha256_file  # noqa: F401 (re-exported for scripts/peers)

# tinyobj / clbdpt constants (host/scene/mtl_materials.cpp)
DEFAULT_GLASS_IOR = 1.5
MIN_ALPHA, MAX_ALPHA = 1e-3, 1.0
DEFAULT_MATERIAL = {"kind": "diffuse", "kd": [0.5, 0.5, 0.5], "ks": [0, 0, 0], "ke": [0, 0, 0]}
# clbdpt's scene defaults (README "Scene file")
DEFAULT_FOV = 39.3
DEFAULT_MAX_DEPTH = 5
# Environment maps are copied nearest-neighbour upsampled by this factor, so that a peer's
# bilinear lookup (Mitsuba has no other) reproduces clbdpt's nearest-texel lookup everywhere but
# in thin bands along texel edges (1/ENV_UPSAMPLE of a texel wide).
ENV_UPSAMPLE = 8
# MTL keys naming textures clbdpt reads; a scene using them is not converted (the peers' texture
# conventions -- sRGB decoding, v orientation, cut-out threshold -- would each need checking).
TEXTURE_KEYS = ("map_kd", "map_ks", "map_ke", "map_d", "bump", "map_bump", "norm")


class NotConvertible(Exception):
    """The scene uses something this converter does not reproduce faithfully."""


def luminance(c):
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]


def _floats(tokens, n, default=0.0):
    vals = [float(t) for t in tokens[:n]]
    if len(vals) == 1 and n == 3:  # "Kd 0.5" means grey
        vals = vals * 3
    while len(vals) < n:
        vals.append(default)
    return vals


# ---- MTL -------------------------------------------------------------------------------------


def parse_mtl(path):
    """name -> dict of the keys clbdpt reads (lower-case keys; colours as 3 floats)."""
    materials, cur = {}, None
    with open(path, errors="replace") as f:
        for raw in f:
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            tok = line.split()
            key = tok[0].lower()
            if key == "newmtl":
                cur = {"name": " ".join(tok[1:])}
                materials[cur["name"]] = cur
            elif cur is None:
                continue
            elif key in ("kd", "ks", "ke", "tf"):
                cur[key] = [max(0.0, v) if math.isfinite(v) else 0.0 for v in _floats(tok[1:], 3)]
            elif key in ("ns", "ni", "pr", "d"):
                cur[key] = float(tok[1])
            elif key == "tr":
                cur["d"] = 1.0 - float(tok[1])
            elif key == "illum":
                cur["illum"] = int(float(tok[1]))
            elif key in TEXTURE_KEYS:
                cur.setdefault("textures", []).append(key)
    return materials


def map_material(mtl):
    """clbdpt's reading of one MTL material (host/scene/mtl_materials.cpp map_mtl_material)."""
    if mtl is None:
        return dict(DEFAULT_MATERIAL)
    if mtl.get("textures"):
        raise NotConvertible(f"material '{mtl['name']}' uses textures ({', '.join(mtl['textures'])})")
    kd = list(mtl.get("kd", [0.0, 0.0, 0.0]))
    ks = list(mtl.get("ks", [0.0, 0.0, 0.0]))
    ke = list(mtl.get("ke", [0.0, 0.0, 0.0]))
    illum = mtl.get("illum", 0)
    m = {"name": mtl["name"], "ke": ke}
    if illum == 5:
        m.update(kind="mirror", kd=[0.0] * 3, ks=ks)
    elif illum == 7:
        ni = mtl.get("ni", 1.0)
        m.update(kind="glass", ior=ni if (math.isfinite(ni) and ni > 1.0) else DEFAULT_GLASS_IOR)
        return m
    elif any(c > 0 for c in ks):
        pr = mtl.get("pr", 0.0)
        if pr > 0:
            alpha = pr * pr
        else:
            alpha = math.sqrt(2.0 / (max(0.0, mtl.get("ns", 1.0)) + 2.0))
        if not math.isfinite(alpha):
            alpha = MAX_ALPHA
        m.update(kind="glossy", kd=kd, ks=ks, alpha=min(max(alpha, MIN_ALPHA), MAX_ALPHA))
    else:
        m.update(kind="diffuse", kd=kd, ks=[0.0] * 3)
    for i in range(3):  # energy conservation, as the loader does
        s = m["kd"][i] + m["ks"][i]
        if s > 1.0:
            m["kd"][i] /= s
            m["ks"][i] /= s
    return m


# ---- OBJ -------------------------------------------------------------------------------------


def parse_obj(path):
    """Positions, normals, the MTL libraries and per-material face lists [(v, vn), ...]."""
    positions, normals, mtllibs = [], [], []
    groups = {}  # material name (None = no usemtl) -> list of faces
    current = groups.setdefault(None, [])
    current_name = None
    with open(path, errors="replace") as f:
        pending = ""
        for raw in f:
            line = raw.rstrip("\n").rstrip("\r")
            if line.endswith("\\"):
                pending += line[:-1] + " "
                continue
            line = (pending + line).split("#", 1)[0].strip()
            pending = ""
            if not line:
                continue
            tok = line.split()
            key = tok[0]
            if key == "v":
                positions.append(tuple(float(t) for t in tok[1:4]))
            elif key == "vn":
                normals.append(tuple(float(t) for t in tok[1:4]))
            elif key == "f":
                face = []
                for t in tok[1:]:
                    parts = t.split("/")
                    vi = int(parts[0])
                    vi = vi - 1 if vi > 0 else len(positions) + vi
                    ni = None
                    if len(parts) >= 3 and parts[2]:
                        ni = int(parts[2])
                        ni = ni - 1 if ni > 0 else len(normals) + ni
                    face.append((vi, ni))
                if len(face) >= 3:
                    current.append(face)
            elif key == "usemtl":
                current_name = " ".join(tok[1:])
                current = groups.setdefault(current_name, [])
            elif key == "mtllib":
                mtllibs.append(line.split(None, 1)[1].strip())
    return positions, normals, mtllibs, {k: v for k, v in groups.items() if v}


def triangulate(face):
    """Fan triangulation keeping the winding (clbdpt: fan for quads, ear clipping beyond -- the
    same triangles for the convex polygons the bundled scenes have)."""
    if len(face) > 4:
        raise NotConvertible(f"polygon with {len(face)} corners (clbdpt ear-clips those)")
    return [(face[0], face[i], face[i + 1]) for i in range(1, len(face) - 1)]


def write_ply(path, verts, norms, tris):
    with open(path, "wb") as f:
        header = ["ply", "format binary_little_endian 1.0", f"element vertex {len(verts)}",
                  "property float x", "property float y", "property float z"]
        if norms:
            header += ["property float nx", "property float ny", "property float nz"]
        header += [f"element face {len(tris)}", "property list uchar int vertex_indices", "end_header"]
        f.write(("\n".join(header) + "\n").encode("ascii"))
        vfmt = struct.Struct("<6f" if norms else "<3f")
        for i, v in enumerate(verts):
            f.write(vfmt.pack(*(v + norms[i]) if norms else v))
        tfmt = struct.Struct("<B3i")
        for t in tris:
            f.write(tfmt.pack(3, *t))


def _tri_area2(p0, p1, p2):
    a = [p1[i] - p0[i] for i in range(3)]
    b = [p2[i] - p0[i] for i in range(3)]
    c = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
    return math.sqrt(c[0] ** 2 + c[1] ** 2 + c[2] ** 2)


# ---- scene -----------------------------------------------------------------------------------


def film_size(scene_json, width):
    """Film of `width` pixels with the scene's aspect ratio."""
    with open(scene_json) as f:
        film = json.load(f).get("film", {})
    w, h = film.get("width", 256), film.get("height", 256)
    return width, max(1, round(width * h / w))


def convert(scene_json, out_dir, width, height):
    """Writes out_dir/<n>_<material>.ply and out_dir/scene.json; returns the description.
    Raises NotConvertible with the reason when the scene uses what is not reproduced."""
    os.makedirs(out_dir, exist_ok=True)
    base = os.path.dirname(os.path.abspath(scene_json))
    with open(scene_json) as f:
        js = json.load(f)
    cam = js.get("camera", {})
    if "eye" not in cam or "target" not in cam:
        raise NotConvertible("no explicit camera eye/target (clbdpt frames the model itself)")
    eye, target = cam["eye"], cam["target"]
    camera = {"eye": eye, "target": target, "up": cam.get("up", [0, 1, 0]),
              "fov": cam.get("fov", DEFAULT_FOV), "lens_radius": cam.get("lens_radius", 0.0),
              "focus_distance": cam.get("focus_distance",
                                        math.dist(eye, target))}
    render = js.get("render", {})
    desc = {"source": os.path.abspath(scene_json), "width": width, "height": height,
            "max_depth": render.get("max_depth", DEFAULT_MAX_DEPTH), "camera": camera,
            "shapes": [], "lights": [], "notes": []}

    lo, hi = [math.inf] * 3, [-math.inf] * 3
    for mi_, mesh in enumerate(js["meshes"]):
        obj = os.path.join(base, mesh)
        positions, normals, mtllibs, groups = parse_obj(obj)
        mtls = {}
        for lib in mtllibs:
            p = os.path.join(os.path.dirname(obj), lib)
            if os.path.exists(p):
                mtls.update(parse_mtl(p))
        for gi, (name, faces) in enumerate(sorted(groups.items(), key=lambda kv: str(kv[0]))):
            mat = map_material(mtls.get(name))
            emissive = any(c > 0 for c in mat["ke"])
            with_normals = bool(normals) and not emissive and all(
                ni is not None for face in faces for _, ni in face)
            index, verts, norms, tris = {}, [], [], []
            for face in faces:
                for tri in triangulate(face):
                    if _tri_area2(*(positions[v] for v, _ in tri)) == 0.0:
                        continue  # clbdpt drops degenerate triangles
                    ids = []
                    for v, n in tri:
                        k = (v, n if with_normals else None)
                        if k not in index:
                            index[k] = len(verts)
                            verts.append(positions[v])
                            if with_normals:
                                norms.append(normals[n])
                        ids.append(index[k])
                    tris.append(ids)
            if not tris:
                continue
            for p in verts:
                for i in range(3):
                    lo[i], hi[i] = min(lo[i], p[i]), max(hi[i], p[i])
            safe = "".join(c if c.isalnum() else "_" for c in str(name or "default"))
            ply = os.path.join(out_dir, f"m{mi_}_{gi:02d}_{safe}.ply")
            write_ply(ply, verts, norms, tris)
            desc["shapes"].append({"name": f"m{mi_}_{gi:02d}_{safe}", "ply": ply, "normals": with_normals,
                                   "triangles": len(tris), "material": mat,
                                   "emission": mat["ke"] if emissive else None})
    desc["bounds"] = [lo, hi]

    # Participating media (README "Participating media"): named media, the scene-wide one,
    # and per material the media on either side (both default to the scene-wide one).
    media = js.get("media", {})
    desc["media"] = {name: {"sigma_a": m.get("sigma_a", [0, 0, 0]), "sigma_s": m.get("sigma_s", [0, 0, 0]),
                            "g": m.get("g", 0.0)} for name, m in media.items()}
    for name, m in media.items():
        if "density" in m:
            desc["media"][name]["grid"] = density_grid(m["density"], os.path.dirname(os.path.abspath(scene_json)),
                                                       os.path.join(out_dir, f"grid_{name}.f32"))
    desc["medium"] = js.get("medium")
    overrides = js.get("materials", {})
    for shape in desc["shapes"]:
        o = overrides.get(shape["material"].get("name"), {})
        shape["interior"] = o.get("interior", desc["medium"])
        shape["exterior"] = o.get("exterior", desc["medium"])
        shape["interface"] = bool(o.get("interface", False))
        for side in ("interior", "exterior"):
            if shape[side] == "vacuum":
                shape[side] = None

    for light in js.get("lights", []):
        t = light["type"]
        if t == "point":
            desc["lights"].append({"type": "point", "position": light["position"], "intensity": light["intensity"]})
        elif t == "spot":
            spot = {"type": "spot", "position": light["position"], "target": light["target"],
                    "intensity": light["intensity"], "cone_angle": light.get("cone_angle", 30.0),
                    "cone_delta": light.get("cone_delta", 5.0)}
            spot["profile"] = spot_profile(spot["cone_angle"], spot["cone_delta"],
                                           os.path.join(out_dir, f"spot{len(desc['lights'])}.exr"))
            desc["lights"].append(spot)
        elif t == "directional":
            desc["lights"].append({"type": "directional", "direction": light["direction"],
                                   "radiance": light["radiance"]})
        elif t == "environment":
            env = {"type": "environment", "radiance": light.get("radiance", [1, 1, 1]), "map": None}
            if "map" in light:
                env["map"] = os.path.join(base, light["map"])
                env["map_scaled"] = env_map_copy(env["map"], env["radiance"],
                                                 os.path.join(out_dir, "env_scaled.exr"))
            desc["lights"].append(env)
    if not any(s["emission"] for s in desc["shapes"]) and not desc["lights"]:
        raise NotConvertible("no light (clbdpt adds its default white environment)")
    with open(os.path.join(out_dir, "scene.json"), "w") as f:
        json.dump(desc, f, indent=1)
    return desc


# A .vdb file's grid as clbdpt reads it (host/scene/openvdb_grid.cpp): the active voxels'
# bounding box plus one voxel of background around it, negative voxels as 0, placed by the
# inverse of the file's linear transform. Run by Debian's /usr/bin/python3 (python3-openvdb).
def _vdb_dense(path, name, out):
    """(size, world_to_grid) of the grid `name` of a .vdb file, its voxels written to `out`."""
    import subprocess
    script = r"""
import json, sys
import numpy as np
import pyopenvdb as vdb
path, name, out = sys.argv[1:4]
grid = vdb.read(path, name)
lo, hi = grid.evalActiveVoxelBoundingBox()
lo = [c - 1 for c in lo]
hi = [c + 1 for c in hi]
size = [hi[a] - lo[a] + 1 for a in range(3)]
dense = np.zeros(size, dtype=np.float32)
grid.copyToArray(dense, ijk=tuple(lo))
np.clip(dense, 0, None).transpose(2, 1, 0).astype("<f4").tofile(out)
# index -> world is affine: recover it from four points, then invert.
o = np.array(grid.transform.indexToWorld((0, 0, 0)))
axes = np.array([np.array(grid.transform.indexToWorld(tuple(np.eye(3)[a]))) - o for a in range(3)]).T
inv = np.linalg.inv(axes)
rows = [list(inv[a]) + [float(-inv[a] @ o - lo[a])] for a in range(3)]
print(json.dumps({"size": size, "world_to_grid": rows}))
"""
    res = subprocess.run(["/usr/bin/python3", "-c", script, path, name, out], capture_output=True, text=True)
    if res.returncode != 0:
        last = (res.stderr.strip().splitlines() or ["exit status %d" % res.returncode])[-1]
        hint = " (apt-get install python3-openvdb)" if "pyopenvdb" in res.stderr else ""
        raise NotConvertible(f"cannot read the grid '{name}' of {path}: {last}{hint}")
    meta = json.loads(res.stdout)
    return meta["size"], meta["world_to_grid"]


def _place_in_box(size, lo, hi, padding):
    """clbdpt's place_grid_in_box (host/scene/density_grid.cpp)."""
    rows = []
    for a in range(3):
        scale = (size[a] - 2 * padding) / (hi[a] - lo[a])
        rows.append([scale if j == a else 0.0 for j in range(3)] + [-lo[a] * scale - 0.5 + padding])
    return rows


def density_grid(d, scene_dir, out):
    """A medium's "density" (README "Participating media") as clbdpt reads it: voxels (x fastest,
    float32, written to `out`, scale applied), their count per axis, and the affine map from
    scene space to voxel coordinates (voxel centres at integers)."""
    if "file" in d:
        size, rows = _vdb_dense(os.path.join(scene_dir, d["file"]), d.get("grid", "density"), out)
        if "bounds" in d:
            rows = _place_in_box(size, d["bounds"][0], d["bounds"][1], 1)
        values = list(struct.unpack(f"<{size[0] * size[1] * size[2]}f", open(out, "rb").read()))
    else:
        size, values = d["resolution"], [float(v) for v in d["values"]]
        rows = _place_in_box(size, d["bounds"][0], d["bounds"][1], 0)
    values = [v * d.get("scale", 1.0) for v in values]
    with open(out, "wb") as f:
        f.write(struct.pack(f"<{len(values)}f", *values))
    return {"size": size, "voxels": out, "world_to_grid": rows, "max": max(values)}


def _write_exr(path, px):
    import numpy as np
    import OpenImageIO as oiio
    h, w, c = px.shape
    out = oiio.ImageOutput.create(path)
    if out is None or not out.open(path, oiio.ImageSpec(w, h, c, oiio.FLOAT)):
        raise RuntimeError(f"cannot write {path}: {oiio.geterror()}")
    out.write_image(np.ascontiguousarray(px, dtype=np.float32))
    out.close()
    return path


def env_map_copy(src, radiance, dst):
    """The map times `radiance`, nearest-neighbour upsampled ENV_UPSAMPLE x (for Mitsuba, whose
    envmap has an RGB-less scale and only bilinear lookups)."""
    import numpy as np
    import OpenImageIO as oiio
    px = np.asarray(oiio.ImageBuf(src).get_pixels(oiio.FLOAT), dtype=np.float32)
    if px.ndim == 2:
        px = px[:, :, None]
    px = px[:, :, :3] if px.shape[2] >= 3 else np.repeat(px[:, :, :1], 3, axis=2)
    px = np.maximum(np.nan_to_num(px), 0.0) * np.asarray(radiance, np.float32)  # clbdpt clamps < 0
    return _write_exr(dst, np.repeat(np.repeat(px, ENV_UPSAMPLE, axis=0), ENV_UPSAMPLE, axis=1))


def spot_profile(cone_angle, cone_delta, dst, size=512):
    """clbdpt's (pbrt-v3's) spot falloff as a texture over Mitsuba's spot uv square: uv = 0.5 +
    0.5 * (x/z) / tan(cutoff), so a texel's tan(theta) is 2 tan(cutoff) |uv - 0.5|."""
    import numpy as np
    t = (np.arange(size) + 0.5) / size - 0.5
    r = 2.0 * math.tan(math.radians(cone_angle)) * np.hypot(t[None, :], t[:, None])
    cos_t = 1.0 / np.sqrt(1.0 + r * r)
    cos_total, cos_start = math.cos(math.radians(cone_angle)), math.cos(math.radians(cone_angle - cone_delta))
    if cos_start > cos_total:
        delta = np.clip((cos_t - cos_total) / (cos_start - cos_total), 0.0, 1.0)
        f = delta ** 4
    else:
        f = (cos_t >= cos_total).astype(np.float64)
    return _write_exr(dst, np.repeat(f[:, :, None], 3, axis=2))


# ---- pbrt-v3 ---------------------------------------------------------------------------------


def _rgb(v):
    return "[ " + " ".join(f"{x:.9g}" for x in v) + " ]"


def pbrt_scene(desc, spp, seed, out_exr):
    """pbrt-v3 scene text: bdpt, Sobol sampler, box filter of one pixel, no RR (pbrt-v3's bdpt has
    none). The glossy lobe becomes a "mix" of matte and "metal" with eta 0, k 1 (Fresnel = 1);
    this matches clbdpt only for grey Ks (else the scene is not converted for pbrt)."""
    c = desc["camera"]
    lines = [f"# converted from {desc['source']} by scripts/peers",
             "Scale -1 1 1  # pbrt's camera space is left-handed; clbdpt's screen right is forward x up",
             "LookAt " + " ".join(f"{x:.9g}" for x in c["eye"] + c["target"] + c["up"]),
             f'Camera "perspective" "float fov" [ {c["fov"]:.9g} ]'
             + (f' "float lensradius" [ {c["lens_radius"]:.9g} ] "float focaldistance" [ {c["focus_distance"]:.9g} ]'
                if c["lens_radius"] > 0 else ""),
             f'Film "image" "integer xresolution" [ {desc["width"]} ] "integer yresolution" [ {desc["height"]} ]'
             f' "string filename" "{out_exr}"',
             'PixelFilter "box" "float xwidth" [ 0.5 ] "float ywidth" [ 0.5 ]',
             f'Sampler "sobol" "integer pixelsamples" [ {spp} ]',
             f'Integrator "bdpt" "integer maxdepth" [ {desc["max_depth"]} ]',
             "WorldBegin"]
    for light in desc["lights"]:
        t = light["type"]
        if t == "point":
            lines.append(f'LightSource "point" "rgb I" {_rgb(light["intensity"])} "point from" {_rgb(light["position"])}')
        elif t == "spot":
            lines.append(f'LightSource "spot" "rgb I" {_rgb(light["intensity"])} "point from" {_rgb(light["position"])}'
                         f' "point to" {_rgb(light["target"])} "float coneangle" [ {light["cone_angle"]:.9g} ]'
                         f' "float conedeltaangle" [ {light["cone_delta"]:.9g} ]')
        elif t == "directional":
            lines.append(f'LightSource "distant" "rgb L" {_rgb(light["radiance"])} "point from" [ 0 0 0 ]'
                         f' "point to" {_rgb(light["direction"])}')
        elif t == "environment":
            # pbrt: u = phi(x -> y) / 2pi, v = theta from +z / pi; clbdpt: u = phi(x -> z), v from +y.
            # The light-to-world matrix swapping y and z maps one onto the other.
            lines += ["AttributeBegin", "Transform [ 1 0 0 0  0 0 1 0  0 1 0 0  0 0 0 1 ]"]
            if light["map"]:
                # the upsampled copy: pbrt-v3 looks maps up bilinearly (clbdpt: nearest texel)
                lines.append(f'LightSource "infinite" "rgb L" [ 1 1 1 ] "string mapname" "{light["map_scaled"]}"')
            else:
                lines.append(f'LightSource "infinite" "rgb L" {_rgb(light["radiance"])}')
            lines.append("AttributeEnd")
    for s in desc["shapes"]:
        m = s["material"]
        lines.append("AttributeBegin")
        if m["kind"] == "diffuse":
            lines.append(f'Material "matte" "rgb Kd" {_rgb(m["kd"])} "float sigma" [ 0 ]')
        elif m["kind"] == "mirror":
            lines.append(f'Material "mirror" "rgb Kr" {_rgb(m["ks"])}')
        elif m["kind"] == "glass":
            lines.append(f'Material "glass" "rgb Kr" [ 1 1 1 ] "rgb Kt" [ 1 1 1 ] "float eta" [ {m["ior"]:.9g} ]')
        else:
            ks = m["ks"]
            if max(ks) - min(ks) > 1e-6 or ks[0] >= 1.0:
                raise NotConvertible(f"material '{m['name']}': coloured Ks has no pbrt-v3 equivalent")
            w = ks[0]
            kd = [x / (1.0 - w) for x in m["kd"]]
            lines += [f'MakeNamedMaterial "{s["name"]}_d" "string type" "matte" "rgb Kd" {_rgb(kd)} "float sigma" [ 0 ]',
                      f'MakeNamedMaterial "{s["name"]}_s" "string type" "metal" "rgb eta" [ 0 0 0 ] "rgb k" [ 1 1 1 ]'
                      f' "float roughness" [ {m["alpha"]:.9g} ] "bool remaproughness" "false"',
                      # pbrt-v3 MixMaterial: amount scales the first material, 1 - amount the second
                      f'Material "mix" "string namedmaterial1" "{s["name"]}_s" "string namedmaterial2" "{s["name"]}_d"'
                      f' "rgb amount" {_rgb([w, w, w])}']
        if s["emission"]:
            lines.append(f'AreaLightSource "diffuse" "rgb L" {_rgb(s["emission"])}')
        lines.append(f'Shape "plymesh" "string filename" "{s["ply"]}"')
        lines.append("AttributeEnd")
    lines.append("WorldEnd")
    return "\n".join(lines) + "\n"
