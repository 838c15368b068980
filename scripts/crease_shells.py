"""Unburnt-edge strain of shells whose edges are creases (docs/lattice.md, "Creases"): a 10 cm
paper box of 20 x 20 quads a face on its table lit at the middle of a bottom edge, and lanterns
(tubes r = 10 cm, 30 cm tall) of 8, 12 and 16 sides lit half-way up (cells=64, 30 s at 1/24 s).
Per shell: couples, the lattice's fit, and the most over the run (once a second) of the 99th
percentile of |l/L - 1| over edges whose vertices are both unburnt.
Run: python scripts/crease_shells.py [--shells box tube8 tube12 tube16] [--seconds 30]
"""
import argparse

import numpy as np

import thinburn
from thinburn import _surface_shapes as S
from thinburn._mesh_measures import EdgeStrain


def box(a=0.1, n=20):
    """A closed cube of side a on the table (z >= 0), n x n quads a face, vertices welded."""
    g = np.linspace(0.0, a, n + 1)
    U, W = np.meshgrid(g, g, indexing="ij")
    lo, hi = np.zeros_like(U), np.full_like(U, a)
    sides = [(U, W, lo), (U, W, hi), (U, lo, W), (U, hi, W), (lo, U, W), (hi, U, W)]
    verts, faces = [], []
    for P in sides:
        base = len(verts)
        verts.extend(np.stack(P, -1).reshape(-1, 3))
        for i in range(n):
            for j in range(n):
                v0 = base + i * (n + 1) + j
                faces += [[v0, v0 + 1, v0 + n + 2], [v0, v0 + n + 2, v0 + n + 1]]
    V, F = np.array(verts), np.array(faces)
    _, first, weld = np.unique(np.round(V / (a / n / 100)).astype(np.int64), axis=0, return_index=True,
                               return_inverse=True)
    return V[first], weld.reshape(-1)[F]


SHELLS = {"box": (box, (0.05, 0.0, 0.0)),
          **{f"tube{k}": ((lambda k=k: S.cylinder(0.1, 0.3, k, 36)), (0.1, 0.0, 0.15)) for k in (8, 12, 16)}}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shells", nargs="+", default=list(SHELLS), choices=list(SHELLS))
    ap.add_argument("--seconds", type=int, default=30)
    a = ap.parse_args()
    for name in a.shells:
        make, lit = SHELLS[name]
        V, F = make()
        measure = EdgeStrain(V, F)
        sim = thinburn.Simulation(V, F, cells=64, floor=0.0)
        sim.ignite(lit)
        worst = 0.0
        for k in range(24 * a.seconds):
            sim.step(1 / 24)
            if k % 24 == 23:
                worst = max(worst, np.percentile(measure.unburnt(sim), 99))
        print(f"{name:7s} {sim.lattice_couples:4d} couples  fit {sim.lattice_fit:.2g}  unburnt p99, most over "
              f"{a.seconds} s: {100 * worst:.2f} %  burnt {(sim.cell_states() == 2).mean():.2f}", flush=True)


if __name__ == "__main__":
    main()
