"""A 50 cm cloth dropped on a 10 cm ball, as an artist's trial set it up in Blender (docs/lattice.md,
"Near a collider the mesh keeps the spline"): a 61 x 61 mesh 5 cm above the ball's top, the ball
on the table (floor), its Outer thickness 2 cm (Blender's default) unless --outer, friction 0.05
(Blender's default Friction 5), 128 fire cells and the core's lattice unless --lattice. Prints
every 10 frames the p99 and extremes of the mesh edges' l/L - 1 along the surface, and at the end
the worst edge, how near the mesh came to the ball and the wall time.

    python scripts/ball_drape.py [--outer 0.001] [--lattice 18] [--frames 60]
"""
import argparse
import time

import numpy as np

import thinburn
from thinburn.scenes import rect_sheet


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--outer", type=float, default=0.02, help="the ball's Outer thickness, m")
    ap.add_argument("--lattice", type=int, default=0, help="couples per side (0: the core's)")
    ap.add_argument("--frames", type=int, default=60, help="frames at 24 fps")
    a = ap.parse_args()
    n = 61
    v, f = rect_sheet(0.5, 0.5, nx=n, ny=n, z=0.25)
    v[:, :2] -= v[:, :2].mean(0)
    kw = dict(lattice=a.lattice) if a.lattice else {}
    sim = thinburn.Simulation(v, f, material="cloth", cells=128, floor=0.0, **kw)
    sim.set_colliders(spheres=[dict(centre=(0, 0, 0.1), radius=0.1, friction=0.05, thickness=a.outer)])
    idx = np.arange(n * n).reshape(n, n)
    edges = np.concatenate([np.stack([idx[:, :-1].ravel(), idx[:, 1:].ravel()], 1),
                            np.stack([idx[:-1, :].ravel(), idx[1:, :].ravel()], 1)])
    rest = np.linalg.norm(v[edges[:, 0]] - v[edges[:, 1]], axis=1)
    worst, t0 = (0.0, 0), time.perf_counter()
    for k in range(1, a.frames + 1):
        sim.step(1 / 24)
        if k % 10 and k != a.frames:
            continue
        s = sim.surface_lengths(edges) / rest - 1.0
        j = int(np.argmax(np.abs(s)))
        worst = max(worst, (abs(s[j]), k, s[j]))
        print(f"frame {k:3d}: along the surface p99 |l/L - 1| {100 * np.percentile(np.abs(s), 99):5.2f} %, "
              f"shortest {100 * s.min():+6.2f} %, longest {100 * s.max():+6.2f} %", flush=True)
    r = np.linalg.norm(sim.vertex_positions() - (0, 0, 0.1), axis=1)
    print(f"lattice {sim.lattice_size}, Outer {1000 * a.outer:g} mm: worst edge {100 * worst[2]:+.1f} % at frame "
          f"{worst[1]}; the mesh {1000 * (r.min() - 0.1 - a.outer):.2f} mm outside the grown ball; "
          f"{time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
