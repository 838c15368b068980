"""Render the add-on's fire: `python scripts/render_fire.py` (writes docs/images/blender_fire_*.png;
docs/blender.md lists the commands behind each picture there).

Bakes a 0.3 m sheet of paper lying on a table, lit at its centre, with the add-on from this
checkout (bpy as a module, throwaway user folders), then renders Cycles frames of the flames,
the char and the embers: the default ThinBurn material, and a sheet with its own blue
Principled BSDF that "Add Burn to Material" wrapped; with --mantaflow, Blender's own fire
solver's flames from the burning band (Add Mantaflow Fire). Needs bpy (CPython 3.11) and thinburn
installed in the same environment. About a minute per picture at the defaults on 2 cores.
"""
from __future__ import annotations

import argparse
import math
import shutil
import tempfile
from pathlib import Path

from bench_blender import ROOT, enable_addon  # scripts/ is on the path when a script runs


def build_scene(cache: Path, size: float, n: int, frames: int, own_material: bool,
                flakes: float = 0.0, height: float = 0.0):
    import bpy
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    step = size / (n - 1)
    verts = [(-size / 2 + i * step, -size / 2 + j * step, height) for j in range(n) for i in range(n)]
    faces = [(j * n + i, j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i)
             for j in range(n - 1) for i in range(n - 1)]
    mesh = bpy.data.meshes.new("Sheet")
    mesh.from_pydata(verts, [], faces)
    sheet = bpy.data.objects.new("Sheet", mesh)
    scene.collection.objects.link(sheet)
    bpy.context.view_layer.objects.active = sheet
    if own_material:
        mat = bpy.data.materials.new("Blue Card")
        bsdf = mat.node_tree.nodes["Principled BSDF"]
        bsdf.inputs["Base Color"].default_value = (0.05, 0.18, 0.6, 1.0)
        bsdf.inputs["Roughness"].default_value = 0.7
        mesh.materials.append(mat)
    s = sheet.thinburn
    s.enabled, s.cells, s.frame_start, s.frame_end = True, 64, 1, frames
    s.cache_dir = str(cache)
    s.floor_mode, s.floor_height = "HEIGHT", 0.0
    s.mat_burn_duration = 3.0
    s.crumple_gain = 0.3  # a gentler curl keeps the ring of fire in view
    s.mat_V0 = 12.0  # mm/s: a faster front than paper's 3.5, so a short bake shows a wide ring
    s.flakes = flakes
    if height > 0:
        s.crumple = False  # held flat in the air (no pins needed), burning through
        s.mat_burn_duration = 1.0
    coll = bpy.data.collections.new("Igniters")
    scene.collection.children.link(coll)
    s.igniter_collection = coll
    igniter = bpy.data.objects.new("Igniter", None)
    coll.objects.link(igniter)
    igniter.location = (0.0, 0.0, height)
    igniter.thinburn_igniter.radius = 0.02
    # a table under the sheet
    bpy.ops.mesh.primitive_plane_add(size=4 * size, location=(0.0, 0.0, -0.001))
    table = bpy.context.active_object
    wood = bpy.data.materials.new("Table")
    wood.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.12, 0.08, 0.05, 1.0)
    table.data.materials.append(wood)
    bpy.context.view_layer.objects.active = sheet
    return sheet


def camera_and_world(size: float, width: int, samples: int, elevation: float = 39.29):
    """A camera 1.42 sheet sizes from the sheet's centre, `elevation` degrees above the table
    (39.29: the docs' pictures; a few degrees: the flames from the side), aimed 1.29 degrees
    above the centre."""
    import bpy
    scene = bpy.context.scene
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    e = math.radians(elevation)
    cam.location = (0.0, -1.42 * size * math.cos(e), 1.42 * size * math.sin(e))
    cam.rotation_euler = (math.radians(91.29 - elevation), 0.0, 0.0)
    cam.data.lens = 32
    scene.collection.objects.link(cam)
    scene.camera = cam
    dark_world_and_fill(scene, energy=0.4, size=size, location=(0.6 * size, -0.6 * size, 1.5 * size))
    cycles_png(scene, width, samples)


def dark_world_and_fill(scene, energy: float, size: float, location):
    """A near-black world (the flames are the light) and one area fill lamp; returns the lamp."""
    import bpy
    world = bpy.data.worlds.new("World")
    scene.world = world
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.004, 0.004, 0.006, 1.0)
    lamp = bpy.data.objects.new("Fill", bpy.data.lights.new("Fill", "AREA"))
    lamp.data.energy = energy
    lamp.data.size = size
    lamp.location = location
    scene.collection.objects.link(lamp)
    return lamp


def cycles_png(scene, width: int, samples: int) -> None:
    """Cycles on the CPU at `samples`, width x 3/4 width PNGs."""
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = width, width * 3 // 4, 100
    r.image_settings.file_format = "PNG"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.volume_biased = True  # ray-marched volumes: far faster flames (docs/blender.md)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "images")
    ap.add_argument("--width", type=int, default=480)
    ap.add_argument("--samples", type=int, default=32)
    ap.add_argument("--frames", type=int, nargs="+", default=[60],
                    help="frames to render (24 fps; the fire starts at frame 1)")
    ap.add_argument("--own-material", action="store_true",
                    help="give the sheet its own Principled BSDF before the bake")
    ap.add_argument("--name", default="blender_fire")
    ap.add_argument("--flakes", type=float, default=0.0, help="the sheet's Ash Flakes share")
    ap.add_argument("--intensity", type=float, default=None, help="the sheet's Flame Intensity")
    ap.add_argument("--flame-temperature", type=float, default=None,
                    help="the sheet's Flame Temperature, K")
    ap.add_argument("--height", type=float, default=0.0,
                    help="hold the sheet this high above the table (Crumple off), m")
    ap.add_argument("--engine", default="CYCLES", choices=["CYCLES", "BLENDER_EEVEE"])
    ap.add_argument("--view", default="AgX", help="the scene's view transform (AgX: Blender's default)")
    ap.add_argument("--elevation", type=float, default=39.29,
                    help="the camera's height above the table, degrees (6: the flames from the side)")
    ap.add_argument("--mantaflow", type=int, default=0, metavar="RES",
                    help="also Add Mantaflow Fire at this Smoke Resolution and bake it (0: off)")
    ap.add_argument("--looks", nargs="*", default=[],
                    help="extra looks as intensity:kelvin:height, rendered per frame (look-dev)")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    user = Path(tempfile.mkdtemp(prefix="thinburn-render-"))
    try:
        enable_addon(user)
        import bpy
        size = 0.3
        sheet = build_scene(user / "cache", size, 49, max(args.frames), args.own_material,
                            args.flakes, args.height)
        if args.intensity is not None:
            sheet.thinburn.flame_intensity = args.intensity
        if args.flame_temperature is not None:
            sheet.thinburn.flame_temperature = args.flame_temperature
        bpy.ops.thinburn.bake()
        if args.mantaflow:
            sheet.thinburn.mantaflow_resolution = args.mantaflow
            sheet.thinburn.frame_end = max(args.frames)
            bpy.ops.thinburn.add_mantaflow_fire(bake=True)
        camera_and_world(size, args.width, args.samples, args.elevation)
        bpy.context.scene.view_settings.view_transform = args.view
        bpy.context.scene.render.engine = args.engine
        looks = [None] + [tuple(float(v) for v in look.split(":")) for look in args.looks]
        for frame in args.frames:
            bpy.context.scene.frame_set(frame)
            for look in looks:
                tag = ""
                if look is not None:
                    s = sheet.thinburn
                    s.flame_intensity, s.flame_temperature, s.flame_height = look
                    tag = "_" + "_".join(f"{v:g}" for v in look)
                path = args.out / f"{args.name}_{frame:03d}{tag}.png"
                bpy.context.scene.render.filepath = str(path)
                bpy.ops.render.render(write_still=True)
                print("wrote", path)
        del sheet
        bpy.ops.wm.read_homefile(use_empty=True)  # free Mantaflow's solvers before Python ends
    finally:
        shutil.rmtree(user, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
