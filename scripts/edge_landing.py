"""A 20 cm sheet standing upright, dropped onto the floor (docs/lattice.md, "Floor"): per preset,
the worst strain of the mesh's two bottom rows over the run, the p99 of all its edges' |l/L - 1|
at the end, and its top's height (a soft fabric collapses into a pile).

    python scripts/edge_landing.py [--cells 32] [--drop 0.05] [--seconds 2] [--materials paper cloth silk]
"""
import argparse

import numpy as np

import thinburn
from thinburn._mesh_measures import EdgeStrain
from thinburn.scenes import rect_sheet


def run(material, cells, drop, seconds):
    v, f = rect_sheet(0.2, 0.2, nx=41, ny=41, vertical=True, z=drop)
    sim = thinburn.Simulation(v, f, material=material, cells=cells, floor=0.0)
    measure = EdgeStrain(v, f)
    e = measure.edges
    bottom = (v[e[:, 0], 2] < drop + 0.011) & (v[e[:, 1], 2] < drop + 0.011)  # two 5 mm rows
    worst = 0.0
    for _ in range(int(round(24 * seconds))):
        sim.step(1 / 24)
        strain = measure(sim.vertex_positions())
        worst = max(worst, float(strain[bottom].max()))
    x = sim.vertex_positions()
    return sim.lattice_couples, worst, float(np.percentile(strain, 99)), float(x[:, 2].max())


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=32)
    ap.add_argument("--drop", type=float, default=0.05)
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--materials", nargs="+", default=["paper", "cloth", "silk"])
    a = ap.parse_args()
    for m in a.materials:
        couples, worst, p99, top = run(m, a.cells, a.drop, a.seconds)
        print(f"{m:10s} {couples} couples: bottom rows worst {100 * worst:.3f} %, all edges p99 "
              f"{100 * p99:.2f} % at {a.seconds:g} s, top at {100 * top:.1f} cm", flush=True)


if __name__ == "__main__":
    main()
