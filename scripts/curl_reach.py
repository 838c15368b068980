"""How far from the fire a burning sheet curls (docs/dynamics.md §2, "Pyrolysis reaches as far
as"; the artists' trial: "the paper's unburnt far end curls up").

An A4 sheet of 61 x 61 vertices lying 0.5 mm above its table, lit at a corner (2 cm igniter),
cells=64, 1/24 s steps: at the end, the lit corner's height and the far corner's, in mm above
the table, and the share of the unburnt vertices more than 2 mm above it; for the paper's reading of eq 3 (every burning cell counts, pyrolysis_range=0) and
the default range. Scenes: the preset's own spread speed for 40 s, and 25 mm/s for 5 s (as an
artist sets it for a short shot).
Run: python scripts/curl_reach.py [--materials paper hard_paper cloth] [--ranges 0 0.03]
    [--lattice M] (the sheet's own lattice by default: 5 x 5 couples)
"""
import argparse

import numpy as np

import thinburn
from thinburn.scenes import rect_sheet


def burn(material="paper", speed=None, seconds=40.0, **params):
    """(lit corner, far corner) in m above the table, and the share of the unburnt vertices
    more than 2 mm above it."""
    V, F = rect_sheet(0.21, 0.297, nx=61, ny=61, z=0.0005)
    mat = thinburn.MATERIALS[material]
    if speed is not None:
        mat = mat.with_(V0=speed)
    sim = thinburn.Simulation(V, F, material=mat, cells=64, floor=0.0, **params)
    sim.ignite((0.0, 0.0, 0.0005), radius=0.02)
    for _ in range(int(round(24 * seconds))):
        sim.step(1 / 24)
    X = sim.vertex_positions()
    unburnt = sim.vertex_ignition_times() > sim.time
    return X[0, 2], X[-1, 2], float(np.mean(X[unburnt, 2] > 0.002))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--materials", nargs="+", default=["paper", "hard_paper", "cloth"])
    ap.add_argument("--ranges", type=float, nargs="+", default=[0.0, 0.03])
    ap.add_argument("--lattice", type=int, default=None)
    a = ap.parse_args()
    print("material   speed        range  lit corner  far corner (mm)  unburnt > 2 mm up")
    for material in a.materials:
        for speed, seconds in ((None, 40.0), (25.0, 5.0)):
            for r in a.ranges:
                lit, far, up = burn(material, speed, seconds, pyrolysis_range=r, lattice=a.lattice)
                label = "preset, 40 s" if speed is None else "25 mm/s, 5 s"
                print(f"{material:10s} {label:12s} {r:5.3f}  {1e3 * lit:10.1f}  {1e3 * far:10.1f}       {100 * up:8.1f} %",
                      flush=True)


if __name__ == "__main__":
    main()
