"""Throughput of wedges: bakes per minute on 1, 2 and 4 local Dask workers against one plain loop.

    python scripts/bench_wedge.py [--out bench_out/wedge] [--wedges 12] [--frames 240] [--cells 64] [--repeat 2]

The same wedges (the paper demo scene, crumple_gain × v0) are baked by
``thinburn.wedge.run_wedges`` four ways, each into a fresh folder so nothing is skipped: in one
plain loop in this process (``workers=0``: no Dask), and on a LocalCluster of 1, 2 and 4
worker processes with one thread each. Wall times include everything a user waits for: the
cluster's start and close, the bakes, each wedge's frames.npz, summary.json and picture, and
the contact sheet. The modes run interleaved, --repeat rounds, each keeping its fastest
round. Overhead = Dask-1's wall time over the loop's, minus one. Writes
results.json and throughput.png in --out. This is a benchmark, not a test: on a shared
machine its numbers move from run to run (the load average is recorded at start and end).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import sys
import time

import numpy as np


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default=os.path.join("bench_out", "wedge"))
    p.add_argument("--wedges", type=int, default=12, choices=[2, 4, 6, 8, 10, 12, 14, 16])
    p.add_argument("--frames", type=int, default=240)
    p.add_argument("--cells", type=int, default=64)
    p.add_argument("--workers", type=int, nargs="+", default=[1, 2, 4])
    p.add_argument("--repeat", type=int, default=2, help="rounds; each mode keeps its best")
    args = p.parse_args(argv)

    from thinburn import wedge
    from thinburn.scenefile import demo_scene

    spec = demo_scene("paper", cells=args.cells, frames=args.frames)
    gains = [0.25, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0][: args.wedges // 2]
    params = [("crumple_gain", gains), ("v0", [0.0035, 0.007])]
    n = len(wedge.combinations(params))
    os.makedirs(args.out, exist_ok=True)
    scratch = os.path.join(args.out, "scratch")
    modes = [0] + list(args.workers)
    rows = {w: dict(mode="loop" if w == 0 else f"dask-{w}", workers=w, wedges=n, walls=[],
                    task_seconds=[], write_seconds=[], load_average_before=[]) for w in modes}
    load0 = os.getloadavg()
    t_all = time.perf_counter()
    for rep in range(args.repeat):  # interleaved, so a busy spell on the machine hits every mode
        for workers in modes:
            row = rows[workers]
            folder = os.path.join(scratch, f"workers_{workers}")
            shutil.rmtree(folder, ignore_errors=True)
            print(f"{row['mode']} (round {rep + 1}/{args.repeat}): {n} wedges of {args.frames} frames, "
                  f"{args.cells} cells ...", file=sys.stderr, flush=True)
            row["load_average_before"].append(round(os.getloadavg()[0], 2))
            t0 = time.perf_counter()
            res = wedge.run_wedges(spec, params, folder, workers=workers)
            wall = time.perf_counter() - t0
            if res["failed"]:
                print(f"  failed: {res['failed']}", file=sys.stderr)
                return 1
            task_s, write_s = [], []
            for name in res["done"]:
                with open(os.path.join(folder, name, "summary.json")) as f:
                    summary = json.load(f)
                task_s.append(summary["wall_seconds"])
                write_s.append(summary["write_seconds"])
            row["walls"].append(round(wall, 3))
            row["task_seconds"].append(round(float(np.mean(task_s)), 3))
            row["write_seconds"].append(round(float(np.mean(write_s)), 3))
            print(f"  {wall:6.1f} s  {60.0 * n / wall:6.1f} bakes/min  (inside a task: bake "
                  f"{task_s and np.mean(task_s):.2f} s, write {np.mean(write_s):.2f} s)",
                  file=sys.stderr, flush=True)
    runs = []
    for w in modes:
        row = rows[w]
        row["wall_seconds"] = min(row["walls"])  # the best round: the least disturbed
        row["bakes_per_minute"] = round(60.0 * n / row["wall_seconds"], 2)
        runs.append(row)
    loop = runs[0]["wall_seconds"]
    for row in runs:
        row["speedup_over_loop"] = round(loop / row["wall_seconds"], 3)
    overhead = runs[1]["wall_seconds"] / loop - 1.0 if len(runs) > 1 and runs[1]["workers"] == 1 else None
    meta = dict(command="python scripts/bench_wedge.py " + " ".join(argv if argv is not None else sys.argv[1:]),
                scene="paper demo (43x61 vertices)", frames=args.frames, cells=args.cells,
                params={k: v for k, v in params}, cpus=os.cpu_count(), machine=platform.platform(),
                python=platform.python_version(), load_average_start=[round(x, 2) for x in load0],
                load_average_end=[round(x, 2) for x in os.getloadavg()],
                total_seconds=round(time.perf_counter() - t_all, 1),
                dask_1_overhead_over_loop=None if overhead is None else round(overhead, 3))
    with open(os.path.join(args.out, "results.json"), "w") as f:
        json.dump({"meta": meta, "runs": runs}, f, indent=2)
    _chart(runs, meta, os.path.join(args.out, "throughput.png"))
    shutil.rmtree(scratch, ignore_errors=True)
    print(f"\n{'mode':8s} {'wall s':>8s} {'bakes/min':>10s} {'x loop':>7s}")
    for row in runs:
        print(f"{row['mode']:8s} {row['wall_seconds']:8.1f} {row['bakes_per_minute']:10.1f} "
              f"{row['speedup_over_loop']:7.2f}")
    if overhead is not None:
        print(f"Dask with 1 worker against the loop: {100 * overhead:+.1f} % wall time")
    print(f"load average {meta['load_average_start']} -> {meta['load_average_end']}; "
          f"wrote {os.path.join(args.out, 'results.json')} and throughput.png")
    return 0


def _chart(runs, meta, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    fig, ax = plt.subplots(figsize=(5.0, 3.0), dpi=100)
    names = [r["mode"] for r in runs]
    rates = [r["bakes_per_minute"] for r in runs]
    bars = ax.bar(names, rates, color=["#777777"] + ["#d9822b"] * (len(runs) - 1))
    for b, r in zip(bars, runs):
        ax.text(b.get_x() + b.get_width() / 2, b.get_height(), f"{r['bakes_per_minute']:.1f}",
                ha="center", va="bottom", fontsize=8)
    ax.set_ylabel("bakes per minute")
    ax.set_title(f"{runs[0]['wedges']} wedges, {meta['frames']} frames, {meta['cells']} cells, "
                 f"{meta['cpus']} CPUs", fontsize=9)
    ax.margins(y=0.15)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
