"""Benchmark: the cost of a whole simulated frame (fire, particles, heat, pyrolysis, lattice
motion, FFD of the mesh) at 128² cells, for each preset's demo scene. Prints a table and
saves JSON. Not a test: timings depend on the machine and its load.

    python scripts/bench_frame.py [--cells 128] [--seconds 20] [--threads 1] [--out bench_frame.json]
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np

import thinburn
from thinburn.demo import build, default_scene


def measure(material: str, cells: int, seconds: float, threads: int, shell: bool) -> dict:
    scene = default_scene(material)
    if shell:
        sim = build(scene, material, cells=cells, threads=threads)
    else:
        sim = thinburn.Simulation(scene.vertices, scene.faces, material=material, cells=cells,
                                  threads=threads, shell=False)
        sim.ignite(scene.ignite_at, time=0.0, radius=scene.ignite_radius)
    warm = int(2 * 24)
    for _ in range(warm):  # let the fire get going
        sim.step(1 / 24)
    frames = int(seconds * 24)
    t0 = time.perf_counter()
    for _ in range(frames):
        sim.step(1 / 24)
        sim.vertex_positions()
    wall = time.perf_counter() - t0
    stats = sim.stats()
    return {"material": material, "cells": cells, "shell": shell, "threads": threads,
            "frames": frames, "seconds": wall, "ms_per_frame": 1000 * wall / frames,
            "frames_per_second": frames / wall, "lattice": sim.lattice_size,
            "vertices": int(len(scene.vertices)), "last_stats": {k: float(v) for k, v in stats.items()}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=128)
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--out", default="bench_frame.json")
    args = ap.parse_args()
    rows = []
    for material in thinburn.MATERIALS:
        for shell in (False, True):
            r = measure(material, args.cells, args.seconds, args.threads, shell)
            rows.append(r)
            print(f"{material:>10}  shell={'on ' if shell else 'off'}  M={r['lattice']:>2}  "
                  f"{r['ms_per_frame']:8.3f} ms/frame  {r['frames_per_second']:9.1f} frames/s  "
                  f"awake={r['last_stats'].get('awake', 0):.0f} particles={r['last_stats'].get('particles', 0):.0f}",
                  flush=True)
    with open(args.out, "w") as f:
        json.dump({"paper_fps_pentium4": 10.0, "rows": rows}, f, indent=2)
    print(f"saved {args.out}; the paper reports ~10 frames/s at 128² cells (rendering included)")


if __name__ == "__main__":
    main()
