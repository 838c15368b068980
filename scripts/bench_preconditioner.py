"""Benchmark: the implicit solve's preconditioners (block LDL^T against Jacobi) on the demo
scenes with the lattice forced to M couples per side, so that nearly all 2 M^2 control
vertices are awake. Prints a table and writes JSON. It is where the default of
``ldlt_max_vertices`` comes from (docs/dynamics.md §4). Not a test: timings depend on the load.

    python scripts/bench_preconditioner.py [--materials paper cloth curtain] [--sizes 9 13 17 21 25]
                                           [--frames 48] [--threads 1] [--refactor-iterations N]
                                           [--out bench_preconditioner.json]
"""
from __future__ import annotations

import argparse
import json
import time

import thinburn
from thinburn.demo import default_scene

WARMUP = 48  # frames: the fire gets going and the sheet starts to curl


def run(material: str, M: int, preconditioner: str, frames: int, threads: int, **params) -> dict:
    scene = default_scene(material)
    sim = thinburn.Simulation(scene.vertices, scene.faces, material=material, cells=128,
                              threads=threads, floor=scene.floor, pinned=scene.pinned, lattice=M,
                              **{**scene.params, "preconditioner": preconditioner, **params})
    sim.wind = scene.wind
    sim.ignite(scene.ignite_at, time=0.0, radius=scene.ignite_radius)
    for _ in range(WARMUP):
        sim.step(1 / 24)
    seconds, iterations, awake, factorizations = 0.0, 0, 0, 0
    for _ in range(frames):
        t0 = time.perf_counter()
        sim.step(1 / 24)
        seconds += time.perf_counter() - t0
        s = sim.stats()
        iterations += s["cg_iterations"]
        awake += s["awake"]
        factorizations += s["factorizations"]
    return dict(material=material, M=M, preconditioner=preconditioner, **params,
                ms_per_frame=1e3 * seconds / frames, cg_iterations=iterations / frames,
                awake=awake / frames, factorizations=factorizations / frames)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--materials", nargs="+", default=["paper", "cloth", "curtain"])
    ap.add_argument("--sizes", type=int, nargs="+", default=[9, 13, 17, 21, 25])
    ap.add_argument("--frames", type=int, default=48)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--refactor-iterations", type=int, default=None,
                    help="the ldlt runs' refactor_iterations (default: the core's)")
    ap.add_argument("--out", default="bench_preconditioner.json")
    args = ap.parse_args()
    rows = []
    print(f"{'material':>8} {'M':>3} {'awake':>6} | {'ldlt ms':>8} {'it':>5} {'fact':>5} | "
          f"{'jacobi ms':>9} {'it':>5} | {'jacobi/ldlt':>11}")
    for material in args.materials:
        for M in args.sizes:
            extra = {} if args.refactor_iterations is None else dict(refactor_iterations=args.refactor_iterations)
            ldlt = run(material, M, "ldlt", args.frames, args.threads, **extra)
            jac = run(material, M, "jacobi", args.frames, args.threads)
            rows += [ldlt, jac]
            print(f"{material:>8} {M:>3} {ldlt['awake']:>6.0f} | {ldlt['ms_per_frame']:>8.2f} "
                  f"{ldlt['cg_iterations']:>5.1f} {ldlt['factorizations']:>5.2f} | "
                  f"{jac['ms_per_frame']:>9.2f} {jac['cg_iterations']:>5.1f} | "
                  f"{jac['ms_per_frame'] / ldlt['ms_per_frame']:>11.2f}", flush=True)
    with open(args.out, "w") as f:
        json.dump(dict(threads=args.threads, frames=args.frames, warmup=WARMUP, rows=rows), f, indent=2)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
