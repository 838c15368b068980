"""How far the fine mesh dips into a collider between couples (docs/dynamics.md §3.2).

A 0.3 m cloth square is dropped 2 cm onto a sphere of radius R and left 3 s; the control
vertices are held at the margin, the mesh between them follows the lattice's interpolation, so
it may cut the sphere's curve. Prints, per R, lattice M and margin, the smallest signed distance
of a mesh vertex to the sphere (negative: inside), of a control vertex, and the wall time.

    python scripts/collider_dip.py
"""
import time

import numpy as np

import thinburn
from thinburn.scenes import rect_sheet


def dip(R, M, margin):
    v, f = rect_sheet(0.3, 0.3, nx=61, ny=61)
    sim = thinburn.Simulation(v, f, cells=48, lattice=M, material="cloth", speed_noise=0.0, duration_noise=0.0)
    c = np.array([0.15, 0.15, -R - 0.02])
    sim.set_colliders(spheres=[dict(centre=c, radius=R, friction=0.5)], margin=margin)
    used = 0.5 * sim.lattice_thickness if margin is None else margin
    t0 = time.perf_counter()
    for _ in range(72):
        sim.step(1 / 24)
    wall = time.perf_counter() - t0
    mesh = np.linalg.norm(sim.vertex_positions() - c, axis=1) - R
    ctrl = np.linalg.norm(sim.lattice_positions().reshape(-1, 3) - c, axis=1) - R
    return used, sim.lattice_thickness, mesh.min(), ctrl.min(), wall


if __name__ == "__main__":
    print(f"{'R m':>6} {'M':>3} {'thick mm':>8} {'margin mm':>9} {'mesh min mm':>11} {'ctrl min mm':>11} {'3 s wall s':>10}")
    for R in (0.05, 0.1, 0.25):
        for M in (12, 24):
            for margin in (None, 0.0):
                used, t, m, c, wall = dip(R, M, margin)
                print(f"{R:6.2f} {M:3d} {1e3 * t:8.2f} {1e3 * used:9.2f} {1e3 * m:11.2f} {1e3 * c:11.2f} {wall:10.2f}")
