"""How far the mesh goes into colliders narrower than a control cell, with the shell's contact
samples (set_colliders(samples=...), docs/dynamics.md §3.2) and without (samples=0: the control
vertices alone, the contact before the samples). The scenes of tests/test_shell_contact.py:

- rod:  a 1 m cloth square (M = 16: 6.7 cm cells, margin 5 mm) dropped 2 cm onto a 1 cm square
        rod halfway between two sample lines, 1 s;
- ball: the same square dropped 1 cm onto a 3 cm ball on the floor, off the sample lines, 1 s;
- edge: the 0.6 x 0.1 m strip of tests/test_colliders.py over a box's edge (4 cm x 0.67 cm
        cells), the edge between two sample columns, 2 s;
- lantern: the demo lantern (a curved shell, 166 couples) on its side, turned 0.25 rad about
        its axis, dropped 2 cm onto a 1 cm rod across its middle, 1.5 s (samples: mesh vertices a control spacing / samples apart);
- carry: a 0.2 m cloth square resting on a box that moves 0.2 m along x in 1 s (set_transform
        once a frame): how far the sheet went with it; and the same box turning 30 degrees
        about z in 1 s: how far the sheet turned;
- cost:  an A4 paper sheet (cells=64, M = 5) burning on a box's top for 8 s: ms per step of the
        whole simulation with and without samples (one run each, timings on a shared machine).

Prints per scene and sample count the smallest signed distance of a mesh vertex to the collider
over the frames (negative: inside), the highest mesh vertex at the end, and the wall time.

    python scripts/collider_shell.py
"""
import time

import numpy as np

import thinburn
from thinburn.colliders import Colliders
from thinburn.scenes import lantern, rect_sheet

QUIET = dict(speed_noise=0.0, duration_noise=0.0)
HALF_SAMPLE = 0.5 / 60


def square(**kw):
    z = kw.pop("z", 0.0)
    return thinburn.Simulation(*rect_sheet(1.0, 1.0, nx=97, ny=97, z=z), cells=48, lattice=16,
                               material="cloth", **QUIET, **kw)


def strip():
    return thinburn.Simulation(*rect_sheet(0.6, 0.1, nx=97, ny=17), cells=32, lattice=16, material="cloth", **QUIET)


def lantern_on_its_side():
    # Turned a quarter radian about its axis, as in the test: the rod meets it between rows of
    # couples (lying square, the rim-seeded lattice has a couple right over the rod).
    v, f = lantern()
    c, s = np.cos(0.25), np.sin(0.25)
    v = (v - v.mean(0)) @ np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]).T @ np.array(
        [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]).T
    v[:, 2] -= v[:, 2].min()
    return thinburn.Simulation(v, f, cells=40, material="paper", **QUIET)


SCENES = {
    "rod": (lambda: square(), dict(boxes=[dict(centre=(0.5 + HALF_SAMPLE, 0.5, -0.025),
                                               half_extents=(0.005, 0.6, 0.005), friction=0.5)]), 1.0),
    "ball": (lambda: square(z=0.04, floor=0.0),
             dict(spheres=[dict(centre=(0.5 + HALF_SAMPLE, 0.5 + HALF_SAMPLE, 0.015), radius=0.015, friction=0.5)]), 1.0),
    "lantern": (lantern_on_its_side, dict(boxes=[dict(centre=(0.0, 0.0, -0.02), half_extents=(0.005, 0.3, 0.005),
                                                      friction=0.5)]), 1.5),
    "edge": (strip, dict(boxes=[dict(centre=(-0.145, 0.05, -0.51), half_extents=(0.5, 0.5, 0.5), friction=1.0)]), 2.0),
}


def penetration(name, samples):
    make, shapes, seconds = SCENES[name]
    sim = make()
    col = Colliders(**shapes)
    sim.set_colliders(col, samples=samples)
    worst = np.inf
    t0 = time.perf_counter()
    for _ in range(int(round(24 * seconds))):
        sim.step(1 / 24)
        worst = min(worst, col.query(sim.vertex_positions())[0].min())
    return worst, sim.vertex_positions()[:, 2].max(), time.perf_counter() - t0


def carried():
    sim = thinburn.Simulation(*rect_sheet(0.2, 0.2, nx=21, ny=21), cells=16, lattice=6, material="cloth", **QUIET)
    col = sim.set_colliders(boxes=[dict(centre=(0.1, 0.1, -0.26), half_extents=(0.25, 0.25, 0.25), friction=1.0)])
    for _ in range(12):
        sim.step(1 / 24)
    x0 = sim.vertex_positions().mean(0)
    for k in range(24):
        col.set_transform(0, (0.1 + 0.2 * (k + 1) / 24, 0.1, -0.26))
        sim.step(1 / 24)
    return (sim.vertex_positions().mean(0) - x0)[0]


def turned():
    sim = thinburn.Simulation(*rect_sheet(0.2, 0.2, nx=21, ny=21), cells=16, lattice=6, material="cloth", **QUIET)
    col = sim.set_colliders(boxes=[dict(centre=(0.1, 0.1, -0.26), half_extents=(0.25, 0.25, 0.25), friction=1.0)])
    for _ in range(12):
        sim.step(1 / 24)
    x0 = sim.vertex_positions()
    for k in range(24):
        a = np.radians(30) * (k + 1) / 24
        col.set_transform(0, (0.1, 0.1, -0.26), [[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
        sim.step(1 / 24)
    x1 = sim.vertex_positions()
    d0, d1 = x0[:, :2] - x0[:, :2].mean(0), x1[:, :2] - x1[:, :2].mean(0)
    return np.degrees(np.arctan2((d0[:, 0] * d1[:, 1] - d0[:, 1] * d1[:, 0]).sum(), (d0 * d1).sum()))


def cost(samples):
    sim = thinburn.Simulation(*rect_sheet(), cells=64, material="paper", **QUIET)
    sim.set_colliders(boxes=[dict(centre=(0.1, 0.15, -0.5), half_extents=(0.5, 0.5, 0.5))], samples=samples)
    sim.ignite_near([(0.0, 0.0, 0.0)], 0.01)
    t0 = time.perf_counter()
    for _ in range(8 * 24):
        sim.step(1 / 24)
    return 1e3 * (time.perf_counter() - t0) / (8 * 24)


if __name__ == "__main__":
    print(f"{'scene':>5} {'samples':>7} {'mesh min mm':>11} {'top z mm':>9} {'wall s':>7}")
    for name in SCENES:
        for samples in (0, 4, 8):
            worst, top, wall = penetration(name, samples)
            print(f"{name:>5} {samples:7d} {1e3 * worst:11.2f} {1e3 * top:9.1f} {wall:7.1f}", flush=True)
    print(f"carry: the sheet moved {1e3 * carried():.1f} mm with the box's 200 mm")
    print(f"turn: the sheet turned {turned():.2f} degrees with the box's 30")
    print(f"cost: burning A4 on a box {cost(0):.2f} ms/step without samples, {cost(4):.2f} with 4")
