"""Unburnt-edge strain of an A4 letter folded across its width, on a table, lit at a corner of
its flat half (docs/lattice.md, "Creases").

The half beyond x = 10.5 cm turns up by `turn` degrees at the fold (150: folded back over the
flat half at 30 degrees, shell_strain.py's letter). `line`: the fold runs along a column of
vertices (65 columns); `strip`: between two columns (64), so the fold is a row of faces 0.86 mm
wide turned by half the angle at each side. Per scene at 10, 20, 30 and 40 s (cells=96, 1/24 s):
the 99th percentile of |l/L - 1| over edges whose vertices are both unburnt, over all of them and
over those within 1 cm of the fold.
Run: python scripts/folded_letter.py [--turns 30 90 150] [--folds line strip] [--seconds 40]
    [--crease-angle 25]

--crossings: instead, the demo's letter (thinburn.scenes.folded_sheet, folded across its middle
on a row of vertices) folded nearly shut (--turns, default 160 170 175), on its table, lit at a
corner of the lying half, cells=64: in how many frames a mesh edge passes through a triangle of
the sheet (ipctk.has_intersections), the first few, and in how many it does so among the faces a
render keeps (the add-on removes a face once all its vertices burnt out).
"""
import argparse

import numpy as np

import thinburn
from thinburn._mesh_measures import EdgeStrain
from thinburn.scenes import rect_sheet


def letter(turn, columns):
    v, f = rect_sheet(0.21, 0.297, nx=columns, ny=90)
    up = v[:, 0] > 0.105 + 1e-9
    d = v[up, 0] - 0.105
    t = np.radians(turn)
    v[up, 0], v[up, 2] = 0.105 + d * np.cos(t), d * np.sin(t)
    return v, f


def crossings(turns, seconds):
    import ipctk
    from thinburn._mesh_measures import mesh_edges
    from thinburn.scenes import A4, folded_sheet

    def collision_mesh(V, F):
        E = mesh_edges(F).astype(np.int32)
        return ipctk.CollisionMesh(np.asfortranarray(V), np.asfortranarray(E), np.asfortranarray(F.astype(np.int32)))

    for turn in turns:
        V, F = folded_sheet(A4[0], A4[1], angle=turn, nx=43, ny=61)
        mesh = collision_mesh(V, F)
        sim = thinburn.Simulation(V, F, cells=64, floor=0.0)
        sim.ignite((0.004, 0.004, 0.0))
        crossed, kept_crossed = [], 0
        for k in range(24 * seconds):
            sim.step(1 / 24)
            X = np.asfortranarray(sim.vertex_positions())
            if ipctk.has_intersections(mesh, X):
                crossed.append(k + 1)
                kept = (sim.vertex_burnout_times() > sim.time)[F].any(axis=1)
                kept_crossed += ipctk.has_intersections(collision_mesh(V, F[kept]), X)
        print(f"turn {turn:5.1f}: {len(crossed)} of {24 * seconds} frames cross, first {crossed[:3]}; "
              f"{kept_crossed} among the faces a render keeps", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--turns", type=float, nargs="+", default=None)
    ap.add_argument("--folds", nargs="+", default=["line", "strip"], choices=["line", "strip"])
    ap.add_argument("--seconds", type=int, default=40)
    ap.add_argument("--cells", type=int, default=96)
    ap.add_argument("--crossings", action="store_true")
    ap.add_argument("--crease-angle", type=float, default=25.0, help="Simulation's crease_angle, degrees")
    a = ap.parse_args()
    if a.crossings:
        return crossings(a.turns or [160.0, 170.0, 175.0], a.seconds)
    for turn in a.turns or [30.0, 90.0, 150.0]:
        for fold in a.folds:
            V, F = letter(turn, 65 if fold == "line" else 64)
            measure = EdgeStrain(V, F)
            E = measure.edges
            mid = 0.5 * (V[E[:, 0]] + V[E[:, 1]])
            near = np.hypot(mid[:, 0] - 0.105, mid[:, 2]) < 0.01
            sim = thinburn.Simulation(V, F, cells=a.cells, floor=0.0, crease_angle=a.crease_angle)
            sim.ignite((0.0, 0.0, 0.0))
            out = []
            for k in range(24 * a.seconds):
                sim.step(1 / 24)
                if k % 240 == 239:
                    out.append(f"{100 * np.percentile(measure.unburnt(sim), 99):5.2f} "
                               f"({100 * np.percentile(measure.unburnt(sim, near), 99):5.2f})")
            print(f"turn {turn:5.1f}  {fold:5s}  {sim.lattice_couples:3d} couples  unburnt p99 % (within 1 cm of "
                  "the fold): " + "  ".join(out), flush=True)


if __name__ == "__main__":
    main()
