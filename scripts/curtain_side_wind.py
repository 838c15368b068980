"""The demo curtain (64 cells) in a wind along its plane (docs/dynamics.md §9): per integrator and
dt, the mean and standard deviation over frames of the mesh centroid's y and z over the second
half of the run. A wind along the plane flutters the curtain or stands it out as a sail, and
which one depends on dt.

    python scripts/curtain_side_wind.py [--wind 3 0 0] [--seconds 20] [--runs implicit:24 implicit:96 ...]
"""
import argparse
import time

import numpy as np

from thinburn.demo import build, default_scene

RUNS = ["implicit:24", "implicit:96", "implicit:480", "implicit:960", "symplectic:24", "symplectic:96"]


def run(integrator, dt, wind, seconds):
    sim = build(default_scene("curtain"), material="curtain", cells=64, threads=1)
    sim.set_dynamics(integrator=integrator)
    sim.wind = wind
    every = max(1, int(round((1 / 24) / dt)))  # sample at frame rate
    centroids = []
    t0 = time.perf_counter()
    for k in range(int(round(seconds / dt))):
        sim.step(dt)
        if k % every == 0 and sim.time >= seconds / 2:
            centroids.append(sim.vertex_positions().mean(0))
    return np.array(centroids), time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--wind", type=float, nargs=3, default=[3.0, 0.0, 0.0])
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--runs", nargs="+", default=RUNS, help="integrator:1/dt")
    a = ap.parse_args()
    for spec in a.runs:
        integrator, per_second = spec.split(":")
        c, wall = run(integrator, 1.0 / float(per_second), tuple(a.wind), a.seconds)
        print(f"{integrator:10s} dt 1/{per_second:4s}: centroid y {c[:, 1].mean():+.3f} +- {c[:, 1].std():.3f} m, "
              f"z {c[:, 2].mean():.3f} +- {c[:, 2].std():.3f} m ({wall:.1f} s)", flush=True)


if __name__ == "__main__":
    main()
