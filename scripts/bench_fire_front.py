"""Fire front: error against closed forms versus seconds, per method and grid size.

    python scripts/bench_fire_front.py [--big] [--repeat 3] [--out bench_fire_front.json]

Cases (all with closed-form arrival times):
  point    unit speed, source at the centre; relative error over cells >= 8 cells away.
  gradient v = 1 + 2x on the unit square (T = arccosh(1 + 4|a-b|^2 / (2 v(a) v(b))) / 2).
  ellipse  unit speed with drive e = (0.3, 0.4), |e| = 0.5: focus-at-source ellipse.
  drive    the ellipse at 257 x 257 for |e| = 0.5 ... 0.9 along the column axis (where the
           8-neighbour Huygens update stops being causal).
Variants of the fast-marching settings (FrontOptions) are measured on the same cases to
back the choices in docs/fire_front.md. Seconds: best of --repeat runs of ignite + advance
(one thread; the front is a sequential event loop).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time

import numpy as np

from thinburn import _core
from thinburn.fire_front import method_enum

METHODS = ("cellular", "cellular16", "fmm1", "fmm")
VARIANTS = {
    # name: (method, FrontOptions as keyword arguments)
    "fmm2 unfactored, init r=3": ("fmm", dict(factored=False, init_radius=3.0)),
    "fmm2 unfactored, init r=1": ("fmm", dict(factored=False, init_radius=1.0)),
    "fmm2 factored, init r=3": ("fmm", dict(factored=True, init_radius=3.0)),
    "fmm1 eulerian drive": ("fmm1", dict(huygens=False)),
    "fmm2 eulerian drive": ("fmm", dict(huygens=False)),
}


def case(name: str, n: int, e=(0.3, 0.4)):
    """speed (n, n), source (row, col), spacing h, drive or None, exact T, mask of scored cells."""
    if name == "point":
        src = (n // 2, n // 2)
        dr, dc = np.meshgrid(np.arange(n) - src[0], np.arange(n) - src[1], indexing="ij")
        dist = np.hypot(dr, dc).astype(float)
        return np.ones((n, n)), src, 1.0, None, dist, dist >= 8
    if name == "gradient":
        h = 1.0 / (n - 1)
        x = np.arange(n) * h
        xx, yy = np.meshgrid(x, x)
        v = 1.0 + 2.0 * xx
        src = (n // 2, n // 4)
        d2 = (xx - x[src[1]]) ** 2 + (yy - x[src[0]]) ** 2
        exact = np.arccosh(1.0 + 4.0 * d2 / (2.0 * (1.0 + 2.0 * x[src[1]]) * v)) / 2.0
        return v, src, h, None, exact, np.sqrt(d2) >= 8 * h
    if name == "ellipse":
        src = (n // 2, n // 2)
        dr, dc = np.meshgrid(np.arange(n) - src[0], np.arange(n) - src[1], indexing="ij")
        d = np.hypot(dr, dc)
        exact = (d - (e[0] * dr + e[1] * dc)) / (1.0 - e[0] ** 2 - e[1] ** 2)
        return np.ones((n, n)), src, 1.0, e, exact, d >= 8
    raise ValueError(name)


def solve(speed, src, h, drive, method, repeat, **options):
    n = speed.shape[0]
    flat = np.ascontiguousarray(speed, dtype=np.float64).ravel()
    er = ec = None
    if drive is not None:
        er, ec = np.full(n * n, float(drive[0])), np.full(n * n, float(drive[1]))
    best, t = math.inf, None
    for _ in range(repeat):
        front = _core.FireFront(n, n, h, h, method_enum(method), **options)
        front.set_speed(flat, er, ec)
        start = time.perf_counter()
        front.ignite(float(src[0]), float(src[1]), 0.0)
        front.advance(math.inf)
        best = min(best, time.perf_counter() - start)
        t = front.arrival()
    return t, best


def score(t, exact, mask):
    rel = np.abs(t - exact)[mask] / exact[mask]
    return dict(max_rel=float(rel.max()), mean_rel=float(rel.mean()),
                max_abs=float(np.abs(t - exact).max()))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--big", action="store_true", help="also run 1025 x 1025")
    ap.add_argument("--repeat", type=int, default=3, help="runs per timing (best is kept)")
    ap.add_argument("--out", default="bench_fire_front.json", help="where to write the json")
    args = ap.parse_args()
    sizes = [65, 129, 257, 513] + ([1025] if args.big else [])
    rows = []
    runs = [(m, m, {}) for m in METHODS] + [(k, m, o) for k, (m, o) in VARIANTS.items()]
    for cname in ("point", "gradient", "ellipse"):
        print(f"\n== {cname}")
        print(f"{'method':28s} {'n':>5s} {'max rel':>10s} {'mean rel':>10s} {'max abs':>10s} {'seconds':>9s}")
        for label, method, opts in runs:
            if cname != "ellipse" and "eulerian" in label:
                continue  # the option only matters with a drive
            for n in sizes:
                speed, src, h, drive, exact, mask = case(cname, n)
                t, secs = solve(speed, src, h, drive, method, args.repeat, **opts)
                s = score(t, exact, mask)
                rows.append(dict(case=cname, method=label, n=n, seconds=secs, **s))
                print(f"{label:28s} {n:5d} {s['max_rel']:10.2e} {s['mean_rel']:10.2e} "
                      f"{s['max_abs']:10.2e} {secs:9.4f}")
    print("\n== drive (n = 257, e along the column axis)")
    print(f"{'method':28s} {'|e|':>5s} {'max rel':>10s} {'mean rel':>10s} {'max abs':>10s} {'seconds':>9s}")
    for method in ("cellular16", "fmm1", "fmm"):
        for mag in (0.5, 0.6, 0.7, 0.8, 0.9):
            speed, src, h, drive, exact, mask = case("ellipse", 257, e=(0.0, mag))
            t, secs = solve(speed, src, h, drive, method, args.repeat)
            s = score(t, exact, mask)
            rows.append(dict(case="drive", method=method, n=257, e=mag, seconds=secs, **s))
            print(f"{method:28s} {mag:5.2f} {s['max_rel']:10.2e} {s['mean_rel']:10.2e} "
                  f"{s['max_abs']:10.2e} {secs:9.4f}")
    meta = dict(machine=platform.machine(), processor=platform.processor(),
                python=platform.python_version(), repeat=args.repeat)
    if os.path.dirname(args.out):
        os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w") as f:
        json.dump(dict(meta=meta, results=rows), f, indent=1)
    print(f"\nwrote {args.out}")


if __name__ == "__main__":
    main()
