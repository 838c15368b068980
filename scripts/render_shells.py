"""Bake and render curved shells with the add-on: `python scripts/render_shells.py --scene lantern`
(writes docs/images/blender_<scene>_<frame>.png and prints what the bake measured).

Scenes (issue #11): ``lantern`` (an open cylinder, r = 0.1 m, 0.3 m tall, standing on a table,
lit on its side), ``sphere`` (a UV sphere, r = 0.1 m, lit on its equator), ``letter`` (a sheet
folded at 30 degrees), ``stack`` (three flat sheets 4 mm apart in one object, lit at a
corner) and ``a4`` (the flat A4 sheet on a table). Each is baked with the add-on from this
checkout (bpy as a module, throwaway user folders), then rendered in Cycles. The printout
gives the bake's seconds per frame, the ignition times (frames) at probe points, and the
largest edge strain of the baked positions. Needs bpy (CPython 3.11) and thinburn installed in
the same environment.
"""
from __future__ import annotations

import argparse
import json
import math
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bench_blender import ADDON_NAME, ROOT, enable_addon  # scripts/ is on the path when a script runs
from render_fire import cycles_png, dark_world_and_fill

sys.path.insert(0, str(ROOT / "tests" / "blender"))
import blender_helpers as H  # noqa: E402  (the scene builders the tests use)


def _igniter(sheet, location, radius=0.01):
    return H.make_igniter(sheet, location, lit_from=1, radius=radius)


def build(scene_name: str, args):
    """(sheet, probes {name: world point}, camera (location, target)) of a scene."""
    import bpy
    table = H.make_box_table(top=0.0, size=1.2)
    if scene_name == "lantern":
        sheet = H.make_lantern(radius=0.1, depth=0.3)
        lit = (0.1, 0.0, 0.15)
        probes = {"lit": lit, "side": (0.0, 0.1, 0.15), "far": (-0.1, 0.0, 0.15),
                  "top_far": (-0.1, 0.0, 0.3)}
        cam = ((0.55, -0.45, 0.4), (0.0, 0.0, 0.14))
    elif scene_name == "sphere":
        sheet = H.make_uv_sphere(radius=0.1, centre=(0.0, 0.0, 0.1))
        lit = (0.1, 0.0, 0.1)
        probes = {"lit": lit, "side": (0.0, 0.1, 0.1), "far": (-0.1, 0.0, 0.1),
                  "top": (0.0, 0.0, 0.2)}
        cam = ((0.5, -0.4, 0.35), (0.0, 0.0, 0.09))
    elif scene_name == "letter":
        sheet = H.make_folded(fold_deg=30.0)
        lit = (-0.105, -0.15, 0.0)
        probes = {"lit": lit, "fold": (0.0, 0.0, 0.0), "far": (0.105, 0.15 * math.cos(math.radians(30)),
                                                              0.15 * math.sin(math.radians(30)))}
        cam = ((0.35, -0.45, 0.35), (0.0, 0.0, 0.03))
    elif scene_name == "stack":
        sheet = H.make_stack()
        lit = (-0.1, -0.1, 0.0)
        probes = {"lit": lit, "top_sheet_corner": (-0.08, -0.08, 0.008),
                  "far": (0.1, 0.1, 0.0)}
        cam = ((0.3, -0.4, 0.35), (0.0, 0.0, 0.0))
    elif scene_name == "a4":
        sheet = H.make_rect("Sheet", 0.21, 0.297, 43, 61)  # A4, lying on the table
        lit = (-0.105, -0.1485, 0.0)
        probes = {"lit": lit, "centre": (0.0, 0.0, 0.0), "far": (0.105, 0.1485, 0.0)}
        cam = ((0.3, -0.4, 0.35), (0.0, 0.0, 0.0))
    else:
        raise SystemExit(f"unknown scene {scene_name!r}")
    s = H.setup_bake(sheet, frames=args.frames, cells=args.cells, cache_dir=args.cache, floor=False)
    s.threads = 0
    s.floor_mode, s.floor_object = "OBJECT", table
    s.mat_V0 = args.v0
    s.crumple = not args.no_crumple
    s.crumple_gain = args.crumple_gain
    s.lattice = args.lattice
    s.flame_intensity, s.flame_temperature = 2.0, 1700.0  # as render_fire.py's Standard looks
    _igniter(sheet, lit, radius=args.radius)
    wood = bpy.data.materials.new("Table")
    wood.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.12, 0.08, 0.05, 1.0)
    table.data.materials.append(wood)
    bpy.context.view_layer.objects.active = sheet
    return sheet, probes, cam


def render_frames(frames, path_of):
    """Render each frame of the scene to path_of(frame) (a Path), printing each file and its time."""
    import bpy
    for frame in frames:
        bpy.context.scene.frame_set(frame)
        path = path_of(frame)
        bpy.context.scene.render.filepath = str(path)
        t0 = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        print(f"{path} ({time.perf_counter() - t0:.1f} s)", flush=True)


def camera_and_world(cam, width: int, samples: int):
    import bpy
    import mathutils
    scene = bpy.context.scene
    ob = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    ob.location = cam[0]
    direction = mathutils.Vector(cam[1]) - mathutils.Vector(cam[0])
    ob.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
    ob.data.lens = 35
    scene.collection.objects.link(ob)
    scene.camera = ob
    lamp = dark_world_and_fill(scene, energy=3.0, size=0.5, location=(0.3, -0.6, 0.9))
    lamp.rotation_euler = (mathutils.Vector((0, 0, 0.1)) - lamp.location).to_track_quat("-Z", "Y").to_euler()
    cycles_png(scene, width, samples)
    scene.view_settings.view_transform = "Standard"


def measure(sheet, probes, rest, cache_path: Path, fps: float) -> dict:
    """Ignition frames at the probes (nearest vertex), strain and motion of the baked positions."""
    ignite = H.point_attribute(sheet, "thinburn_ignite_time")
    out = {"vertices": len(rest), "ignited": int(np.count_nonzero(ignite < 1e8))}
    for name, p in probes.items():
        k = int(np.argmin(np.linalg.norm(rest - np.asarray(p), axis=1)))
        out[f"ignite_{name}"] = float(ignite[k]) if ignite[k] < 1e8 else None
    _, frames = sys.modules[ADDON_NAME].cache.read_pc2(cache_path)  # the add-on's own reader
    mw = np.array(sheet.matrix_world, dtype=np.float64)
    world = frames @ mw[:3, :3].T + mw[:3, 3]
    strain = H.edge_strain(rest, world, H.mesh_edges(sheet))
    out["max_edge_strain"] = float(strain.max())
    out["max_edge_strain_frame"] = int(np.argmax(strain)) + 1
    out["max_displacement_m"] = float(np.linalg.norm(world - rest, axis=2).max())
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="lantern", choices=["lantern", "sphere", "letter", "stack", "a4"])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "images")
    ap.add_argument("--width", type=int, default=480)
    ap.add_argument("--samples", type=int, default=16)
    ap.add_argument("--frames", type=int, default=96, help="frames to bake (24 fps)")
    ap.add_argument("--render", type=int, nargs="*", default=[48, 96], help="frames to render")
    ap.add_argument("--cells", type=int, default=64)
    ap.add_argument("--v0", type=float, default=20.0, help="spread speed, mm/s (paper: 3.5)")
    ap.add_argument("--radius", type=float, default=0.01, help="igniter radius, m")
    ap.add_argument("--no-crumple", action="store_true")
    ap.add_argument("--crumple-gain", type=float, default=0.3,
                    help="Crumple Amount (the add-on's default is 1; 0.3 keeps curved shells sane, "
                         "docs/blender.md)")
    ap.add_argument("--lattice", type=int, default=0, help="Motion Detail (0: the core's choice)")
    ap.add_argument("--name", default=None, help="picture name (default blender_<scene>)")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    user = Path(tempfile.mkdtemp(prefix="thinburn-shells-"))
    args.cache = user / "cache"
    try:
        enable_addon(user)
        import bpy
        bpy.ops.wm.read_homefile(use_empty=True)
        sheet, probes, cam = build(args.scene, args)
        rest = H.world_vertices(sheet)
        t0 = time.perf_counter()
        job = sys.modules["thinburn_addon"].job.BakeJob(bpy.context, sheet)
        job.run()
        print(job.message)
        for text in job.warnings:
            print("warning:", text)
        bake_s = time.perf_counter() - t0
        info = {"scene": args.scene, "frames": args.frames, "cells": args.cells, "v0_mm_s": args.v0,
                "crumple_gain": args.crumple_gain, "lattice": args.lattice, "shape": job.shape,
                "bake_s": round(bake_s, 2), "bake_s_per_frame": round(bake_s / args.frames, 4)}
        info.update(measure(sheet, probes, rest, H.cache_file(args.cache, sheet.name + ".pc2"),
                            24.0))
        print(json.dumps(info, indent=1))
        if args.render:
            camera_and_world(cam, args.width, args.samples)
            name = args.name or f"blender_{args.scene}"
            render_frames(args.render, lambda frame: args.out / f"{name}_{frame:03d}.png")
    finally:
        shutil.rmtree(user, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
