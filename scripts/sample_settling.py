"""How a sheet resting on a collider through the shell's contact samples settles
(docs/dynamics.md §3.2): the rod and edge scenes of scripts/collider_shell.py run for --seconds;
printed per scene: the substeps of the last step, the steps redone (stretch_redos) over the last
second, the awake control vertices, the median and largest control-vertex speed over the last
frame (mm/s; sleep_speed is 0.1 mm/s) and the wall time per simulated second (one run on a
shared machine: a ratio against the same scene, not an absolute).

    python scripts/sample_settling.py [--seconds 6]
"""
import argparse
import time

import numpy as np

import collider_shell
from thinburn.colliders import Colliders

DT = 1 / 24


def settle(name, seconds):
    make, shapes, _ = collider_shell.SCENES[name]
    sim = make()
    sim.set_colliders(Colliders(**shapes), samples=4)
    frames = int(round(seconds / DT))
    redos, prev = 0, sim.lattice_positions().reshape(-1, 3)
    start = time.perf_counter()
    for k in range(frames):
        prev = sim.lattice_positions().reshape(-1, 3)
        sim.step(DT)
        if k >= frames - 24:
            redos += sim.step_stats()["stretch_redos"]
    wall = time.perf_counter() - start
    speed = np.linalg.norm(sim.lattice_positions().reshape(-1, 3) - prev, axis=1) / DT * 1e3
    st = sim.step_stats()
    return st["substeps"], redos, st["awake"], float(np.median(speed)), float(speed.max()), wall / seconds


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=6.0)
    a = ap.parse_args()
    print("| scene | substeps | redos (last s) | awake | speed median / max (mm/s) | wall s per s |")
    print("|---|---|---|---|---|---|")
    for name in ("rod", "edge"):
        sub, redos, awake, med, top, wall = settle(name, a.seconds)
        print(f"| {name} | {sub} | {redos} | {awake} | {med:.2f} / {top:.2f} | {wall:.2f} |", flush=True)


if __name__ == "__main__":
    main()
