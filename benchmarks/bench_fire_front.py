"""Fire front: error against closed forms versus seconds, per method and grid size.

    python -m benchmarks.bench_fire_front [--big] [--repeat 3] [--out bench_fire_front.json]

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
import os
import platform

from .bench import front_case as case
from .bench import front_score as score
from .bench import front_solve as solve

METHODS = ("cellular", "cellular16", "fmm1", "fmm")
VARIANTS = {
    # name: (method, FrontOptions as keyword arguments)
    "fmm2 unfactored, init r=3": ("fmm", dict(factored=False, init_radius=3.0)),
    "fmm2 unfactored, init r=1": ("fmm", dict(factored=False, init_radius=1.0)),
    "fmm2 factored, init r=3": ("fmm", dict(factored=True, init_radius=3.0)),
    "fmm1 eulerian drive": ("fmm1", dict(huygens=False)),
    "fmm2 eulerian drive": ("fmm", dict(huygens=False)),
}


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
