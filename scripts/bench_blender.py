#!/usr/bin/env python3
"""ThinBurn bake vs Blender's own cloth bake of the same grid, in one run.

    python scripts/bench_blender.py            # 128×128 vertices, 250 frames
    python scripts/bench_blender.py --grid 32 --frames 50   # a quick look

Needs bpy (pip install bpy, CPython 3.11) and thinburn installed in the same environment.
Both bakes run in background mode on the same 1 m × 1 m grid of grid×grid vertices:
ThinBurn with the paper preset, `cells` fire cells and a corner igniter lit at the first
frame; Blender's cloth with its default settings (it does not burn). Prints the times and
their ratio (cloth / ThinBurn) and saves them as JSON.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import sys
import tempfile
import time
from pathlib import Path

from blender_session import ROOT, enable_addon


def grid(name: str, n: int, size: float = 1.0, z: float = 1.0):
    import bpy
    step = size / (n - 1)
    verts = [(-size / 2 + i * step, -size / 2 + j * step, z) for j in range(n) for i in range(n)]
    faces = [(j * n + i, j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i)
             for j in range(n - 1) for i in range(n - 1)]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    return obj


def bake_thinburn(n: int, frames: int, cells: int, threads: int, cache: Path) -> dict:
    import bpy
    bpy.ops.wm.read_homefile(use_empty=True)
    sheet = grid("Sheet", n)
    s = sheet.thinburn
    s.enabled, s.cells, s.frame_start, s.frame_end = True, cells, 1, frames
    s.threads = threads
    s.cache_dir = str(cache)
    coll = bpy.data.collections.new("Igniters")
    bpy.context.scene.collection.children.link(coll)
    s.igniter_collection = coll
    igniter = bpy.data.objects.new("Igniter", None)
    coll.objects.link(igniter)
    igniter.location = (-0.5, -0.5, 1.0)
    igniter.thinburn_igniter.radius = 0.03
    t0 = time.perf_counter()
    bpy.ops.thinburn.bake()
    seconds = time.perf_counter() - t0
    ignite = [v.value for v in sheet.data.attributes["thinburn_ignite_time"].data]
    return {"threads": threads or os.cpu_count(), "seconds": round(seconds, 3),
            "vertices_ignited": sum(1 for v in ignite if v < 1e8)}


def bake_cloth(n: int, frames: int) -> dict:
    import bpy
    bpy.ops.wm.read_homefile(use_empty=True)
    sheet = grid("Cloth", n)
    md = sheet.modifiers.new("Cloth", "CLOTH")
    cache = md.point_cache
    cache.frame_start, cache.frame_end = 1, frames
    bpy.context.scene.frame_start, bpy.context.scene.frame_end = 1, frames
    t0 = time.perf_counter()
    with bpy.context.temp_override(point_cache=cache, active_object=sheet, object=sheet):
        bpy.ops.ptcache.bake(bake=True)
    seconds = time.perf_counter() - t0
    return {"seconds": seconds, "baked": bool(cache.is_baked), "quality": md.settings.quality}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--grid", type=int, default=128, help="vertices per side")
    ap.add_argument("--frames", type=int, default=250)
    ap.add_argument("--cells", type=int, default=128, help="ThinBurn fire cells per side")
    ap.add_argument("--threads", type=int, nargs="+", default=[0],
                    help="ThinBurn core threads, one bake per value (0: every core)")
    ap.add_argument("--out", type=Path, default=ROOT / "bench_out" / "blender.json")
    args = ap.parse_args(argv)

    user = Path(tempfile.mkdtemp(prefix="thinburn-bench-"))
    try:
        enable_addon(user)
        import bpy
        import thinburn
        ours = [bake_thinburn(args.grid, args.frames, args.cells, t, user / "cache")
                for t in args.threads]
        cloth = bake_cloth(args.grid, args.frames)
    finally:
        shutil.rmtree(user, ignore_errors=True)
    for run in ours:
        run["ratio_cloth_over_thinburn"] = round(cloth["seconds"] / run["seconds"], 2)
    result = {
        "grid": args.grid, "frames": args.frames, "cells": args.cells,
        "thinburn_bake_s": ours[0]["seconds"],
        "blender_cloth_bake_s": round(cloth["seconds"], 3),
        "ratio_cloth_over_thinburn": ours[0]["ratio_cloth_over_thinburn"],
        "thinburn_runs": ours,
        "cloth_quality_steps": cloth["quality"], "cloth_baked": cloth["baked"],
        "cpu_count": os.cpu_count(),
        "blender": bpy.app.version_string, "thinburn": thinburn.__version__,
        "python": platform.python_version(), "machine": platform.machine(),
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))
    for run in ours:
        print(f"ThinBurn bake ({run['threads']} threads) {run['seconds']} s, Blender cloth bake "
              f"{result['blender_cloth_bake_s']} s: {run['ratio_cloth_over_thinburn']}x")
    print(f"saved {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
