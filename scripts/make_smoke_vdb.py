#!/usr/bin/python3
"""Writes scenes/smoke/smoke.vdb: a rising, swirling plume of smoke for the bundled smoke scene.

A procedural density (a column that widens and sways as it rises, modulated by a few
sinusoids standing in for turbulence) sampled on voxels of 4 scene units, placed by the grid's
own transform inside the box x 90..280, y 166..500, z 70..240 of the Cornell box (above the
short block, clear of the tall one), which scenes/smoke/smoke-box.obj bounds. Needs Debian's
python3-openvdb:  sudo apt-get install python3-openvdb && /usr/bin/python3 scripts/make_smoke_vdb.py
"""
import math
import os

import numpy as np
import pyopenvdb as vdb

LO = np.array([90.0, 166.0, 70.0])
HI = np.array([280.0, 500.0, 240.0])
VOXEL = 4.0


def density(u, v, w):
    """Density at box coordinates u, v, w in [0, 1] (v up)."""
    cx = 0.5 + 0.14 * np.sin(6.0 * v)
    cz = 0.5 + 0.10 * np.cos(5.0 * v + 1.0)
    radius = 0.10 + 0.22 * v
    d2 = ((u - cx) ** 2 + (w - cz) ** 2) / radius**2
    column = np.exp(-d2)
    turbulence = 0.55 + 0.45 * np.sin(17.0 * u + 9.0 * v) * np.cos(13.0 * w - 7.0 * v) * np.sin(11.0 * v + 5.0 * u)
    rise = np.clip(v / 0.08, 0.0, 1.0) * np.clip((1.0 - v) / 0.25, 0.0, 1.0)
    edge = np.clip(np.minimum.reduce([u, 1 - u, w, 1 - w]) / 0.06, 0.0, 1.0)
    return np.clip(column * turbulence * rise * edge, 0.0, None)


def main():
    n = np.floor((HI - LO) / VOXEL).astype(int)
    # Voxel centres, as box coordinates.
    u, v, w = np.meshgrid(*[(np.arange(n[a]) + 0.5) * VOXEL / (HI[a] - LO[a]) for a in range(3)], indexing="ij")
    values = density(u, v, w).astype(np.float32)
    values[values < 0.01] = 0.0  # leave faint voxels inactive: a sparse grid, as simulations write
    grid = vdb.FloatGrid(0.0)
    grid.copyFromArray(values, tolerance=0.0)
    grid.name = "density"
    transform = vdb.createLinearTransform(voxelSize=VOXEL)
    transform.translate(tuple(LO + 0.5 * VOXEL))  # voxel (0, 0, 0) centred half a voxel in from LO
    grid.transform = transform
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "smoke", "smoke.vdb")
    vdb.write(out, grids=[grid])
    print(f"{out}: {n[0]}x{n[1]}x{n[2]} voxels, {grid.activeVoxelCount()} active, max density {values.max():.3f}")


if __name__ == "__main__":
    main()
