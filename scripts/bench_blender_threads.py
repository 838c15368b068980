#!/usr/bin/env python3
"""In Blender (bpy), right after a cloth bake: 48 frames of the A4 sheet on all cores and on 1.

    python scripts/bench_blender_threads.py

Issue #10 measured 0.83 s on the default count against 0.029 s on one thread with the OpenMP
core (Blender's own threads had just run the cloth). Needs bpy (CPython 3.11). Prints the
seconds of each run, counts alternating (all, 1, all, 1).
"""
from __future__ import annotations

import time


def cloth_bake(frames: int = 40, n: int = 48) -> float:
    import bpy
    bpy.ops.wm.read_homefile(use_empty=True)
    step = 1.0 / (n - 1)
    verts = [(-0.5 + i * step, -0.5 + j * step, 1.0) for j in range(n) for i in range(n)]
    faces = [(j * n + i, j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i)
             for j in range(n - 1) for i in range(n - 1)]
    mesh = bpy.data.meshes.new("grid")
    mesh.from_pydata(verts, [], faces)
    obj = bpy.data.objects.new("grid", mesh)
    bpy.context.scene.collection.objects.link(obj)
    obj.modifiers.new("Cloth", "CLOTH")
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, frames
    t = time.perf_counter()
    for f in range(1, frames + 1):
        scene.frame_set(f)
    return time.perf_counter() - t


def main() -> None:
    import thinburn
    from thinburn.scenes import rect_sheet
    print(f"cloth bake, 40 frames: {cloth_bake():.2f} s")
    v, f = rect_sheet(0.21, 0.297, nx=43, ny=61)
    for threads in (None, 1, None, 1):
        sim = thinburn.Simulation(v, f, cells=128, floor=0.0, threads=threads)
        sim.ignite((0, 0, 0), time=0.0, radius=0.01)
        t = time.perf_counter()
        for _ in range(48):
            sim.step(1 / 24)
            sim.vertex_positions()
        print(f"threads={sim.threads}: {time.perf_counter() - t:.3f} s for 48 frames", flush=True)


if __name__ == "__main__":
    main()
