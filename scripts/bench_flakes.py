"""Time the ash flakes' motion: `python scripts/bench_flakes.py [--n 129] [--frames 240]`.

A flat n x n-vertex sheet (1 m) whose faces all burn out over the bake, Ash Flakes 0.5: how
long fire.flake_frames takes (the add-on's, from this checkout) and how many flakes it makes.
With --against FILE, the same for the flake_frames of another fire.py (an older checkout's,
e.g. `git show e8503d1:blender_addon/fire.py > /tmp/fire_old.py`), for comparison.
"""
from __future__ import annotations

import argparse
import importlib
import shutil
import sys
import tempfile
import time
import types
from pathlib import Path

import numpy as np

from blender_session import ADDON_NAME, enable_addon  # scripts/ is on the path when a script runs


def sheet(n: int, frames: int):
    x, y = np.meshgrid(np.linspace(-0.5, 0.5, n), np.linspace(-0.5, 0.5, n))
    rest = np.stack([x.ravel(), y.ravel(), np.full(n * n, 0.1)], axis=1)
    positions = np.repeat(rest[None], frames, axis=0)
    faces = [[j * n + i, j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i]
             for j in range(n - 1) for i in range(n - 1)]
    burnout = (np.hypot(rest[:, 0], rest[:, 1]) / 0.71) * 0.8 * frames  # a ring burning outwards
    return positions, faces, burnout


def timed(flake_frames, positions, faces, burnout):
    start = time.perf_counter()
    result = flake_frames(positions, faces, burnout, 1 / 24, 0.5, seed=0, floor=0.0)
    return time.perf_counter() - start, result[1]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=129)
    ap.add_argument("--frames", type=int, default=240)
    ap.add_argument("--against", type=Path, help="another fire.py to time the same way")
    args = ap.parse_args(argv)
    user = Path(tempfile.mkdtemp(prefix="thinburn-bench-"))
    try:
        enable_addon(user)
        fire = importlib.import_module(f"{ADDON_NAME}.fire")
        data = sheet(args.n, args.frames)
        seconds, count = timed(fire.flake_frames, *data)
        print(f"this checkout: {count} flakes, {args.frames} frames, {seconds:.2f} s")
        if args.against is not None:
            old = types.ModuleType(f"{ADDON_NAME}.fire_against")
            old.__package__ = ADDON_NAME
            exec(compile(args.against.read_text(), str(args.against), "exec"), old.__dict__)
            seconds, count = timed(old.flake_frames, *data)
            print(f"{args.against}: {count} flakes, {args.frames} frames, {seconds:.2f} s")
    finally:
        shutil.rmtree(user, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
