"""A paper sphere rolling on its table in wind (docs/lattice.md, "Floor"): the demo's sphere
(r = 10 cm) at 32 cells, floor at z = 0, a 3 m/s wind along x, 4 s (--seconds). Prints per step
size and integrator how far its centre travelled, its speed over the second half, how high its lowest
mesh point rode above the table after the first 0.5 s (median, mean, largest), with the wall
seconds a simulated second.

    python scripts/rolling_sphere.py [--dts 24 96 240] [--integrators implicit symplectic] [--seconds 4]
                                     [--friction 0.5] [--substeps N] [--slip-ratio 3]

--substeps fixes the substeps of each step (no stretch redo): `--dts 24 --substeps 160` is the
implicit run's own small-step limit (docs/dynamics.md §3). --slip-ratio sets the dynamics'
slip_ratio (a held floor contact slides beyond it times friction).
"""
import argparse
import time

import numpy as np

import thinburn
from thinburn.demo import shell_scene


def roll(steps_per_second, integrator, seconds=4.0, wind=3.0, friction=None, substeps=0, slip_ratio=None):
    sc = shell_scene("sphere")
    sim = thinburn.Simulation(sc.vertices, sc.faces, material="paper", cells=32, floor=0.0,
                              integrator=integrator)
    if friction is not None:
        sim.set_dynamics(friction=friction)
    if substeps:
        sim.set_dynamics(substeps=substeps)
    if slip_ratio is not None:
        sim.set_dynamics(slip_ratio=slip_ratio)
    sim.wind = (wind, 0.0, 0.0)
    dt = 1.0 / steps_per_second
    n = int(round(seconds / dt))
    x, low = [], []
    t0 = time.perf_counter()
    for k in range(n):
        sim.step(dt)
        p = sim.vertex_positions()
        x.append(p[:, 0].mean())
        low.append(p[:, 2].min())
    wall = (time.perf_counter() - t0) / seconds
    x, low = np.array(x), np.array(low)[int(round(0.5 / dt)):]
    half = n // 2
    speed = (x[-1] - x[half - 1]) / (dt * (n - half))
    return x[-1], speed, low, wall


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dts", type=int, nargs="+", default=[24, 96, 240], help="steps per second")
    ap.add_argument("--integrators", nargs="+", default=["implicit", "symplectic"])
    ap.add_argument("--seconds", type=float, default=4.0)
    ap.add_argument("--friction", type=float, default=None, help="the floor's (default: the material's 0.5)")
    ap.add_argument("--substeps", type=int, default=0, help="fixed substeps per step (default 0: chosen per step)")
    ap.add_argument("--slip-ratio", type=float, default=None, help="the dynamics' slip_ratio (default 3)")
    a = ap.parse_args()
    for integrator in a.integrators:
        for sps in a.dts:
            travel, speed, low, wall = roll(sps, integrator, a.seconds, friction=a.friction,
                                           substeps=a.substeps, slip_ratio=a.slip_ratio)
            fixed = f" x {a.substeps}" if a.substeps else ""
            print(f"{integrator:10s} dt = 1/{sps:<4d}{fixed} travelled {travel:5.3f} m, {speed:4.2f} m/s over the last half; "
                  f"lowest point above the table: median {1000 * np.median(low):5.2f} mm, mean "
                  f"{1000 * low.mean():5.2f}, max {1000 * low.max():5.1f}; {wall:6.2f} s per simulated s", flush=True)


if __name__ == "__main__":
    main()
