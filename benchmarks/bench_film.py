"""Benchmark: film scale (issue #11, item 4). A flat 1 m paper sheet with N² cells (512²) and an
n × n vertex mesh (1000 × 1000 = 1M vertices), lit at a corner, frames/s on 1 and 2 threads
with a per-phase profile of the frame. Not a test: timings depend on the machine and its load
(the load average is printed and saved with every number).

A frame is sim.step(1/24) then sim.vertex_positions(), as in python -m thinburn.bench (its
frame loop is repeated below, so the script stands alone); each frame keeps its fastest time
over --repeat runs on fresh simulations (the simulation is deterministic: frame k does the
same work in every run), the thread counts taken in turn.

    python -m benchmarks.bench_film [--cells 512] [--side 1000] [--frames 48] [--start 1 60]
                                 [--threads 1 2] [--repeat 2] [--reuse-output] [--out film.json]
                                 [--variants default preconditioner=ldlt,wake_hold=0 ...]

Each --variant is a set of Simulation keywords (`key=value,key=value`; `default`: none); the
variants' runs interleave with the thread counts', so a change of load biases none. Each --start is a window: that many simulated seconds are stepped untimed first (the fire
then covers a 1 cm disc at 1 s, a 20 cm quarter-disc at 60 s).
"""
from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

import thinburn
from thinburn.scenes import rect_sheet

from benchmarks.perf import frame_summary, interleaved_best_frames

SHEET = 1.0  # m, the sheet's side
DT = 1 / 24


def film_mesh(side: int):
    """The film sheet: a side × side vertex grid over a SHEET-metre square (2 (side-1)² faces)."""
    return rect_sheet(SHEET, SHEET, nx=side, ny=side)


def parse_variant(text: str) -> dict:
    """'key=value,key=value' -> Simulation keywords (numbers where they parse); 'default' -> {}."""
    if text == "default":
        return {}
    out = {}
    for item in text.split(","):
        key, _, value = item.partition("=")
        try:
            out[key] = int(value)
        except ValueError:
            try:
                out[key] = float(value)
            except ValueError:
                out[key] = value
    return out


def make_sim(verts, faces, cells: int, threads: int, reuse: bool = False, **params):
    sim = thinburn.Simulation(verts, faces, material="paper", cells=cells, threads=threads,
                              floor=0.0, **params)  # on a table, as the demo sheets
    sim.ignite((0.0, 0.0, 0.0), time=0.0, radius=0.02)  # a corner
    return ReusedOutput(sim) if reuse else sim


class ReusedOutput:
    """A Simulation whose vertex_positions() writes into one array kept from frame to frame
    (vertex_positions(out=...)): what a renderer or an exporter that copies each frame on
    does. A fresh (n, 3) array per frame costs its page faults (see docs/bench.md)."""

    def __init__(self, sim):
        self.sim = sim
        self.out = np.empty((sim.n_vertices, 3))

    def vertex_positions(self):
        return self.sim.vertex_positions(out=self.out)

    def __getattr__(self, name):
        return getattr(self.sim, name)


def profile(sim, frames: int, dt: float = DT) -> tuple:
    """Mean ms per frame of each phase (Simulation.phase_seconds), over `frames` more frames,
    and the mean of mesh_points_redone over them (None without it)."""
    sim.step(dt)
    before = sim.phase_seconds()
    redone = []
    t0 = time.perf_counter()
    for _ in range(frames):
        sim.step(dt)
        sim.vertex_positions()
        redone.append(getattr(sim, "mesh_points_redone", None))
    wall = time.perf_counter() - t0
    after = sim.phase_seconds()
    out = {k: 1e3 * (after[k] - before[k]) / frames for k in after}
    out["frame (wall)"] = 1e3 * wall / frames
    mean_redone = None if None in redone else float(np.mean(redone))
    return out, mean_redone


def measure(verts, faces, args, start: float, log) -> list:
    """Rows for one window: `args.frames` frames timed after `start` simulated seconds."""
    warmup = max(1, round(start * 24))
    makers = {(v, t): (lambda v=v, t=t: make_sim(verts, faces, args.cells, t, args.reuse_output, **parse_variant(v)))
              for v in args.variants for t in args.threads}
    load0 = os.getloadavg()
    best = interleaved_best_frames(makers, args.frames, warmup, args.repeat)
    load1 = os.getloadavg()
    rows = []
    for (variant, t), (step_ms, pos_ms, stats, sim) in best.items():
        r = dict(variant=variant, threads=t, start_seconds=start, cells=args.cells, vertices=len(verts),
                 lattice=sim.lattice_size, reuse_output=args.reuse_output, load_before=load0,
                 load_after=load1, **frame_summary(step_ms, pos_ms, stats))
        r["profile_ms"], r["mesh_points_redone_mean"] = (
            profile(sim, args.profile_frames) if hasattr(sim, "phase_seconds") else ({}, None))
        r["mesh_points_redone"] = getattr(sim, "mesh_points_redone", None)  # the last frame's
        rows.append(r)
        log(f"start={start:5.1f} s {variant} threads={t}  {r['frames_per_second']:6.1f} frames/s  "
            f"{r['ms_per_frame']:7.2f} ms/frame (vertex_positions {r['positions_ms']:.2f} ms)  "
            f"awake={r['awake']:.0f} burning={r['burning']:.0f} cg={r['cg_iterations']:.0f}  "
            f"load {load0[0]:.2f} -> {load1[0]:.2f}")
        log("    " + "  ".join(f"{k} {v:.2f}" for k, v in r["profile_ms"].items())
            + f"  (mesh vertices redone {r['mesh_points_redone_mean']} a frame, "
              f"{r['mesh_points_redone']} the last)")
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=512)
    ap.add_argument("--side", type=int, default=1000, help="mesh vertices per side")
    ap.add_argument("--frames", type=int, default=48, help="frames timed per window")
    ap.add_argument("--start", type=float, nargs="+", default=[1.0, 60.0],
                    help="simulated seconds stepped (untimed) before each window")
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--profile-frames", type=int, default=24)
    ap.add_argument("--reuse-output", action="store_true",
                    help="vertex_positions(out=...) into one array kept across frames")
    ap.add_argument("--variants", nargs="+", default=["default"],
                    help="Simulation keywords per variant, 'key=value,key=value' ('default': none)")
    ap.add_argument("--out", default="film.json")
    args = ap.parse_args()
    verts, faces = film_mesh(args.side)
    t0 = time.perf_counter()
    probe = make_sim(verts, faces, args.cells, args.threads[0])
    build_s = time.perf_counter() - t0
    print(f"film: {len(verts)} vertices, {probe.num_cells} cells, lattice {probe.lattice_size}, "
          f"build {build_s:.1f} s, thinburn at {thinburn.__file__}", flush=True)
    del probe
    rows = []
    for start in args.start:
        rows += measure(verts, faces, args, start, lambda m: print(m, flush=True))
    with open(args.out, "w") as f:
        json.dump(dict(build_seconds=build_s, argv=vars(args), rows=rows), f, indent=2)
    print(f"saved {args.out}")


if __name__ == "__main__":
    main()
