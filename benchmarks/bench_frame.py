"""Benchmark: the cost of a whole simulated frame (fire, particles, heat, pyrolysis, lattice
motion, FFD of the mesh) for each preset's demo scene, with the shell off and on. Prints a
table and saves JSON. Not a test: timings depend on the machine and its load.

The frame loop is benchmarks.bench's (python -m benchmarks --parts frames runs the same
measurement at 128² cells for the demo meshes and 16k-vertex meshes; docs/bench.md).

    python -m benchmarks.bench_frame [--cells 128] [--seconds 20] [--threads 1] [--out bench_frame.json]
"""
from __future__ import annotations

import argparse
import json

import thinburn
from thinburn.demo import build, default_scene

from .perf import PAPER_REFERENCE, best_frames, frame_summary


def make_sim(material: str, cells: int, threads: int, shell: bool):
    scene = default_scene(material)
    if shell:
        return build(scene, material, cells=cells, threads=threads)
    sim = thinburn.Simulation(scene.vertices, scene.faces, material=material, cells=cells,
                              threads=threads, shell=False)
    sim.ignite(scene.ignite_at, time=0.0, radius=scene.ignite_radius)
    return sim


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=128)
    ap.add_argument("--seconds", type=float, default=20.0, help="simulated seconds timed")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--out", default="bench_frame.json")
    args = ap.parse_args()
    rows = []
    for material in thinburn.MATERIALS:
        for shell in (False, True):
            step_ms, pos_ms, stats, sim = best_frames(
                lambda: make_sim(material, args.cells, args.threads, shell),
                frames=int(args.seconds * 24), warmup=48, repeat=1)
            r = dict(material=material, cells=args.cells, shell=shell, threads=sim.threads,
                     lattice=sim.lattice_size, vertices=int(sim.n_vertices),
                     **frame_summary(step_ms, pos_ms, stats))
            rows.append(r)
            print(f"{material:>10}  shell={'on ' if shell else 'off'}  M={r['lattice']:>2}  "
                  f"{r['ms_per_frame']:8.3f} ms/frame  {r['frames_per_second']:9.1f} frames/s  "
                  f"awake={r['awake']:.0f} particles={r['particles']:.0f}", flush=True)
    with open(args.out, "w") as f:
        json.dump({"paper": PAPER_REFERENCE, "rows": rows}, f, indent=2)
    print(f"saved {args.out}; the paper reports ~10 frames/s at 128² cells (rendering included)")


if __name__ == "__main__":
    main()
