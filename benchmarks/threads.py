"""The threads part of ``python -m benchmarks``: does a second thread ever hurt?

Every preset's demo scene at 128² cells with a ~16k-vertex mesh, and two larger sheets (paper:
512² cells with ~100k vertices, 128² with ~400k), are timed on 1 thread and on all logical
cores: first on the
machine as it is ("quiet"), then with every core loaded by a busy loop in another process
that the bench starts itself ("busy": what a user sees while Blender renders). Fit rows hold
the ratio of the all-cores time to the 1-thread time per scene and load; issue #10's goal is
a busy ratio of at most 1.10, and below 1 on quiet cores where a frame has enough work.
"""
from __future__ import annotations

import contextlib
import multiprocessing as mp
import os

import numpy as np

from thinburn._threads import hardware_threads
from thinburn.demo import build, default_scene
from thinburn.materials import MATERIALS

from .perf import _pyplot, frame_summary, interleaved_best_frames, save_figure

GOAL_BUSY_RATIO = 1.10
SCENES = tuple((m, 128, 16000) for m in MATERIALS) + (("paper", 512, 100000), ("paper", 128, 400000))


def _spin(stop) -> None:
    """A busy loop until `stop` is set (checked every few milliseconds)."""
    x = 0
    while not stop.is_set():
        for _ in range(200_000):
            x += 1


@contextlib.contextmanager
def loaded_cores(n: int):
    """n processes that keep a core busy each, for the duration of the block."""
    ctx = mp.get_context("spawn")
    stop = ctx.Event()
    procs = [ctx.Process(target=_spin, args=(stop,), daemon=True) for _ in range(n)]
    for p in procs:
        p.start()
    try:
        yield
    finally:
        stop.set()
        for p in procs:
            p.join(timeout=10)
            if p.is_alive():
                p.terminate()


def _time_scenes(scenes, counts, frames, warmup, repeat, load, log):
    rows = []
    for material, cells, verts in scenes:
        scene = default_scene(material, vertices=verts)
        big = cells > 128 or verts > 20000
        makers = {t: (lambda t=t: build(scene, material, cells=cells, threads=t)) for t in counts}
        timed = interleaved_best_frames(makers, frames // 2 if big else frames, warmup // 2 if big else warmup, repeat)
        for threads, (step_ms, pos_ms, stats, sim) in timed.items():
            s = frame_summary(step_ms, pos_ms, stats)
            name = f"{material} {cells}² {len(scene.vertices) // 1000}k"
            rows.append(dict(part="threads", method=name, scene=material, resolution=cells,
                             vertices=int(len(scene.vertices)), lattice=sim.lattice_size,
                             threads=sim.threads, load=load, **s))
            log(f"threads     {load:5s} {name:22s} threads={sim.threads} {s['ms_per_frame']:8.2f} ms/frame")
    return rows


def bench_threads(frames, warmup, repeat, log, scenes=SCENES):
    """Rows per scene, thread count and load, and the ratio rows."""
    counts = sorted({1, hardware_threads()})
    rows = _time_scenes(scenes, counts, frames, warmup, repeat, "quiet", log)
    with loaded_cores(os.cpu_count() or 1):
        rows += _time_scenes(scenes, counts, frames, warmup, repeat, "busy", log)
    for load in ("quiet", "busy"):
        for name in dict.fromkeys(r["method"] for r in rows):
            sub = {r["threads"]: r for r in rows if r["method"] == name and r["load"] == load}
            if len(sub) < 2:
                continue
            ratio = sub[max(sub)]["ms_per_frame"] / sub[1]["ms_per_frame"]
            rows.append(dict(part="fit", method="threads_ratio", scene=name, load=load,
                             threads=max(sub), ratio=ratio))
            log(f"threads     {load:5s} {name:22s} {max(sub)} threads / 1 thread = {ratio:.2f}")
    return rows


def plot_threads(rows, path):
    """The all-cores time over the 1-thread time per scene, quiet and busy."""
    plt = _pyplot()
    fits = [r for r in rows if r["part"] == "fit" and r["method"] == "threads_ratio"]
    names = list(dict.fromkeys(r["scene"] for r in fits))
    fig, ax = plt.subplots(figsize=(9, 4.5))
    for k, (load, colour) in enumerate((("quiet", "tab:blue"), ("busy", "tab:orange"))):
        sub = {r["scene"]: r for r in fits if r["load"] == load}
        ax.bar(np.arange(len(names)) + (k - 0.5) * 0.38, [sub[n]["ratio"] if n in sub else 0 for n in names],
               0.38, color=colour, label=f"{load} machine" + (" (every core loaded by the bench)" if load == "busy" else ""))
    ax.axhline(1.0, color="k", lw=1)
    ax.axhline(GOAL_BUSY_RATIO, color="tab:red", ls="--", lw=1,
               label=f"issue #10 goal when busy: <= {GOAL_BUSY_RATIO:.2f}")
    threads = fits[0]["threads"] if fits else 2
    ax.set_xticks(np.arange(len(names)))
    ax.set_xticklabels(names, fontsize=8, rotation=15)
    ax.set_ylabel(f"time per frame, {threads} threads / 1 thread")
    ax.set_title("Does a second thread hurt? (below 1: it helps)", fontsize=9)
    ax.set_ylim(0, max([1.4] + [r["ratio"] * 1.15 for r in fits]))
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    save_figure(fig, path)
