"""A pleated curtain (docs/lattice.md, "Detail finer than the lattice"): 1 m x 1.4 m, pleats
y = a sin(2 pi x / wavelength), pinned along its top, lit at its hem, 20 s at 1/24 s. Prints per
case the lattice it got (couples, Simulation.lattice_fit), the worst over the seconds of the
99th percentile and of the largest |l/L - 1| over unburnt mesh edges, and wall seconds per
simulated second.

    python scripts/pleated_curtain.py [--cells 128] [--seconds 20] [--lattice M] [--cases 0 1 2 3]
                                      [--preconditioner auto|ldlt|jacobi] [--sleeping on|off]

--lattice M forces M (9 at 128 cells is the lattice the grid's rule alone chose: 64 couples).
--cases picks rows of CASES; --preconditioner is the implicit solve's (docs/dynamics.md §4).
Each row also says the passes, factorizations and CG iterations a step (step_stats) and how many
solves the LDL^T factor preconditioned; --sleeping off integrates every vertex every step.
"""
import argparse
import time

import numpy as np

import thinburn
from thinburn._mesh_measures import EdgeStrain
from thinburn.scenes import rect_sheet

CASES = [(0.02, 0.2, 0.0), (0.01, 0.2, 0.0), (0.01, 0.3, 0.0), (0.02, 0.2, 1.5)]  # a, wavelength, wind


def pleated(a, wavelength):
    v, f = rect_sheet(1.0, 1.4, nx=81, ny=113, vertical=True, z=0.05)
    v[:, 1] = a * np.sin(2 * np.pi * v[:, 0] / wavelength)
    return v, f


def run(a, wavelength, wind, cells, seconds, lattice=None, preconditioner="auto", sleeping=True):
    v, f = pleated(a, wavelength)
    top = np.flatnonzero(np.isclose(v[:, 2], v[:, 2].max()))
    sim = thinburn.Simulation(v, f, material="curtain", cells=cells, pinned=top, climb=0.4, lattice=lattice)
    sim.set_dynamics(preconditioner=preconditioner, sleeping=sleeping)
    sim.wind = (0.0, wind, 0.0)
    sim.ignite((0.5, 0.0, 0.06), radius=0.02)
    measure = EdgeStrain(v, f)
    e = measure.edges
    p99 = worst = 0.0
    solves = {"passes": 0, "factorizations": 0, "cg_iterations": 0, "ldlt_solves": 0}
    t0 = time.perf_counter()
    steps = int(round(24 * seconds))
    for k in range(steps):
        sim.step(1 / 24)
        st = sim.step_stats()
        for key in solves:
            solves[key] += st[key]
        if k % 24 == 23:
            x, char = sim.vertex_positions(), sim.vertex_char()
            keep = (char[e[:, 0]] < 0.05) & (char[e[:, 1]] < 0.05)
            s = measure(x)[keep]
            p99, worst = max(p99, float(np.percentile(s, 99))), max(worst, float(s.max()))
    wall = (time.perf_counter() - t0) / seconds
    per_step = {key: count / steps for key, count in solves.items()}
    return sim.lattice_couples, sim.lattice_fit, p99, worst, wall, per_step, solves["ldlt_solves"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=128)
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--lattice", type=int, default=None)
    ap.add_argument("--cases", type=int, nargs="+", default=list(range(len(CASES))))
    ap.add_argument("--preconditioner", choices=("auto", "ldlt", "jacobi"), default="auto")
    ap.add_argument("--sleeping", choices=("on", "off"), default="on")
    a = ap.parse_args()
    for amp, wavelength, wind in (CASES[i] for i in a.cases):
        couples, fit, p99, worst, wall, per, ldlt = run(amp, wavelength, wind, a.cells, a.seconds, a.lattice,
                                                       a.preconditioner, a.sleeping == "on")
        print(f"pleats {100 * amp:.0f} cm every {100 * wavelength:.0f} cm, wind {wind} m/s: {couples} couples, "
              f"fit {fit:.2f}; unburnt edges p99 {100 * p99:.2f} %, worst {100 * worst:.2f} %; "
              f"{wall:.2f} s per simulated s; a step: {per['passes']:.2f} passes, {per['factorizations']:.2f} "
              f"factorizations, {per['cg_iterations']:.1f} CG iterations; {ldlt} LDLT solves", flush=True)


if __name__ == "__main__":
    main()
