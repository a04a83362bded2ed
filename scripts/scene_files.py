"""Which files a clbdpt scene reads, and a hash of them all: the key under which the
benchmark scripts (convergence.py, peers) cache references."""
import hashlib
import json
import os


def sha256_file(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def scene_files(scene):
    """The scene file and the files it references (meshes, their MTL libraries, env maps)."""
    files = [scene]
    base = os.path.dirname(scene)
    meshes = []
    if scene.endswith(".json"):
        with open(scene) as f:
            desc = json.load(f)
        meshes = [os.path.join(base, m) for m in desc.get("meshes", [])]
        for light in desc.get("lights", []):
            if isinstance(light, dict) and "map" in light:
                files.append(os.path.join(base, light["map"]))
    else:
        meshes = [scene]
    for m in meshes:
        if m not in files:
            files.append(m)
        try:
            with open(m, errors="replace") as f:
                for line in f:
                    if line.startswith("mtllib"):
                        for name in line.split()[1:]:
                            files.append(os.path.join(os.path.dirname(m), name))
        except OSError:
            pass
    return files


def scene_hash(scene):
    h = hashlib.sha256()
    for p in scene_files(scene):
        h.update(os.path.relpath(p, os.path.dirname(scene)).encode() + b"\0")
        h.update((sha256_file(p) if os.path.exists(p) else "missing").encode() + b"\0")
    return h.hexdigest()
