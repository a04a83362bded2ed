#!/usr/bin/env python3
"""Regenerates the bundled test/demo scenes (OBJ + MTL + JSON, and the sky's EXR map).

    /usr/bin/python3 scripts/make_scenes.py [--out-dir DIR]

Writes, under scenes/ (or DIR):

  cornell-specular/  the Cornell box of scenes/cornell-box (walls and light copied from its OBJ,
                     the two blocks dropped) with a glass and a mirror sphere on the floor, the
                     caustics box of Jensen and Veach.
  lamp-ceiling/      a closed room lit only by a lamp whose emitter faces up into an opaque shade
                     open at the top: all visible light has bounced off the ceiling first.
  veach-mis/         Veach's multiple importance sampling test (thesis fig. 9.2): four glossy
                     plates from rough to near-mirror under four spherical lights of equal power.
  point-spot/        a few diffuse objects lit only by a warm point light and a cool spot light.
  sky/               objects on a ground plane under a procedural lat-long sky with a bright sun.

The output is deterministic: no randomness, fixed number formatting. Conventions (see the
scene format): faces are counter-clockwise seen from the side they face (the side an emitter
lights), sphere vertices carry smooth normals (vn), and the camera's right is cross(forward, up).
Needs numpy, and the OpenImageIO Python bindings for the EXR map.
"""
import argparse
import json
import math
import os
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# ----------------------------------------------------------------------------------------------
# Small vector helpers (plain tuples, so the output does not depend on numpy's float printing).


def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def mul(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def normalize(a):
    n = math.sqrt(dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


def rot_y(p, degrees):
    """Rotates p by `degrees` about the +y axis (taking +z toward +x)."""
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    return (c * p[0] + s * p[2], p[1], -s * p[0] + c * p[2])


def fmt(x):
    """A fixed, short decimal form: 6 decimals, trailing zeros dropped, no '-0'."""
    s = f"{x:.6f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def rounded(v, digits=4):
    """A JSON-friendly copy of a number or a vector: ints stay ints, floats are rounded."""
    if isinstance(v, dict):
        return {k: rounded(x, digits) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [rounded(x, digits) for x in v]
    if isinstance(v, float):
        r = round(v, digits)
        return int(r) if r == int(r) and abs(r) < 1e9 else r
    return v


# ----------------------------------------------------------------------------------------------
# OBJ writer: objects of triangles, each triangle checked against the side it should face.


class ObjWriter:
    def __init__(self, header, mtllib):
        self.lines = [f"# {line}" if line else "#" for line in header] + [f"mtllib {mtllib}"]
        self.vertex_count = 0
        self.normal_count = 0
        self.triangles = 0

    def comment(self, text):
        self.lines.append(f"# {text}")

    def object(self, name, material):
        self.lines += ["", f"o {name}", f"usemtl {material}"]

    def vertex(self, p):
        self.lines.append(f"v {fmt(p[0])} {fmt(p[1])} {fmt(p[2])}")
        self.vertex_count += 1
        return self.vertex_count

    def normal(self, n):
        self.lines.append(f"vn {fmt(n[0])} {fmt(n[1])} {fmt(n[2])}")
        self.normal_count += 1
        return self.normal_count

    def face(self, indices, normals=None):
        if normals is None:
            self.lines.append("f " + " ".join(str(i) for i in indices))
        else:
            self.lines.append("f " + " ".join(f"{i}//{n}" for i, n in zip(indices, normals)))
        self.triangles += len(indices) - 2

    def polygon(self, points, facing):
        """A planar convex polygon, wound so that its normal points along `facing`."""
        n = cross(sub(points[1], points[0]), sub(points[2], points[0]))
        if dot(n, facing) < 0:
            points = list(reversed(points))
            n = mul(n, -1)
        assert dot(normalize(n), normalize(facing)) > 0.5, "polygon nearly edge-on to its facing"
        first = self.vertex_count + 1
        for p in points:
            self.vertex(p)
        # Written as triangles, so every face the renderer sees is the one checked here.
        for k in range(1, len(points) - 1):
            self.face([first, first + k, first + k + 1])

    def quad(self, p0, p1, p2, p3, facing):
        self.polygon([p0, p1, p2, p3], facing)

    def box(self, lo, hi, angle=0.0, pivot=None, inward=False, skip=()):
        """An axis-aligned box [lo, hi], rotated by `angle` degrees about the vertical line
        through `pivot` (default: its centre); faces point out (or in, for a room)."""
        if pivot is None:
            pivot = mul(add(lo, hi), 0.5)

        def place(p):
            q = rot_y(sub(p, pivot), angle)
            return add(q, pivot)

        x0, y0, z0 = lo
        x1, y1, z1 = hi
        faces = {
            "-x": ([(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)], (-1, 0, 0)),
            "+x": ([(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)], (1, 0, 0)),
            "-y": ([(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)], (0, -1, 0)),
            "+y": ([(x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0)], (0, 1, 0)),
            "-z": ([(x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (x1, y0, z0)], (0, 0, -1)),
            "+z": ([(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0, 0, 1)),
        }
        for key in ("-y", "+y", "-x", "+x", "-z", "+z"):
            if key in skip:
                continue
            points, n = faces[key]
            n = rot_y(n, angle)
            if inward:
                n = mul(n, -1)
            self.polygon([place(p) for p in points], n)

    def sphere(self, center, radius, stacks, slices, smooth=True):
        """A UV sphere: `stacks` bands from pole to pole, `slices` around; faces point out."""
        c = center
        positions = {}

        def point(d):
            p = add(c, mul(d, radius))
            v = self.vertex(p)
            positions[v] = p
            return (v, self.normal(d) if smooth else None)

        top = point((0.0, 1.0, 0.0))
        ring = []  # ring[i - 1][j]: (vertex index, normal index) for stacks i = 1 .. stacks-1
        for i in range(1, stacks):
            theta = math.pi * i / stacks
            row = []
            for j in range(slices):
                phi = 2 * math.pi * j / slices
                row.append(point((math.sin(theta) * math.cos(phi), math.cos(theta),
                                  math.sin(theta) * math.sin(phi))))
            ring.append(row)
        bottom = point((0.0, -1.0, 0.0))

        def tri(a, b, e):
            pa, pb, pe = positions[a[0]], positions[b[0]], positions[e[0]]
            n = cross(sub(pb, pa), sub(pe, pa))
            centroid = mul(add(add(pa, pb), pe), 1.0 / 3.0)
            assert dot(n, sub(centroid, c)) > 0, "sphere triangle wound inwards"
            self.face([a[0], b[0], e[0]], [a[1], b[1], e[1]] if smooth else None)

        # With phi running from +x toward +z, j -> j+1 turns clockwise seen from above (+y), so
        # counter-clockwise seen from outside is: pole, j+1, j for the top cap, and so on.
        for j in range(slices):
            tri(top, ring[0][(j + 1) % slices], ring[0][j])
        for i in range(stacks - 2):
            for j in range(slices):
                j1 = (j + 1) % slices
                a, b = ring[i][j], ring[i][j1]
                d, e = ring[i + 1][j], ring[i + 1][j1]
                tri(a, b, e)
                tri(a, e, d)
        for j in range(slices):
            tri(bottom, ring[-1][j], ring[-1][(j + 1) % slices])

    def disk(self, center, radius, segments, facing):
        """A horizontal disk (triangle fan around its centre) facing +y or -y."""
        points = []
        for j in range(segments):
            phi = 2 * math.pi * j / segments
            points.append((center[0] + radius * math.cos(phi), center[1], center[2] + radius * math.sin(phi)))
        # A fan from the centre keeps the triangles well shaped.
        c = self.vertex(center)
        idx = [self.vertex(p) for p in points]
        up = facing[1] > 0
        for j in range(segments):
            a, b = idx[j], idx[(j + 1) % segments]
            pa, pb = points[j], points[(j + 1) % segments]
            n = cross(sub(pa, center), sub(pb, center))
            if (n[1] > 0) != up:
                a, b = b, a
            self.face([c, a, b])

    def cylinder(self, center, radius, y0, y1, segments):
        """The open side of a vertical cylinder (no caps), facing outwards."""
        for j in range(segments):
            p0 = 2 * math.pi * j / segments
            p1 = 2 * math.pi * (j + 1) / segments
            a = (center[0] + radius * math.cos(p0), y0, center[2] + radius * math.sin(p0))
            b = (center[0] + radius * math.cos(p1), y0, center[2] + radius * math.sin(p1))
            mid = (math.cos((p0 + p1) / 2), 0, math.sin((p0 + p1) / 2))
            self.quad(a, b, (b[0], y1, b[2]), (a[0], y1, a[2]), mid)

    def text(self):
        return "\n".join(self.lines) + "\n"


# ----------------------------------------------------------------------------------------------
# MTL and JSON.


def mtl_text(header, materials):
    """materials: list of (name, [(key, value-or-tuple), ...])."""
    out = [f"# {line}" if line else "#" for line in header]
    for name, props in materials:
        out.append("")
        out.append(f"newmtl {name}")
        for key, value in props:
            if isinstance(value, (tuple, list)):
                out.append(f"{key} " + " ".join(fmt(v) for v in value))
            elif isinstance(value, int):
                out.append(f"{key} {value}")
            else:
                out.append(f"{key} {fmt(value)}")
    return "\n".join(out) + "\n"


def scene_json(camera, film, meshes, lights, render):
    """The scene file in the layout of scenes/cornell-box: one line per section or light."""
    def one(obj):
        return json.dumps(rounded(obj), separators=(", ", ": "))

    parts = [f'  "camera": {one(camera)}', f'  "film": {one(film)}', f'  "meshes": {one(meshes)}']
    if lights:
        parts.append('  "lights": [\n' + ",\n".join(f"    {one(light)}" for light in lights) + "\n  ]")
    parts.append(f'  "render": {one(render)}')
    return "{\n" + ",\n".join(parts) + "\n}\n"


def write(path, text, written):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w", newline="\n") as f:
        f.write(text)
    written.append(path)


def camera(eye, target, fov, up=(0, 1, 0)):
    return {"eye": list(eye), "target": list(target), "up": list(up), "fov": fov,
            "lens_radius": 0.0, "focus_distance": math.dist(eye, target)}


# ----------------------------------------------------------------------------------------------
# 1. cornell-specular


def cornell_specular(out_dir, written, counts):
    src_dir = os.path.join(ROOT, "scenes", "cornell-box")
    keep = ["floor", "ceiling", "back_wall", "green_wall", "red_wall", "light"]

    # Parse the original OBJ: global vertex list, and the faces of each named object.
    vertices, objects, current = [], {}, None
    with open(os.path.join(src_dir, "cornell.obj")) as f:
        for raw in f:
            tok = raw.split()
            if not tok or tok[0].startswith("#"):
                continue
            if tok[0] == "v":
                vertices.append(tuple(float(x) for x in tok[1:4]))
            elif tok[0] == "o":
                current = {"material": None, "faces": []}
                objects[tok[1]] = current
            elif tok[0] == "usemtl":
                current["material"] = tok[1]
            elif tok[0] == "f":
                current["faces"].append([int(x.split("/")[0]) for x in tok[1:]])
    missing = [name for name in keep if name not in objects]
    if missing:
        sys.exit(f"make_scenes: scenes/cornell-box/cornell.obj lacks object(s) {missing}")

    obj = ObjWriter(
        ["The Cornell box of scenes/cornell-box (walls and light copied from its cornell.obj, the",
         "two blocks dropped) with a mirror sphere (back left) and a glass sphere (front right), as",
         "in the caustics box of Jensen and Veach. Millimetres; generated by scripts/make_scenes.py."],
        "cornell-specular.mtl")
    for name in keep:
        o = objects[name]
        obj.object(name, o["material"])
        remap = {}
        for face in o["faces"]:
            for i in face:
                if i not in remap:
                    remap[i] = obj.vertex(vertices[i - 1])
        for face in o["faces"]:
            obj.face([remap[i] for i in face])  # the original winding, unchanged

    # Spheres of radius 90 resting on the floor (y = 0); the box spans x 0..556, z 0..559.
    # The camera looks along +z, so screen-left is +x (the red wall).
    r = 90.0
    obj.object("mirror_sphere", "mirror")
    obj.sphere((390.0, r, 370.0), r, 24, 48)
    obj.object("glass_sphere", "glass")
    obj.sphere((175.0, r + 0.01, 190.0), r, 32, 64)  # finer: refraction shows the facets
    write(os.path.join(out_dir, "cornell-specular", "cornell-specular.obj"), obj.text(), written)
    counts["cornell-specular"] = obj.triangles

    with open(os.path.join(src_dir, "cornell.mtl")) as f:
        original = f.read().rstrip("\n")
    extra = mtl_text([], [
        ("mirror", [("Kd", (0, 0, 0)), ("Ks", (0.9, 0.9, 0.9)), ("illum", 5)]),
        ("glass", [("Kd", (0, 0, 0)), ("Ks", (1, 1, 1)), ("Ni", 1.5), ("illum", 7)]),
    ])
    header = ("# Materials of scenes/cornell-box (copied by scripts/make_scenes.py), then a perfect mirror\n"
              "# (illum 5) and smooth glass (illum 7, index 1.5).\n")
    write(os.path.join(out_dir, "cornell-specular", "cornell-specular.mtl"), header + original + "\n" + extra, written)

    with open(os.path.join(src_dir, "cornell-box.json")) as f:
        base = json.load(f)
    write(os.path.join(out_dir, "cornell-specular", "cornell-specular.json"),
          scene_json(base["camera"], base["film"], ["cornell-specular.obj"], [],
                     {"spp": 64, "max_depth": 8, "seed": 0}), written)


# ----------------------------------------------------------------------------------------------
# 2. lamp-ceiling


def lamp_ceiling(out_dir, written, counts):
    W, H = 3.0, 3.0  # room: x, z in [-W, W], y in [0, H]
    obj = ObjWriter(
        ["A closed 6 x 3 x 6 m room lit only by a floor lamp whose emitter (a disk facing up) sits",
         "inside an opaque shade open at the top: no light reaches the floor or the camera",
         "directly, everything visible is lit via the ceiling. Generated by scripts/make_scenes.py."],
        "lamp-ceiling.mtl")
    obj.object("floor", "floor")
    obj.quad((-W, 0, -W), (W, 0, -W), (W, 0, W), (-W, 0, W), (0, 1, 0))
    obj.object("ceiling", "ceiling")
    obj.quad((-W, H, -W), (W, H, -W), (W, H, W), (-W, H, W), (0, -1, 0))
    obj.object("walls", "wall")
    obj.quad((-W, 0, W), (W, 0, W), (W, H, W), (-W, H, W), (0, 0, -1))      # z = +W
    obj.quad((-W, 0, -W), (W, 0, -W), (W, H, -W), (-W, H, -W), (0, 0, 1))   # z = -W
    obj.quad((W, 0, -W), (W, 0, W), (W, H, W), (W, H, -W), (-1, 0, 0))      # x = +W
    obj.quad((-W, 0, -W), (-W, 0, W), (-W, H, W), (-W, H, -W), (1, 0, 0))   # x = -W

    # Furniture. The camera stands in the (+x, -z) corner looking toward (-x, +z).
    obj.object("sofa", "red")
    obj.box((-0.4, 0.0, 2.15), (1.8, 0.45, 2.95))
    obj.box((-0.4, 0.45, 2.7), (1.8, 0.95, 2.95))
    obj.box((-0.6, 0.0, 2.15), (-0.4, 0.65, 2.95))
    obj.box((1.8, 0.0, 2.15), (2.0, 0.65, 2.95))
    obj.object("table", "blue")
    obj.box((0.0, 0.42, 0.6), (1.2, 0.5, 1.4), angle=15)
    obj.box((0.1, 0.0, 0.7), (1.1, 0.42, 1.3), angle=15)
    obj.object("cabinet", "green")
    obj.box((-2.95, 0.0, -1.6), (-2.45, 1.3, -0.2))
    obj.object("cube", "yellow")
    obj.box((-1.0, 0.0, -1.2), (-0.5, 0.5, -0.7), angle=30)

    # The lamp, at (lx, lz): base, pole, shade (open cylinder + bottom), emitter inside.
    lx, lz = -1.4, 1.4
    shade_r, shade_y0, shade_y1 = 0.26, 1.4, 1.8
    obj.object("lamp_stand", "metal")
    obj.box((lx - 0.18, 0.0, lz - 0.18), (lx + 0.18, 0.04, lz + 0.18))
    obj.box((lx - 0.02, 0.04, lz - 0.02), (lx + 0.02, shade_y0, lz + 0.02))
    obj.object("lamp_shade", "shade")
    obj.cylinder((lx, 0, lz), shade_r, shade_y0, shade_y1, 32)
    obj.disk((lx, shade_y0, lz), shade_r, 32, (0, -1, 0))
    obj.object("lamp_emitter", "emitter")
    obj.disk((lx, shade_y0 + 0.03, lz), 0.18, 24, (0, 1, 0))
    write(os.path.join(out_dir, "lamp-ceiling", "lamp-ceiling.obj"), obj.text(), written)
    counts["lamp-ceiling"] = obj.triangles

    write(os.path.join(out_dir, "lamp-ceiling", "lamp-ceiling.mtl"), mtl_text(
        ["Diffuse room and furniture; the only light is the lamp's emitter (one-sided, facing up).",
         "Generated by scripts/make_scenes.py."],
        [("floor", [("Kd", (0.55, 0.45, 0.35)), ("illum", 1)]),
         ("ceiling", [("Kd", (0.75, 0.75, 0.75)), ("illum", 1)]),
         ("wall", [("Kd", (0.7, 0.7, 0.68)), ("illum", 1)]),
         ("red", [("Kd", (0.6, 0.1, 0.08)), ("illum", 1)]),
         ("blue", [("Kd", (0.12, 0.2, 0.55)), ("illum", 1)]),
         ("green", [("Kd", (0.15, 0.45, 0.2)), ("illum", 1)]),
         ("yellow", [("Kd", (0.7, 0.6, 0.15)), ("illum", 1)]),
         ("metal", [("Kd", (0.2, 0.2, 0.2)), ("illum", 1)]),
         ("shade", [("Kd", (0.8, 0.7, 0.5)), ("illum", 1)]),
         ("emitter", [("Kd", (0, 0, 0)), ("Ke", LAMP_RADIANCE), ("illum", 1)])]), written)

    write(os.path.join(out_dir, "lamp-ceiling", "lamp-ceiling.json"),
          scene_json(camera((2.6, 1.55, -2.6), (-1.0, 1.0, 1.2), 65.0), {"width": 256, "height": 256},
                     ["lamp-ceiling.obj"], [], {"spp": 64, "max_depth": 6, "seed": 0}), written)


LAMP_RADIANCE = (300.0, 260.0, 200.0)


# ----------------------------------------------------------------------------------------------
# 3. veach-mis


# Plates of the classic scene (Mitsuba's veach_mi, after Steve Marschner's): 8 wide in x, each
# tilted toward the camera; from the top (farthest) plate, the smoothest, to the bottom one.
VEACH_PLATES = [
    ((-2.70651, 0.25609), (-2.08375, -0.526323)),
    ((-3.28825, 1.36972), (-2.83856, 0.476536)),
    ((-3.73096, 2.70046), (-3.43378, 1.74564)),
    ((-3.99615, 4.0667), (-3.82069, 3.08221)),
]
VEACH_ROUGHNESS = [0.04, 0.1, 0.2, 0.35]          # MTL Pr; GGX alpha = Pr^2
VEACH_LIGHTS = [(-3.75, 0.0333), (-1.25, 0.1), (1.25, 0.3), (3.75, 0.9)]  # (x, radius)
VEACH_POWER = 0.5  # radiance * radius^2, the same for every light (so equal power)


def veach_mis(out_dir, written, counts):
    obj = ObjWriter(
        ["Veach's multiple importance sampling test scene (thesis, fig. 9.2), after Mitsuba's",
         "veach_mi: four glossy plates, rough (front) to near-mirror (back), lit by four spherical",
         "lights of equal power (radiance * radius^2 constant). Generated by scripts/make_scenes.py."],
        "veach-mis.mtl")
    obj.object("floor", "dark")
    obj.quad((-10, -4.14615, -10), (10, -4.14615, -10), (10, -4.14615, 10), (-10, -4.14615, 10), (0, 1, 0))
    obj.object("back_wall", "dark")
    obj.quad((-10, -4.14615, -2), (10, -4.14615, -2), (10, 10, -2), (-10, 10, -2), (0, 0, 1))
    camera_eye = (0.0, 2.0, 15.0)
    for k, ((ya, za), (yb, zb)) in enumerate(VEACH_PLATES):
        obj.object(f"plate{k + 1}", f"plate{k + 1}")
        a, b = (-4.0, ya, za), (4.0, ya, za)
        c, d = (4.0, yb, zb), (-4.0, yb, zb)
        centre = mul(add(a, c), 0.5)
        obj.quad(a, b, c, d, sub(camera_eye, centre))  # front face toward the camera
    for k, (x, r) in enumerate(VEACH_LIGHTS):
        obj.object(f"light{k + 1}", f"light{k + 1}")
        stacks = 12 if r < 0.2 else 24
        obj.sphere((x, 0.0, 0.0), r, stacks, 2 * stacks)
    write(os.path.join(out_dir, "veach-mis", "veach-mis.obj"), obj.text(), written)
    counts["veach-mis"] = obj.triangles

    materials = [("dark", [("Kd", (0.1, 0.1, 0.1)), ("illum", 1)])]
    for k, pr in enumerate(VEACH_ROUGHNESS):
        alpha = pr * pr
        ns = 2.0 / (alpha * alpha) - 2.0
        materials.append((f"plate{k + 1}", [("Kd", (0.07, 0.07, 0.07)), ("Ks", (0.8, 0.8, 0.8)),
                                             ("Ns", round(ns, 1)), ("Pr", pr), ("illum", 2)]))
    for k, (x, r) in enumerate(VEACH_LIGHTS):
        le = VEACH_POWER / (r * r)
        materials.append((f"light{k + 1}", [("Kd", (0, 0, 0)), ("Ke", (le, le, le)), ("illum", 1)]))
    write(os.path.join(out_dir, "veach-mis", "veach-mis.mtl"), mtl_text(
        ["Plates: small Kd, GGX lobe Ks with roughness Pr (alpha = Pr^2; Ns gives the same alpha).",
         f"Lights: Ke = {VEACH_POWER} / radius^2, equal power. Generated by scripts/make_scenes.py."],
        materials), written)

    # Mitsuba's camera position, aimed a little higher and wider so all lights and plates fit.
    write(os.path.join(out_dir, "veach-mis", "veach-mis.json"),
          scene_json(camera(camera_eye, (0.0, -1.5, 2.5), 26.0), {"width": 384, "height": 256},
                     ["veach-mis.obj"], [], {"spp": 64, "max_depth": 5, "seed": 0}), written)


# ----------------------------------------------------------------------------------------------
# 4. point-spot


def point_spot(out_dir, written, counts):
    obj = ObjWriter(
        ["Diffuse floor, back wall, two boxes and a sphere, lit only by a warm point light and a",
         "cool spot light (delta lights; nothing emissive). Generated by scripts/make_scenes.py."],
        "point-spot.mtl")
    obj.object("floor", "floor")
    obj.quad((-5, 0, -4), (5, 0, -4), (5, 0, 3), (-5, 0, 3), (0, 1, 0))
    obj.object("back_wall", "wall")
    obj.quad((-5, 0, 3), (5, 0, 3), (5, 5, 3), (-5, 5, 3), (0, 0, -1))
    obj.object("box", "red")
    obj.box((0.6, 0.0, 0.4), (1.5, 0.9, 1.3), angle=25)
    obj.object("tall_box", "white")
    obj.box((-1.9, 0.0, 1.3), (-1.2, 1.6, 2.0), angle=-20)
    obj.object("sphere", "green")
    obj.sphere((-0.4, 0.55, -0.1), 0.55, 24, 48)
    write(os.path.join(out_dir, "point-spot", "point-spot.obj"), obj.text(), written)
    counts["point-spot"] = obj.triangles

    write(os.path.join(out_dir, "point-spot", "point-spot.mtl"), mtl_text(
        ["Diffuse materials only. Generated by scripts/make_scenes.py."],
        [("floor", [("Kd", (0.6, 0.6, 0.6)), ("illum", 1)]),
         ("wall", [("Kd", (0.7, 0.7, 0.7)), ("illum", 1)]),
         ("red", [("Kd", (0.65, 0.15, 0.1)), ("illum", 1)]),
         ("white", [("Kd", (0.75, 0.75, 0.75)), ("illum", 1)]),
         ("green", [("Kd", (0.2, 0.55, 0.25)), ("illum", 1)])]), written)

    lights = [
        {"type": "point", "position": [-1.2, 2.6, -1.0], "intensity": [14.0, 9.8, 5.6]},
        {"type": "spot", "position": [2.2, 3.4, -1.2], "target": [0.7, 0.0, 0.6],
         "intensity": [10.0, 16.0, 24.0], "cone_angle": 28.0, "cone_delta": 6.0},
    ]
    write(os.path.join(out_dir, "point-spot", "point-spot.json"),
          scene_json(camera((0.3, 2.0, -5.0), (0.0, 0.6, 1.0), 50.0), {"width": 256, "height": 256},
                     ["point-spot.obj"], lights, {"spp": 64, "max_depth": 5, "seed": 0}), written)


# ----------------------------------------------------------------------------------------------
# 5. sky


SUN_ELEVATION = 35.0    # degrees above the horizon
SUN_AZIMUTH = 200.0     # degrees, phi from +x toward +z (the map's u = phi / 2 pi)
SUN_RADIUS = 2.0        # angular radius, degrees
SUN_RADIANCE = (330.0, 310.0, 280.0)
SKY_ZENITH = np.array([0.10, 0.20, 0.48])
SKY_HORIZON = np.array([0.45, 0.55, 0.70])
GROUND = np.array([0.10, 0.09, 0.075])


def direction_of(u, v):
    """Lat-long: v = 0 is +y (up), u = phi / 2 pi with phi from +x toward +z."""
    theta = v * np.pi
    phi = u * 2 * np.pi
    return (np.sin(theta) * np.cos(phi), np.cos(theta), np.sin(theta) * np.sin(phi))


def sky_map(width=256, height=128, supersample=8):
    """The sky as float RGB rows (row 0 = straight up), averaged over supersample^2 points per
    pixel so that the small sun is antialiased and its total power does not depend on the grid."""
    el = math.radians(SUN_ELEVATION)
    az = math.radians(SUN_AZIMUTH)
    sun = np.array([math.cos(el) * math.cos(az), math.sin(el), math.cos(el) * math.sin(az)])
    cos_sun = math.cos(math.radians(SUN_RADIUS))
    n = supersample
    offsets = (np.arange(n) + 0.5) / n
    jj, ii = np.meshgrid(np.arange(height), np.arange(width), indexing="ij")
    image = np.zeros((height, width, 3))
    for oy in offsets:
        for ox in offsets:
            u = (ii + ox) / width
            v = (jj + oy) / height
            x, y, z = direction_of(u, v)
            # Sky: zenith colour to a paler horizon; ground: dark brown, softened across 1 degree.
            t = np.clip(1.0 - y, 0.0, 1.0) ** 3
            sky = SKY_ZENITH[None, None, :] * (1 - t[..., None]) + SKY_HORIZON[None, None, :] * t[..., None]
            g = np.clip(-y / math.sin(math.radians(1.0)), 0.0, 1.0)[..., None]
            color = sky * (1 - g) + GROUND[None, None, :] * g
            in_sun = (x * sun[0] + y * sun[1] + z * sun[2]) >= cos_sun
            color = np.where(in_sun[..., None], np.array(SUN_RADIANCE)[None, None, :], color)
            image += color
    return (image / (n * n)).astype(np.float32)


def write_exr(path, pixels, written):
    import OpenImageIO as oiio

    os.makedirs(os.path.dirname(path), exist_ok=True)
    height, width, channels = pixels.shape
    spec = oiio.ImageSpec(width, height, channels, "float")
    spec.attribute("compression", "zip")
    # OpenImageIO stamps the current time unless told otherwise; a fixed one keeps the file stable.
    spec.attribute("DateTime", "2000:01:01 00:00:00")
    out = oiio.ImageOutput.create(path)
    if out is None or not out.open(path, spec):
        sys.exit(f"make_scenes: cannot write {path}: {oiio.geterror()}")
    if not out.write_image(np.ascontiguousarray(pixels)):
        sys.exit(f"make_scenes: cannot write {path}: {out.geterror()}")
    out.close()
    written.append(path)


def sky(out_dir, written, counts):
    obj = ObjWriter(
        ["A diffuse sphere, a glossy sphere and a box on a large ground quad, lit only by the",
         "environment map sky.exr (procedural sky with a sun). Generated by scripts/make_scenes.py."],
        "sky.mtl")
    obj.object("ground", "ground")
    obj.quad((-40, 0, -40), (40, 0, -40), (40, 0, 40), (-40, 0, 40), (0, 1, 0))
    obj.object("diffuse_sphere", "orange")
    obj.sphere((1.3, 0.6, 0.4), 0.6, 24, 48)
    obj.object("glossy_sphere", "glossy")
    obj.sphere((-1.3, 0.6, 0.2), 0.6, 24, 48)
    obj.object("box", "green")
    obj.box((-0.45, 0.0, 1.2), (0.45, 0.9, 2.1), angle=30)
    write(os.path.join(out_dir, "sky", "sky.obj"), obj.text(), written)
    counts["sky"] = obj.triangles

    write(os.path.join(out_dir, "sky", "sky.mtl"), mtl_text(
        ["Generated by scripts/make_scenes.py."],
        [("ground", [("Kd", (0.4, 0.38, 0.33)), ("illum", 1)]),
         ("orange", [("Kd", (0.7, 0.3, 0.1)), ("illum", 1)]),
         ("glossy", [("Kd", (0.04, 0.06, 0.12)), ("Ks", (0.8, 0.8, 0.8)), ("Ns", 1248.0), ("Pr", 0.2),
                     ("illum", 2)]),
         ("green", [("Kd", (0.25, 0.5, 0.3)), ("illum", 1)])]), written)

    write_exr(os.path.join(out_dir, "sky", "sky.exr"), sky_map(), written)
    lights = [{"type": "environment", "radiance": [1.0, 1.0, 1.0], "map": "sky.exr"}]
    write(os.path.join(out_dir, "sky", "sky.json"),
          scene_json(camera((0.0, 1.3, -6.0), (0.0, 0.55, 0.8), 40.0), {"width": 256, "height": 256},
                     ["sky.obj"], lights, {"spp": 64, "max_depth": 5, "seed": 0}), written)


# ----------------------------------------------------------------------------------------------


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out-dir", default=os.path.join(ROOT, "scenes"),
                        help="where the scene folders go (default: the repository's scenes/)")
    args = parser.parse_args()
    written, counts = [], {}
    for make in (cornell_specular, lamp_ceiling, veach_mis, point_spot, sky):
        make(args.out_dir, written, counts)
    for path in written:
        print(os.path.relpath(path, os.getcwd()))
    for name, n in counts.items():
        print(f"{name}: {n} triangles")


if __name__ == "__main__":
    main()
