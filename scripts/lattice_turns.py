"""How far a flat sheet's lattice turns between neighbouring couple-to-couple segments (degrees;
docs/lattice.md, "Where the lattice folds"): the demo scenes at 64 cells, sampled every second,
and the 20 cm cloth dropped upright into a pile (cells 128, 4 s). FoldBlend blends the mesh
towards the couples from 20 degrees on.

    python scripts/lattice_turns.py [--seconds 30] [--scenes paper silk cloth curtain hard_paper pile]
"""
import argparse

import numpy as np

import thinburn
from thinburn._mesh_measures import lattice_turns
from thinburn.demo import build, default_scene
from thinburn.scenes import rect_sheet


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--scenes", nargs="+", default=["paper", "silk", "cloth", "curtain", "hard_paper", "pile"])
    a = ap.parse_args()
    for name in a.scenes:
        if name == "pile":
            v, f = rect_sheet(0.2, 0.2, nx=41, ny=41, vertical=True, z=0.05)
            sim, seconds = thinburn.Simulation(v, f, material="cloth", cells=128, floor=0.0), 4.0
        else:
            sim, seconds = build(default_scene(name), material=name, cells=64), a.seconds
        worst, share = 0.0, 0.0
        for k in range(int(round(24 * seconds))):
            sim.step(1 / 24)
            if k % 24 == 23:
                t = lattice_turns(sim)
                worst, share = max(worst, float(t.max())), max(share, float(np.mean(t > 20.0)))
        print(f"{name:6s} largest turn {worst:.1f} deg over {seconds:g} s; most couples past 20 deg at once: "
              f"{100 * share:.1f} %", flush=True)


if __name__ == "__main__":
    main()
