"""Why a cloth resting on a ball costs 30+ substeps a frame (docs/dynamics.md §9, "A sheet at
rest on a collider never rests"): the Blender drape of scripts/render_drape.py in the core alone
(a 40 cm cloth, 61 x 61 vertices, 2 cm above a 10 cm ball with Outer 1 mm and friction 0.5, a
floor at the ball's foot, Motion Detail 16, Fire Detail 48, no fire). Prints, for the frames after
it has settled (37 to 48), the substeps each took, how many were redone and the awake control
vertices; then, run again with the substeps fixed at each of --substeps from frame 37, the largest
lattice strain (step_stats' max_strain) over frames 37 to 42.

    python scripts/collider_rest.py [--substeps 3 6 8 12 16 24] [--time 72]

--time N: only the wall time of frames 1 to N at the defaults (2 threads), how the WIP branch
of docs/dynamics.md §9 was compared with main.
"""
import argparse
import time

import numpy as np

import thinburn
from thinburn.scenes import rect_sheet

SETTLE = 36


def drape(frames=SETTLE):
    n = 61
    v, f = rect_sheet(0.4, 0.4, nx=n, ny=n, z=0.22)
    v[:, :2] -= v[:, :2].mean(0)
    sim = thinburn.Simulation(v, f, material="cloth", cells=48, floor=0.0, lattice=16, threads=2)
    sim.set_colliders(spheres=[dict(centre=(0, 0, 0.1), radius=0.1, friction=0.5, thickness=0.001)])
    for _ in range(frames):
        sim.step(1 / 24)
    return sim


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--substeps", type=int, nargs="+", default=[3, 6, 8, 12, 16, 24])
    ap.add_argument("--time", type=int, default=0, metavar="N", help="only time frames 1 to N")
    a = ap.parse_args()
    if a.time:
        t0 = time.perf_counter()
        drape(a.time)
        print(f"frames 1-{a.time}: {time.perf_counter() - t0:.1f} s")
        return
    sim = drape()
    subs, redone, awake, strain = [], 0, [], []
    for _ in range(12):
        sim.step(1 / 24)
        s = sim.step_stats()
        subs.append(s["substeps"])
        redone += s["stretch_redos"] > 0
        awake.append(s["awake"])
        strain.append(s["max_strain"])
    print(f"frames {SETTLE + 1}-{SETTLE + 12} at the defaults: substeps {min(subs)}-{max(subs)} "
          f"(mean {np.mean(subs):.1f}), {redone} of 12 redone, awake {min(awake)}-{max(awake)} of "
          f"{sim.lattice_couples * 2}, max_strain {min(strain):.4f}-{max(strain):.4f}")
    for k in a.substeps:
        sim = drape()
        sim.set_dynamics(substeps=k)
        worst = 0.0
        for _ in range(6):
            sim.step(1 / 24)
            worst = max(worst, sim.step_stats()["max_strain"])
        print(f"substeps fixed at {k:2d}: largest lattice strain {worst:.4f}", flush=True)


if __name__ == "__main__":
    main()
