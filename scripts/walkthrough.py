"""The pictures of docs/blender.md's walkthrough: Quick Burn on a plane, and on a stack of
letters, done as an artist does it (a mesh on a table, the 3D cursor where the fire starts,
Object > Quick Effects > Quick Burn), and a curtain lit by a candle (a Flame igniter under its
hem, Heat Ignites on), then rendered in Cycles.

    python scripts/walkthrough.py [--width 480] [--samples 16] [--frames 120]

Needs bpy and thinburn in one environment. Writes docs/images/walkthrough_<scene>_<frame>.png
and prints what each bake reported.
"""
from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

from bench_blender import ROOT, enable_addon  # scripts/ is on the path when a script runs
from render_shells import camera_and_world, render_frames

sys.path.insert(0, str(ROOT / "tests" / "blender"))
import blender_helpers as H  # noqa: E402  (the scene builders the tests use)


def plane():
    """Add > Mesh > Plane (0.3 m), subdivided 63 times, on a table; the cursor at a corner."""
    import bpy
    bpy.ops.mesh.primitive_plane_add(size=0.3, location=(0.0, 0.0, 0.0005))
    sheet = bpy.context.active_object
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.subdivide(number_cuts=63)
    bpy.ops.object.mode_set(mode="OBJECT")
    return sheet, (-0.15, -0.15, 0.0), ((0.32, -0.42, 0.34), (0.0, 0.0, 0.0))


def letters():
    """Three 0.2 m letters stacked 4 mm apart, each shifted 1 cm (one object, as if joined)."""
    sheet = H.make_stack(name="Letters", z=0.0005)
    return sheet, (-0.1, -0.1, 0.0), ((0.3, -0.4, 0.35), (0.0, 0.0, 0.0))


SCENES = {"plane": plane, "letters": letters}  # Quick Burn's; "curtain" is candle_curtain


def _material(name, color, emission=None, strength=0.0):
    import bpy
    mat = bpy.data.materials.new(name)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    if emission is not None:
        bsdf.inputs["Emission Color"].default_value = (*emission, 1.0)
        bsdf.inputs["Emission Strength"].default_value = strength
    return mat


def candle_curtain(frames: int):
    """A 30 × 40 cm curtain hanging from its top edge 10 cm above a table, and a candle under
    its hem: the candle's flame is an Empty of Kind Flame (Object > ThinBurn Igniter) 3 cm below
    the hem, so the curtain catches from the flame's heat (Heat Ignites), not by touch."""
    import bpy
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, frames
    table = H.make_box_table(top=0.0, size=1.2)
    table.data.materials.append(_material("Table", (0.12, 0.08, 0.05)))
    bpy.ops.mesh.primitive_cylinder_add(radius=0.012, depth=0.06, location=(0.0, 0.0, 0.03))
    wax = bpy.context.active_object
    wax.name = "Candle"
    wax.data.materials.append(_material("Wax", (0.85, 0.8, 0.7)))
    nx, nz = 49, 65
    xs = [-0.15 + 0.3 * i / (nx - 1) for i in range(nx)]
    zs = [0.10 + 0.40 * j / (nz - 1) for j in range(nz)]
    verts = [(x, 0.0, z) for z in zs for x in xs]
    faces = [(j * nx + i, j * nx + i + 1, (j + 1) * nx + i + 1, (j + 1) * nx + i)
             for j in range(nz - 1) for i in range(nx - 1)]
    sheet = H.link_mesh("Curtain", verts, faces)
    sheet.data.materials.append(_material("Linen", (0.75, 0.7, 0.62)))
    top = sheet.vertex_groups.new(name="top")
    top.add(list(range(nx * (nz - 1), nx * nz)), 1.0, "REPLACE")
    s = sheet.thinburn
    s.enabled = True
    s.material = "curtain"
    s.mat_V0 = 25.0  # mm/s, as the Quick Burn pictures: something happens in a few seconds
    s.cells = 48
    s.frame_start, s.frame_end = 1, frames
    s.pin_group = "top"
    s.heat_ignites = True
    s.flame_intensity, s.flame_temperature = 2.0, 1700.0
    s.cache_dir = "//thinburn_cache/"
    coll = bpy.data.collections.new("Candle Flame")
    scene.collection.children.link(coll)
    s.igniter_collection = coll
    flame = bpy.data.objects.new("Candle Flame", None)
    coll.objects.link(flame)
    flame.location = (0.0, 0.0, 0.07)  # the wick's tip, 3 cm under the hem
    flame.thinburn_igniter.kind = "FLAME"
    flame.thinburn_igniter.radius = 0.005  # a flame 1 cm wide
    for o in scene.objects:
        o.select_set(o is sheet)
    bpy.context.view_layer.objects.active = sheet
    t0 = time.perf_counter()
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    ignite = H.point_attribute(sheet, "thinburn_ignite_time")
    lit = ignite[ignite < 1e8]
    print(f"curtain: bake took {time.perf_counter() - t0:.1f} s; first lit at frame "
          f"{lit.min() if len(lit) else None}; {len(lit)} of {len(ignite)} vertices caught fire",
          flush=True)
    return (0.3, -0.72, 0.38), (0.0, 0.0, 0.28)


def quick_burn(scene_name: str, frames: int):
    import bpy
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, frames
    table = H.make_box_table(top=0.0, size=1.2)
    wood = bpy.data.materials.new("Table")
    wood.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.12, 0.08, 0.05, 1.0)
    table.data.materials.append(wood)
    sheet, corner, cam = SCENES[scene_name]()
    # What an artist sets before Quick Burn (kept by it): a faster spread than paper's 3.5 mm/s,
    # so that something happens in 5 s, a Fire Detail that bakes in seconds, and for the stack a
    # Motion Detail finer than its sheets' 4 mm gap allows by default (docs/blender.md).
    s = sheet.thinburn
    s.mat_V0 = 25.0  # mm/s
    s.cells = 64
    if scene_name == "letters":
        s.lattice = 9
    s.flame_intensity, s.flame_temperature = 2.0, 1700.0
    scene.cursor.location = corner
    for o in scene.objects:
        o.select_set(o is sheet)
    bpy.context.view_layer.objects.active = sheet
    t0 = time.perf_counter()
    assert bpy.ops.thinburn.quick_burn() == {"FINISHED"}
    print(f"{scene_name}: Quick Burn and its bake took {time.perf_counter() - t0:.1f} s; Floor = "
          f"{s.floor_mode} {getattr(s.floor_object, 'name', '')}", flush=True)
    return cam


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "images")
    ap.add_argument("--width", type=int, default=480)
    ap.add_argument("--samples", type=int, default=16)
    ap.add_argument("--frames", type=int, default=120)
    ap.add_argument("--render", type=int, nargs="+", default=[60, 120],
                    help="frames to render (the curtain: --frames 192 --render 60 192)")
    ap.add_argument("--scenes", nargs="+", default=[*SCENES, "curtain"],
                    choices=[*SCENES, "curtain"])
    args = ap.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="thinburn-walkthrough-"))
    try:
        enable_addon(work / "user")
        import bpy
        for name in args.scenes:
            bpy.ops.wm.read_homefile(use_empty=True)
            bpy.ops.wm.save_as_mainfile(filepath=str(work / f"{name}.blend"))
            cam = candle_curtain(args.frames) if name == "curtain" else quick_burn(name, args.frames)
            camera_and_world(cam, args.width, args.samples)
            render_frames(args.render, lambda frame: args.out / f"walkthrough_{name}_{frame:03d}.png")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
