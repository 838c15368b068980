"""The pictures of docs/blender.md's walkthrough: Quick Burn on a plane, and on a stack of
letters, done as an artist does it (a mesh on a table, the 3D cursor where the fire starts,
Object > Quick Effects > Quick Burn), then rendered in Cycles.

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
from render_shells import camera_and_world

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


SCENES = {"plane": plane, "letters": letters}


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
    ap.add_argument("--render", type=int, nargs="+", default=[60, 120])
    ap.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    args = ap.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="thinburn-walkthrough-"))
    try:
        enable_addon(work / "user")
        import bpy
        for name in args.scenes:
            bpy.ops.wm.read_homefile(use_empty=True)
            bpy.ops.wm.save_as_mainfile(filepath=str(work / f"{name}.blend"))
            cam = quick_burn(name, args.frames)
            camera_and_world(cam, args.width, args.samples)
            for frame in args.render:
                bpy.context.scene.frame_set(frame)
                path = args.out / f"walkthrough_{name}_{frame:03d}.png"
                bpy.context.scene.render.filepath = str(path)
                t0 = time.perf_counter()
                bpy.ops.render.render(write_still=True)
                print(f"{path} ({time.perf_counter() - t0:.1f} s)", flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
