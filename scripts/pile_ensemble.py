"""Fabric piles over a spread of starts (docs/lattice.md, "folds"; README "Known limitations").

A square fabric of `size` stands upright on the floor (its bottom edge `z0` above it), is let go
and collapses into a pile: 4 s at 1/24 s, cells=128, the core's default lattice (or
`--lattice M`). A pile is chaotic, so one drop says little: six drops from bottom edges 0, 2,
... 10 mm apart (z0 = 5.0 .. 6.0 cm). Per size and fabric: the 99th percentile of |l/L - 1| over
all mesh edges at 4 s for each drop and their median, the same for the edges' lengths along the
surface (SurfaceStrain: where the lattice creases between couples, an edge across the crease is a
chord, shorter than the surface; docs/lattice.md, "Creases between couples"), the lowest lattice
couple centre (mm; below 0 the mesh is clamped to the floor there), the pile's height, and the
largest |l/L - 1| between neighbouring couples' centres, along the lattice's sides and diagonals
(the control cells' shapes).
Run: python scripts/pile_ensemble.py [--sizes 0.2 0.4] [--materials cloth silk] [--lattice M]
"""
import argparse
import time

import numpy as np

import thinburn
from thinburn._mesh_measures import EdgeStrain, SurfaceStrain
from thinburn.scenes import rect_sheet


def drop(size, material, z0, lattice=None):
    n = 41 if size <= 0.2 else 61
    v, f = rect_sheet(size, size, nx=n, ny=n, vertical=True, z=z0)
    sim = thinburn.Simulation(v, f, material=material, cells=128, floor=0.0, lattice=lattice)
    sim.run(4.0, dt=1 / 24)
    x = sim.vertex_positions()
    centre = sim.lattice_positions().reshape(-1, 2, 3).mean(axis=1)
    cells = cell_strain(sim.lattice_rest_positions().mean(axis=2), sim.lattice_positions().mean(axis=2))
    return (100 * np.percentile(EdgeStrain(v, f)(x), 99), 1000 * centre[:, 2].min(), x[:, 2].max(),
            sim.lattice_couples, 100 * np.percentile(SurfaceStrain(v, f)(sim), 99), 100 * cells)


def cell_strain(rest, now):
    """The largest |l/L - 1| between neighbouring couples' centres (M, M, 3) of a grid lattice,
    along its sides and both diagonals."""
    worst = 0.0
    for a, b in (((slice(1, None), slice(None)), (slice(None, -1), slice(None))),
                 ((slice(None), slice(1, None)), (slice(None), slice(None, -1))),
                 ((slice(1, None), slice(1, None)), (slice(None, -1), slice(None, -1))),
                 ((slice(1, None), slice(None, -1)), (slice(None, -1), slice(1, None)))):
        length = np.linalg.norm(now[a] - now[b], axis=-1) / np.linalg.norm(rest[a] - rest[b], axis=-1)
        worst = max(worst, float(np.abs(length - 1.0).max()))
    return worst


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=float, nargs="+", default=[0.2, 0.4])
    ap.add_argument("--materials", nargs="+", default=["cloth", "silk"])
    ap.add_argument("--lattice", type=int, default=None)
    a = ap.parse_args()
    for size in a.sizes:
        for material in a.materials:
            t0 = time.perf_counter()
            r = np.array([drop(size, material, 0.05 + 0.002 * k, a.lattice) for k in range(6)])
            print(f"{100 * size:.0f} cm {material:6s} {int(r[0, 3])} couples: p99 % "
                  + " ".join(f"{p:5.2f}" for p in r[:, 0]) + f" | median {np.median(r[:, 0]):5.2f} | "
                  "along the surface " + " ".join(f"{p:4.2f}" for p in r[:, 4])
                  + f" | median {np.median(r[:, 4]):4.2f} | "
                  f"lowest centre {np.median(r[:, 1]):6.2f} mm (median) | height {np.median(r[:, 2]):.3f} m | "
                  f"cells' sides and diagonals at most {r[:, 5].max():.2f} % | "
                  f"{time.perf_counter() - t0:.0f} s", flush=True)


if __name__ == "__main__":
    main()
