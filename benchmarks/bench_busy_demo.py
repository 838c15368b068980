#!/usr/bin/env python3
"""240 frames of the A4 demo sheet on 1 thread and on all cores, with every core loaded.

    python -m benchmarks.bench_busy_demo            # busy: one spinning process per core
    python -m benchmarks.bench_busy_demo --quiet    # the machine as it is

Issue #10's measurement of the OpenMP core (4.14 s on the default count against 0.18 s on one
thread with every core busy); docs/threads.md quotes it for the core's own pool. Prints the
seconds of each run, counts alternating (1, all, 1, all).
"""
from __future__ import annotations

import argparse
import contextlib
import os
import time

import thinburn
from thinburn.scenes import rect_sheet

from .threads import loaded_cores


def run(threads, frames=240) -> float:
    v, f = rect_sheet(0.21, 0.297, nx=43, ny=61)
    sim = thinburn.Simulation(v, f, cells=128, floor=0.0, threads=threads)
    sim.ignite((0, 0, 0), time=0.0, radius=0.01)
    t = time.perf_counter()
    for _ in range(frames):
        sim.step(1 / 24)
    return time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quiet", action="store_true", help="do not load the cores")
    args = ap.parse_args()
    load = contextlib.nullcontext() if args.quiet else loaded_cores(os.cpu_count() or 1)
    with load:
        time.sleep(0.5)
        for threads in (1, None, 1, None):
            secs = run(threads)
            print(f"threads={threads or thinburn.hardware_threads()}: {secs:.3f} s for 240 frames", flush=True)


if __name__ == "__main__":
    main()
