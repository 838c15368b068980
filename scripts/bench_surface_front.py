"""Surface fire front: error against exact geodesics and cost, per shape and resolution.

    python scripts/bench_surface_front.py [--sizes 16 32 64 128] [--out bench_surface_front.json]

Shapes (exact geodesics in closed form): a flat sheet, an open cylinder r = 0.1, h = 0.3
(unrolled, the far side included), a unit sphere (great circles), a cone with its apex cut
away (unrolled, round the rim). Error: relative, over cells more than 3 spacings from the
point source. Seconds: building the cells, and ignite + advance to +inf (best of --repeat).
Beside it, the grid front (FireFront, fmm) on an N x N grid for the cost per cell, and the
cost of the incremental advance cut into 500 steps (a frame loop).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import time

import numpy as np

from thinburn import SurfaceCells, SurfaceFront
from thinburn import _surface_shapes as S
from thinburn.fire_front import arrival_times


def shapes():
    cyl_src = np.array([0.1, 0.0, 0.15])
    cone_src = np.array([0.2 * 0.6, 0.0, 0.3 * 0.6])
    sheet_src = np.array([0.3, 0.6, 0.0])
    Vs, Fs = S.icosphere(5)
    return {
        "sheet": (*S.sheet(8), sheet_src, lambda P: S.plane_exact(P, sheet_src)),
        "cylinder": (*S.cylinder(), cyl_src, lambda P: S.cylinder_exact(P, cyl_src)),
        "sphere": (Vs, Fs, Vs[0], lambda P: S.sphere_exact(P, Vs[0])),
        "cone": (*S.cone(nt=128, nr=16), cone_src, lambda P: S.cone_exact(P, cone_src)),
    }


def best_of(repeat, fn):
    out, secs = None, np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        secs = min(secs, time.perf_counter() - t)
    return out, secs


def solve(sc, src):
    front = SurfaceFront(sc)
    front.ignite(src)
    front.advance(np.inf)
    return front.arrival


def frame_loop(sc, src, frames=500):
    """Seconds per frame of advancing a burning front in `frames` equal steps."""
    once = solve(sc, src)
    front = SurfaceFront(sc)
    front.ignite(src)
    t_end = np.max(once[np.isfinite(once)])
    t = time.perf_counter()
    for k in range(1, frames + 1):
        front.advance(t_end * k / frames)
    return (time.perf_counter() - t) / frames


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=int, nargs="+", default=[16, 32, 64, 128])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default="bench_surface_front.json")
    args = ap.parse_args()
    rows = []
    print(f"{'shape':9s} {'N':>4s} {'cells':>6s} {'max rel':>9s} {'mean rel':>9s} {'build s':>8s} "
          f"{'solve s':>8s} {'us/cell':>8s}")
    for name, (V, F, src, exact) in shapes().items():
        for n in args.sizes:
            sc, build = best_of(1, lambda: SurfaceCells(V, F, cells=n))
            t, secs = best_of(args.repeat, lambda: solve(sc, src))
            ex = exact(sc.positions)
            m = ex > 3 * sc.spacing
            rel = np.abs(t - ex)[m] / ex[m]
            row = dict(shape=name, n=n, cells=len(sc), max_rel=float(rel.max()), mean_rel=float(rel.mean()),
                       build_s=build, solve_s=secs, us_per_cell=1e6 * secs / len(sc))
            rows.append(row)
            print(f"{name:9s} {n:4d} {len(sc):6d} {row['max_rel']:9.2e} {row['mean_rel']:9.2e} {build:8.3f} "
                  f"{secs:8.4f} {row['us_per_cell']:8.2f}")
    print("\n== grid front (fmm, N x N, unit speed, centre source) for the cost per cell")
    for n in args.sizes:
        speed = np.ones((n, n))
        _, secs = best_of(args.repeat, lambda: arrival_times(speed, [((n - 1) / 2, (n - 1) / 2)], 1.0 / n))
        rows.append(dict(shape="grid", n=n, cells=n * n, solve_s=secs, us_per_cell=1e6 * secs / (n * n)))
        print(f"{'grid':9s} {n:4d} {n * n:6d} {'':9s} {'':9s} {'':8s} {secs:8.4f} {1e6 * secs / (n * n):8.2f}")
    print("\n== frame loop: the cylinder at N = 128, advance in 500 equal steps")
    V, F, src, _ = shapes()["cylinder"]
    sc = SurfaceCells(V, F, cells=128)
    per_frame = frame_loop(sc, src)
    rows.append(dict(shape="frame_loop", n=128, cells=len(sc), s_per_frame=per_frame))
    print(f"{len(sc)} cells: {per_frame * 1e3:.3f} ms per frame ({1.0 / per_frame:.0f} frames/s)")
    meta = dict(machine=platform.machine(), python=platform.python_version(), repeat=args.repeat)
    if os.path.dirname(args.out):
        os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w") as f:
        json.dump(dict(meta=meta, results=rows), f, indent=1)
    print(f"\nwrote {args.out}")


if __name__ == "__main__":
    main()
