"""What sleeping costs in accuracy and saves in work (docs/dynamics.md §5): each scene run with
sleeping on (the default) and off, the same deterministic burn; printed per scene: the mean
awake vertices over the last 2 s (on / off), the largest distance between the two runs' control
vertices at the end, the largest motion of the scene (how far the lattice moved from rest), and
the wall time of each run (a ratio in one run; the machine's load shows in both).

    python scripts/sleep_accuracy.py [--seconds 60] [--scenes corner strip]

corner: a 1 m paper sheet, 33 x 33 couples, 64 cells, on a table, lit at a corner (the film
bench's lattice, smaller mesh). strip: the 0.6 x 0.1 m cloth strip of tests/test_shell_contact.py
dropped over a box's edge (2 s whatever --seconds says); its line adds the mesh's deepest point
inside the box (m, < 0: inside), with and without sleeping."""
import argparse
import time

import numpy as np

import thinburn
from thinburn.colliders import Colliders
from thinburn.scenes import rect_sheet

DT = 1 / 24
QUIET = dict(speed_noise=0.0, duration_noise=0.0)
STRIP_BOX = Colliders(boxes=[dict(centre=(-0.145, 0.05, -0.51), half_extents=(0.5, 0.5, 0.5), friction=1.0)])


def corner(sleeping):
    sim = thinburn.Simulation(*rect_sheet(1.0, 1.0, nx=41, ny=41), material="paper", cells=64, lattice=33,
                              floor=0.0, sleeping=sleeping, **QUIET)
    sim.ignite((0.0, 0.0, 0.0), time=0.0, radius=0.03)
    return sim


def strip(sleeping):
    sim = thinburn.Simulation(*rect_sheet(0.6, 0.1, nx=97, ny=17), cells=32, lattice=16, material="cloth",
                              sleeping=sleeping, **QUIET)
    sim.set_colliders(STRIP_BOX, samples=4)
    return sim


def run(make, sleeping, seconds):
    sim = make(sleeping)
    rest = sim.lattice_positions().reshape(-1, 3)
    frames = int(round(seconds * 24))
    awake, deepest = [], np.inf
    start = time.perf_counter()
    for _ in range(frames):
        sim.step(DT)
        awake.append(sim.step_stats()["awake"])
        if make is strip:
            deepest = min(deepest, float(STRIP_BOX.query(sim.vertex_positions())[0].min()))
    wall = time.perf_counter() - start
    x = sim.lattice_positions().reshape(-1, 3)
    return dict(x=x, moved=float(np.linalg.norm(x - rest, axis=1).max()), awake=float(np.mean(awake[-48:])),
                wall=wall, deepest=deepest)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--scenes", nargs="+", default=["corner", "strip"], choices=["corner", "strip"])
    a = ap.parse_args()
    print("| scene | seconds | awake (on / off) | largest difference | largest motion | wall s (on / off) | deepest in box (on / off) |")
    print("|---|---|---|---|---|---|---|")
    for name in a.scenes:
        make, seconds = (corner, a.seconds) if name == "corner" else (strip, 2.0)
        on, off = run(make, True, seconds), run(make, False, seconds)
        diff = float(np.linalg.norm(on["x"] - off["x"], axis=1).max())
        deep = f"{on['deepest'] * 1e3:.2f} / {off['deepest'] * 1e3:.2f} mm" if name == "strip" else "-"
        print(f"| {name} | {seconds:g} | {on['awake']:.0f} / {off['awake']:.0f} | {diff * 1e6:.1f} um | "
              f"{off['moved'] * 1e3:.1f} mm | {on['wall']:.1f} / {off['wall']:.1f} | {deep} |")


if __name__ == "__main__":
    main()
