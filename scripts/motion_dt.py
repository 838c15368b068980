"""How the demo scenes' motion depends on dt (issue #12, item 3): `python scripts/motion_dt.py
[--presets paper,cloth] [--wind 0,3] [--time 20]` prints, per preset, wind and integrator, the
RMS distance of the mesh's vertices from the dt = 1/480 s BDF2 run after --time seconds, as a
share of that run's RMS displacement from rest ("rel"), with the wall time of each run. Cells 64,
one thread. The reference is the finest run, not an exact solution."""
from __future__ import annotations

import argparse
import time

import numpy as np

from thinburn import demo

DTS = (1 / 24, 1 / 48, 1 / 96)
REF_DT = 1 / 480
INTEGRATORS = ("implicit", "bdf2", "symplectic")


def run(scene, material, integrator, dt, duration, wind):
    sim = demo.build(scene, material=material, cells=64, threads=1)
    sim.set_dynamics(integrator=integrator)
    if wind:
        sim.wind = (wind, 0.0, 0.0)
    rest = sim.vertex_positions()
    t0 = time.perf_counter()
    sim.run(duration, dt=dt)
    return rest, sim.vertex_positions(), time.perf_counter() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--presets", default="paper,cloth,hard_paper,silk,curtain")
    ap.add_argument("--wind", default="0,3", help="m/s along +x; 0 keeps the scene's own wind")
    ap.add_argument("--time", type=float, default=20.0)
    a = ap.parse_args(argv)
    for material in a.presets.split(","):
        scene = demo.default_scene(material)
        for wind in (float(w) for w in a.wind.split(",")):
            rest, ref, _ = run(scene, material, "bdf2", REF_DT, a.time, wind)
            moved = np.sqrt(((ref - rest) ** 2).sum(1).mean())
            cells = []
            for integ in INTEGRATORS:
                for dt in DTS:
                    _, x, wall = run(scene, material, integ, dt, a.time, wind)
                    rel = np.sqrt(((x - ref) ** 2).sum(1).mean()) / moved
                    cells.append(f"{integ} 1/{round(1 / dt)} {rel:.3f} ({wall:.2f} s)")
            print(f"{material} wind {wind:g}: moved {1000 * moved:.1f} mm | " + " | ".join(cells), flush=True)


if __name__ == "__main__":
    main()
