"""Cost of self-collision (docs/dynamics.md §3.3): time per step of demo scenes with
self_collision on and off, and of the lattice alone while a fold closes onto itself.

    python scripts/bench_self_contact.py [--cells 64] [--seconds 4] [--repeat 3]

Each case runs from the same start with the response on and off, in alternation, and keeps the
least of `repeat` runs' CPU time (process time, all threads: the machine is shared, and wall
time there swings by half). Prints one row per case: CPU ms per step off, on, the difference,
and whether the final meshes (the fold: lattice) on and off are bit-identical.
"""
import argparse
import time

import numpy as np

from thinburn import _core
from thinburn.demo import build, default_scene, shell_scene
from thinburn.dynamics import preset, vertex_masses
from thinburn.lattice import drape


def demo_run(name, cells, seconds, on, vertices=16000):
    """The demo scene with a mesh of about `vertices` (the benchmark's frames part)."""
    scene = shell_scene(name) if name == "letter" else default_scene(name, vertices=vertices)
    sim = build(scene, "paper" if name == "letter" else name, cells=cells)
    sim.set_dynamics(self_collision=on)
    sim.run(1.0)  # past the first steps (everything awake, factorizations)
    steps = int(round(seconds * 24))
    t0 = time.process_time()
    sim.run(seconds)
    return (time.process_time() - t0) / steps, sim.vertex_positions(), ""


def fold_run(on, M=24, steps=96, dt=1 / 240):
    """A 46 cm cloth lattice folded into a U whose upper part is thrown onto the lower one at
    1 m/s (as tests/test_self_contact.py, at twice the resolution): contact in most steps."""
    L, T, fold, bend = 0.02, 0.005, 0.2, 0.01
    W = (M - 1) * L
    s, y = np.meshgrid(np.linspace(0, W, M), np.linspace(0, W, M))
    th = np.clip((s - fold) / bend, 0.0, np.pi)
    x = np.where(s <= fold, s, np.where(s <= fold + np.pi * bend, fold + bend * np.sin(th), fold - (s - fold - np.pi * bend)))
    n = np.stack([-np.sin(th), np.zeros_like(s), np.cos(th)], -1)
    pos = drape(np.stack([x, y, bend * (1 - np.cos(th))], -1), n, T)
    lat = _core.FfdLattice(M, pos)
    dyn = _core.LatticeDynamics(lat, **preset("cloth", stiffness_unit=50.0, has_floor=True, floor_z=-T / 2,
                                              self_collision=on))
    dyn.set_masses(vertex_masses(M, W * W, 0.1))
    vel = np.zeros_like(pos)
    vel[np.repeat(s.ravel() > fold + np.pi * bend, 2), 2] = -1.0
    dyn.set_state(pos, vel)
    D, heat = np.zeros(M * M), np.zeros(2 * M * M)
    substeps = cg = 0
    t0 = time.process_time()
    for _ in range(steps):
        st = dyn.step(dt, D, heat)
        substeps, cg = substeps + st.substeps, cg + st.cg_iterations
    return (time.process_time() - t0) / steps, lat.positions, f" ({substeps} substeps, {cg} CG iterations)"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=128)
    ap.add_argument("--seconds", type=float, default=4.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--scenes", nargs="*", default=["paper", "cloth", "silk", "curtain", "letter"])
    ap.add_argument("--no-fold", action="store_true", help="skip the closing fold")
    a = ap.parse_args()
    cases = [(f"{name} demo, {a.cells} cells", lambda on, name=name: demo_run(name, a.cells, a.seconds, on))
             for name in a.scenes]
    if not a.no_fold:
        cases.append(("U fold closing, M = 24 lattice", fold_run))
    print(f"{'case':34s} {'off cpu ms/step':>16s} {'on cpu ms/step':>15s} {'on - off':>10s} identical")
    for label, run in cases:
        best, final, note = {False: np.inf, True: np.inf}, {}, {}
        for _ in range(a.repeat):
            for on in (False, True):
                t, final[on], note[on] = run(on)
                best[on] = min(best[on], t)
        off, on = 1e3 * best[False], 1e3 * best[True]
        same = "yes" if np.array_equal(final[False], final[True]) else "no"
        extra = f"  off{note[False]}, on{note[True]}" if note[False] else ""
        print(f"{label:34s} {off:16.3f} {on:15.3f} {on - off:+10.3f} {same}{extra}", flush=True)


if __name__ == "__main__":
    main()
