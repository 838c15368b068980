"""Cost of the heat sum (eq 2) and the pyrolysis sum (eq 3), direct vs fast, per call.

Heat: fire particles from a burning ring (radius 0.3 m) on a 1 m sheet at z = 0, in a
0.3 m/s wind, produced by thinburn's own ParticleSystem with its default flame parameters
(the birth rate is scaled to reach the wanted count), onto control vertices on two M x M
lattices 2 mm above and below the sheet. Pyrolysis: a disc of burning cells of a 128 x 128
cell grid as ignition points, onto the same lattices.

For every size: wall time per call (best of a few repeats; "fast" includes the tree build),
the largest relative error of fast against direct, and the largest returned bound relative
to the direct sum (the guarantee is bound <= tolerance). Prints a table and writes json.

    python scripts/bench_heat.py [--out bench_out/bench_heat.json] [--threads 1] [--quick]
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import time

import numpy as np

import thinburn
from thinburn import _core
from thinburn.heat import kernel_sum
from thinburn.particles import DEFAULTS, ParticleSystem


def lattice_targets(m: int) -> np.ndarray:
    g = (np.arange(m) + 0.5) / m - 0.5
    x, y = np.meshgrid(g, g)
    flat = np.c_[x.ravel(), y.ravel()]
    return np.r_[np.c_[flat, np.full(m * m, 0.002)], np.c_[flat, np.full(m * m, -0.002)]]


def fire_ring(n: int, seed: int = 0):
    """About n live particles above a burning ring, after 0.6 s of burning."""
    k, radius, dt = 512, 0.3, 1.0 / 60.0
    a = np.linspace(0.0, 2 * np.pi, k, endpoint=False)
    pos = np.c_[radius * np.cos(a), radius * np.sin(a), np.zeros(k)]
    normal = np.tile([0.0, 0.0, 1.0], (k, 1))
    length = np.full(k, 2 * np.pi * radius / k)
    rate = n / (2 * np.pi * radius * DEFAULTS["lifetime"])
    ps = ParticleSystem(seed=seed, birth_rate=rate, capacity=max(16, 2 * n))
    for _ in range(36):
        ps.emit(pos, normal, length, dt)
        ps.step(dt, (0.3, 0.0, 0.0))
    return ps.positions(), ps.temperatures()


def burning_disc(n: int):
    """About n burning cell centres of a 128 x 128 grid over the sheet, in a disc."""
    g = (np.arange(128) + 0.5) / 128 - 0.5
    x, y = np.meshgrid(g, g)
    r = np.hypot(x, y).ravel()
    keep = np.argsort(r, kind="stable")[:n]
    return np.c_[x.ravel()[keep], y.ravel()[keep], np.zeros(n)], np.ones(n)


def best_time(fn, repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def measure(src, w, tgt, power, tol, repeats):
    direct = kernel_sum(src, w, tgt, power=power, method="direct")
    fast, bound = kernel_sum(src, w, tgt, power=power, method="fast", tolerance=tol,
                             return_bound=True)
    rel = np.abs(fast - direct) / direct
    reps_direct = repeats if len(src) * len(tgt) < 2e8 else 1
    return {
        "sources": int(len(src)),
        "targets": int(len(tgt)),
        "direct_s": best_time(lambda: kernel_sum(src, w, tgt, power=power, method="direct"),
                              reps_direct),
        "fast_s": best_time(lambda: kernel_sum(src, w, tgt, power=power, method="fast",
                                               tolerance=tol), repeats),
        "max_rel_error": float(rel.max()),
        "max_bound_over_sum": float((bound / direct).max()),
        "bound_holds": bool(np.all(np.abs(fast - direct) <= bound + 1e-11 * direct)),
    }


def table(title, rows):
    print(f"\n{title}")
    print(f"{'sources':>8} {'targets':>8} {'direct ms':>10} {'fast ms':>9} {'speedup':>8} "
          f"{'max rel err':>12} {'max bound/sum':>14}")
    for r in rows:
        print(f"{r['sources']:>8} {r['targets']:>8} {1e3 * r['direct_s']:>10.2f} "
              f"{1e3 * r['fast_s']:>9.2f} {r['direct_s'] / r['fast_s']:>8.2f} "
              f"{r['max_rel_error']:>12.2e} {r['max_bound_over_sum']:>14.2e}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="bench_out/bench_heat.json")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--tolerance", type=float, default=0.01)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="small sizes only")
    args = ap.parse_args()
    thinburn.set_threads(args.threads)
    counts = [100, 1000, 10000] if args.quick else [100, 300, 1000, 3000, 10000, 30000, 100000]
    lattices = [32] if args.quick else [32, 64]
    cells = [100, 1000] if args.quick else [100, 1000, 4000, 16384]

    result = {"tolerance": args.tolerance, "threads": thinburn.get_threads(),
              "machine": {"cpu_count": os.cpu_count(), "platform": platform.platform(),
                          "processor": platform.processor()},
              "heat": [], "pyrolysis": []}
    for m in lattices:
        tgt = lattice_targets(m)
        for n in counts:
            src, temp = fire_ring(n)
            result["heat"].append({"lattice": m, **measure(src, temp, tgt, 2, args.tolerance,
                                                            args.repeats)})
        for n in cells:
            src, w = burning_disc(n)
            result["pyrolysis"].append({"lattice": m, **measure(src, w, tgt, 1, args.tolerance,
                                                                 args.repeats)})
    table(f"heat, eq (2), p = 2, tolerance {args.tolerance}, {result['threads']} thread(s)",
          result["heat"])
    table(f"pyrolysis, eq (3), p = 1, tolerance {args.tolerance}, {result['threads']} thread(s)",
          result["pyrolysis"])
    os.makedirs(os.path.dirname(args.out) or ".", exist_ok=True)
    with open(args.out, "w") as f:
        json.dump(result, f, indent=1)
    print(f"\nwrote {args.out}")


if __name__ == "__main__":
    main()
