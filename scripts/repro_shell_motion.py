"""Core problems of curved shells' motion, found through the Blender add-on (no bpy needed):
`python scripts/repro_shell_motion.py` prints one line per case.

Measured on 2 cores (one core per run, threads=1). Fixed in the core, kept as checks:

1. A lantern (open cylinder r = 0.1 m, 0.3 m tall, 96 x 33 vertices, on a floor) lit on its
   side at 40 mm/s with the default crumple_gain = 1: in 2.5 s edges stretch 3 % and vertices
   move 0.5 cm (they used to stretch 65 % and move 6 cm); crumple_gain = 0.3: 1 %. A flat A4
   sheet under the same fire: 1 %.
2. A UV sphere (r = 0.1 m) lit on its equator: 1 % (it was 21 %).
3. A sheet folded at 30 degrees (0.21 x 0.30 m, 41 x 41 vertices): the automatic lattice at
   cells = 32 has 10 couples (h = 20.9 mm); edges stretched 52 % within 2 s (12 % with
   crumple_gain 0.3) until its fold became a crease of the embedding (docs/lattice.md,
   "Creases"): 2 % (1 %). lattice=9 (74 couples) and the add-on's default cells = 128 (64
   couples): 1 % (they were 1 % and 2 %).
4. Three 0.2 m sheets 4 mm apart in one mesh: the automatic lattice builds at cells 16 and 32
   (10 couples, h = 28.9 mm; it used to raise "couple 0 of the control surface has no
   neighbour") and at cells 64 (16 couples); lattice=8 gives 57 couples, h = 12.4 mm. With
   lattice 9, cells = 64 and crumple_gain = 0.3 edges stretch 1 % in 5 s (it was 5.6x). At
   the default cells = 128 (64 couples, a layer thicker than the 4 mm between the sheets) and
   crumple_gain 1: 1 % within 3 s (9 % when first listed here, 11.7x before that).

Still open:

5. lattice = 33 on the lantern (1182 couples) costs 0.10 s per 1/24 s step on one core (0.37 s
   when first measured).
"""
from __future__ import annotations

import time

import numpy as np
import thinburn


def grid_faces(nx, ny, wrap=False):
    faces = []
    cols = nx if wrap else nx - 1
    for j in range(ny - 1):
        for i in range(cols):
            a, b = j * nx + i, j * nx + (i + 1) % nx
            c, d = (j + 1) * nx + (i + 1) % nx, (j + 1) * nx + i
            faces += [(a, b, c), (a, c, d)]
    return np.array(faces)


def lantern(r=0.1, h=0.3, seg=96, rings=33, z0=0.0005):
    t = np.linspace(0, 2 * np.pi, seg, endpoint=False)
    z = np.linspace(0, h, rings) + z0
    v = np.array([(r * np.cos(a), r * np.sin(a), zz) for zz in z for a in t])
    return v, grid_faces(seg, rings, wrap=True)


def sphere(r=0.1, seg=64, rings=32, c=(0, 0, 0.1005)):
    v = [(0, 0, -r)]
    for k in range(1, rings):
        phi = -np.pi / 2 + np.pi * k / rings
        v += [(r * np.cos(phi) * np.cos(a), r * np.cos(phi) * np.sin(a), r * np.sin(phi))
              for a in np.linspace(0, 2 * np.pi, seg, endpoint=False)]
    v.append((0, 0, r))
    v = np.array(v) + c
    f = [(0, 1 + (i + 1) % seg, 1 + i) for i in range(seg)]
    for k in range(rings - 2):
        for i in range(seg):
            a, b = 1 + k * seg + i, 1 + k * seg + (i + 1) % seg
            f += [(a, b, b + seg), (a, b + seg, a + seg)]
    top = len(v) - 1
    base = 1 + (rings - 2) * seg
    f += [(base + i, base + (i + 1) % seg, top) for i in range(seg)]
    return v, np.array(f)


def letter(w=0.21, d=0.15, deg=30.0, n=41, z0=0.0005):
    a = np.radians(deg)
    v = []
    for y in np.linspace(-d, d, n):
        for x in np.linspace(-w / 2, w / 2, n):
            v.append((x, y, z0) if y <= 0 else (x, y * np.cos(a), z0 + y * np.sin(a)))
    return np.array(v), grid_faces(n, n)


def stack(size=0.2, gap=0.004, k=3, n=33, z0=0.0005):
    xs = np.linspace(-size / 2, size / 2, n)
    v, f = [], []
    for s in range(k):
        f.append(grid_faces(n, n) + len(v))
        v += [(x + 0.01 * s, y + 0.01 * s, z0 + gap * s) for y in xs for x in xs]
    return np.array(v), np.concatenate(f)


def a4(n=43, m=61, z0=0.0005):
    xs, ys = np.linspace(0, 0.21, n), np.linspace(0, 0.297, m)
    return np.array([(x, y, z0) for y in ys for x in xs]), grid_faces(n, m)


def edges_of(f):
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    return np.unique(np.sort(e, axis=1), axis=0)


def burn(name, v, f, lit, seconds=2.5, **kw):
    mat = thinburn.MATERIALS["paper"].with_(V0=40.0)  # mm/s, a fast front: a short repro
    try:
        sim = thinburn.Simulation(v, f, material=mat, cells=kw.pop("cells", 32), seed=0,
                                  floor=0.0005, threads=1, **kw)
    except ValueError as exc:
        print(f"{name:34s} {kw}: ValueError: {exc}")
        return
    sim.ignite(lit, time=0.0, radius=0.01)
    e = edges_of(f)
    l0 = np.linalg.norm(v[e[:, 0]] - v[e[:, 1]], axis=1)
    worst, steps = 0.0, int(seconds * 24)
    t1 = time.perf_counter()
    for _ in range(steps):
        sim.step(1 / 24)
        p = sim.vertex_positions()
        worst = max(worst, float(np.abs(np.linalg.norm(p[e[:, 0]] - p[e[:, 1]], axis=1) / l0 - 1).max()))
    step_s = (time.perf_counter() - t1) / steps
    disp = float(np.linalg.norm(p - v, axis=1).max())
    burnt = float(np.mean(np.asarray(sim.cell_states()) == 2))
    print(f"{name:34s} {kw}: {sim.geometry}, {sim.lattice_couples} couples, h {sim.lattice_thickness * 1000:.1f} mm: max edge strain "
          f"{worst:.2f}, max displacement {disp * 100:.1f} cm, burnt {burnt:.0%}, "
          f"{step_s:.4f} s/step")


def main():
    v, f = lantern()
    burn("lantern, crumple_gain 1", v, f, (0.1, 0, 0.1505))
    burn("lantern, crumple_gain 0.3", v, f, (0.1, 0, 0.1505), crumple_gain=0.3)
    v, f = sphere()
    burn("sphere, crumple_gain 1", v, f, (0.1, 0, 0.1005))
    v, f = a4()
    burn("flat A4, crumple_gain 1", v, f, (0, 0, 0.0005))
    v, f = letter()
    burn("letter folded 30 deg, auto lattice", v, f, (-0.105, -0.15, 0.0005), seconds=2.0)
    burn("letter, crumple_gain 0.3", v, f, (-0.105, -0.15, 0.0005), seconds=2.0, crumple_gain=0.3)
    burn("letter, lattice 9", v, f, (-0.105, -0.15, 0.0005), seconds=2.0, lattice=9)
    v, f = stack()
    for cells in (16, 32, 64):
        burn("stack of 3 sheets", v, f, (-0.1, -0.1, 0.0005), seconds=0.5, cells=cells)
    burn("stack of 3 sheets, lattice 8", v, f, (-0.1, -0.1, 0.0005), seconds=0.5, cells=32, lattice=8)
    burn("stack, lattice 9, cells 64, gain 0.3", v, f, (-0.1, -0.1, 0.0045), seconds=5.0, cells=64,
         lattice=9, crumple_gain=0.3)
    burn("stack, cells 128 (the add-on's default)", v, f, (-0.1, -0.1, 0.0045), seconds=3.0,
         cells=128)
    v, f = letter()
    burn("letter, cells 128 (the add-on's default)", v, f, (-0.105, -0.15, 0.0005), seconds=2.0,
         cells=128)
    v, f = lantern()
    burn("lantern, lattice 33", v, f, (0.1, 0, 0.1505), seconds=0.5, lattice=33)


if __name__ == "__main__":
    main()
