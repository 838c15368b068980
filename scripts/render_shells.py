"""Bake and render curved shells with the add-on: `python scripts/render_shells.py --scene lantern`
(writes docs/images/blender_<scene>_<frame>.png and prints what the bake measured).

Scenes (issue #11): ``lantern`` (an open cylinder, r = 0.1 m, 0.3 m tall, standing on a table,
lit on its side), ``sphere`` (a UV sphere, r = 0.1 m, lit on its equator), ``letter`` (a sheet
folded at 30 degrees), ``stack`` (three flat sheets 4 mm apart in one object, lit at a
corner), ``a4`` (the flat A4 sheet on a table), ``box`` (Blender's cube, 10 cm, subdivided 20 x
20 a face, on the table, lit at the middle of a bottom edge) and ``curtain`` (a pleated curtain, 1 m x 1.4 m,
81 x 113 vertices, pleats y = 2 cm sin(2 pi x / 20 cm) in its geometry, Shade Smooth, its hem
5 cm above the table, its top row the Pin Group, Burns Like Curtain, Climb 0.4, lit at the
middle of its hem; ``--wind S`` adds a Wind field of Strength S blowing through it, ``--flame``
lights it with a Flame igniter 3 cm under the hem and Heat Ignites instead; its pictures are
docs/images/blender_pleated_<frame>.png). Each is baked with the add-on from this
checkout (bpy as a module, throwaway user folders), then rendered in Cycles. The printout
gives the bake's seconds per frame, the ignition times (frames) at probe points, and the
largest edge strain of the baked positions; the curtain's also the lattice the core chose (couples,
Simulation.lattice_fit), the 99th percentile of the unburnt edges' strain, how far the pinned
vertices moved and how deep the pleats stay. Needs bpy (CPython 3.11) and thinburn installed in
the same environment. The pleated curtain's pictures:

    python scripts/render_shells.py --scene curtain --frames 192 --cells 128 --v0 50 --samples 32 --render 192
    python scripts/render_shells.py --scene curtain --frames 192 --cells 128 --v0 50 --samples 32 --render 144 \
        --camera 0.55 -0.75 0.45 0 0 0.25
"""
from __future__ import annotations

import argparse
import functools
import json
import math
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from blender_session import ADDON_NAME, ROOT, enable_addon  # scripts/ is on the path when a script runs
from render_fire import cycles_png, dark_world_and_fill

sys.path.insert(0, str(ROOT / "tests" / "blender"))
import blender_helpers as H  # noqa: E402  (the scene builders the tests use)


def _igniter(sheet, location, radius=0.01):
    return H.make_igniter(sheet, location, lit_from=1, radius=radius)


PLEAT_DEPTH, PLEAT_WAVELENGTH = 0.02, 0.2  # the curtain's pleats: y = depth sin(2 pi x / wavelength)


def make_pleated_curtain(nx=81, nz=113, width=1.0, height=1.4, hem=0.05):
    """A vertical plane (x across, z up) of nx x nz vertices with its pleats applied to the
    geometry, Shade Smooth, a linen material and a vertex group "top" of its top row."""
    import bpy
    xs, zs = np.linspace(-width / 2, width / 2, nx), np.linspace(hem, hem + height, nz)
    verts = [(x, PLEAT_DEPTH * math.sin(2 * math.pi * x / PLEAT_WAVELENGTH), z) for z in zs for x in xs]
    faces = [(j * nx + i, j * nx + i + 1, (j + 1) * nx + i + 1, (j + 1) * nx + i)
             for j in range(nz - 1) for i in range(nx - 1)]
    sheet = H.link_mesh("Curtain", verts, faces)
    sheet.data.shade_smooth()  # Shade Smooth (the operator acts on selected objects only)
    linen = bpy.data.materials.new("Linen")
    bsdf = linen.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (0.72, 0.6, 0.45, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.8
    sheet.data.materials.append(linen)
    sheet.vertex_groups.new(name="top").add(list(range(nx * (nz - 1), nx * nz)), 1.0, "REPLACE")
    return sheet


def build(scene_name: str, args):
    """(sheet, probes {name: world point}, camera (location, target)) of a scene."""
    import bpy
    table = H.make_box_table(top=0.0, size=1.2)
    if scene_name == "curtain":
        sheet = make_pleated_curtain()
        lit = (0.0, 0.0, 0.05)
        probes = {"lit": lit, "hem_quarter": (0.25, 0.0, 0.05), "up_10cm": (0.0, 0.0, 0.15),
                  "up_30cm": (0.0, 0.0, 0.35)}
        cam = ((1.1, -2.1, 0.95), (0.0, 0.0, 0.68))
    elif scene_name == "lantern":
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
    elif scene_name == "box":
        # A paper box as an artist makes one: Blender's cube, 10 cm, subdivided (Edit Mode >
        # Subdivide, 19 cuts: 20 x 20 quads a face), resting on the table. Its 12 edges are
        # creases of the lattice's embedding (docs/lattice.md, "Creases").
        bpy.ops.mesh.primitive_cube_add(size=0.1, location=(0.0, 0.0, 0.05))
        sheet = bpy.context.active_object
        sheet.name = "Box"
        bpy.ops.object.mode_set(mode="EDIT")
        bpy.ops.mesh.select_all(action="SELECT")
        bpy.ops.mesh.subdivide(number_cuts=19)
        bpy.ops.object.mode_set(mode="OBJECT")
        lit = (0.0, -0.05, 0.0)
        probes = {"lit": lit, "front_top": (0.0, -0.05, 0.1), "top": (0.0, 0.0, 0.1),
                  "back": (0.0, 0.05, 0.05)}
        cam = ((0.3, -0.35, 0.3), (0.0, 0.0, 0.04))
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
    if scene_name == "curtain":
        s.material = "curtain"  # loads the preset's values: set the speed again after it
        s.mat_V0 = args.v0
        s.pin_group = "top"
        s.climb = args.climb  # flames race up a hanging curtain (0: the front spreads as on a table)
        if args.wind:
            bpy.ops.object.effector_add(type="WIND", location=(0.0, -0.8, 0.7),
                                        rotation=(-math.pi / 2, 0.0, 0.0))  # blows along +y
            bpy.context.active_object.field.strength = args.wind
        if args.flame:  # a candle's flame 3 cm under the hem: it sets the curtain alight by its heat
            s.heat_ignites = True
            flame = _igniter(sheet, (lit[0], lit[1], lit[2] - 0.03), radius=0.005)
            flame.thinburn_igniter.kind = "FLAME"
        else:
            _igniter(sheet, lit, radius=args.radius)
    else:
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


def camera_and_world(cam, width: int, samples: int, lamp_at=(0.3, -0.6, 0.9), energy=3.0, size=0.5,
                     lamp_target=(0.0, 0.0, 0.1)):
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
    lamp = dark_world_and_fill(scene, energy=energy, size=size, location=lamp_at)
    lamp.rotation_euler = (mathutils.Vector(lamp_target) - lamp.location).to_track_quat("-Z", "Y").to_euler()
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
    out["world"], out["ignite"] = world, ignite
    return out


def measure_curtain(sheet, rest, world, ignite) -> dict:
    """The pleated curtain: unburnt edges' strain (p99 and largest per frame), the pinned row's
    motion, the pleats' depth (half the spread in y of a row, at mid-height and 20 cm under the
    top: the pleats' depth in still air, the billow too in wind) and the hem's sway (its mean y)."""
    edges = H.mesh_edges(sheet)
    l0 = np.linalg.norm(rest[edges[:, 0]] - rest[edges[:, 1]], axis=1)
    ign = ignite[edges].min(axis=1)  # the frame the edge's first vertex caught
    p99, worst = [], []
    for k, pos in enumerate(world):
        keep = ign > k + 1
        s = np.abs(np.linalg.norm(pos[edges[keep, 0]] - pos[edges[keep, 1]], axis=1) / l0[keep] - 1)
        p99.append(float(np.percentile(s, 99)) if len(s) else 0.0)
        worst.append(float(s.max()) if len(s) else 0.0)
    p99, worst = np.array(p99), np.array(worst)
    top = np.flatnonzero(np.isclose(rest[:, 2], rest[:, 2].max()))
    hem = np.flatnonzero(np.isclose(rest[:, 2], rest[:, 2].min()))
    zs = np.unique(np.round(rest[:, 2], 6))
    rows = {"mid": zs[len(zs) // 2], "top_20cm": zs[-1] - 0.2}
    depth = {}
    for name, z in rows.items():
        row = np.flatnonzero(np.isclose(rest[:, 2], zs[np.argmin(np.abs(zs - z))]))
        depth[f"pleat_depth_mm_{name}_per_24_frames"] = [
            round(500 * float(np.ptp(f[row, 1] - f[row, 1].mean())), 2) for f in world[::24]]
    every = slice(None, None, 24)
    return {"unburnt_edge_strain_p99_max": round(float(p99.max()), 5),
            "unburnt_edge_strain_p99_frame": int(np.argmax(p99)) + 1,
            "unburnt_edge_strain_max": round(float(worst.max()), 5),
            "unburnt_edge_strain_max_frame": int(np.argmax(worst)) + 1,
            "unburnt_p99_per_24_frames": [round(float(x), 5) for x in p99[every]],
            "unburnt_max_per_24_frames": [round(float(x), 5) for x in worst[every]],
            "pinned_largest_motion_mm": round(1e3 * float(np.linalg.norm(world[:, top] - rest[top], axis=2).max()), 4),
            "hem_mean_y_mm_per_24_frames": [round(1e3 * float(f[hem, 1].mean()), 1) for f in world[every]],
            "hem_lowest_z_m_last": round(float(world[-1, hem, 2].min()), 4),
            **depth}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="lantern", choices=["lantern", "sphere", "letter", "stack", "a4", "box", "curtain"])
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
    ap.add_argument("--wind", type=float, default=0.0,
                    help="curtain: a Wind field of this Strength (m/s at Wind Scale 1) through it")
    ap.add_argument("--flame", action="store_true",
                    help="curtain: a Flame igniter under the hem and Heat Ignites, not a touching igniter")
    ap.add_argument("--climb", type=float, default=0.4, help="curtain: Climb (the core's climb)")
    ap.add_argument("--camera", type=float, nargs=6, default=None, metavar=("X", "Y", "Z", "TX", "TY", "TZ"),
                    help="the camera's location and the point it looks at (default: the scene's)")
    ap.add_argument("--dump", type=Path, default=None,
                    help="save the rest positions, the baked world positions, ignition frames and edges (.npz)")
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
        core, made = sys.modules["thinburn_addon"].job.thinburn, []

        class Kept(core.Simulation):  # the bake's Simulation, to read its lattice afterwards
            @functools.wraps(core.Simulation.__init__)  # the add-on reads the core's keywords off it
            def __init__(self, *a, **kw):
                super().__init__(*a, **kw)
                made.append(self)
        core.Simulation = Kept
        try:
            job = sys.modules["thinburn_addon"].job.BakeJob(bpy.context, sheet)
            job.run()
        finally:
            core.Simulation = Kept.__bases__[0]
        print(job.message)
        for text in job.warnings:
            print("warning:", text)
        bake_s = time.perf_counter() - t0
        info = {"scene": args.scene, "frames": args.frames, "cells": args.cells, "v0_mm_s": args.v0,
                "crumple_gain": args.crumple_gain, "lattice": args.lattice, "shape": job.shape,
                "bake_s": round(bake_s, 2), "bake_s_per_frame": round(bake_s / args.frames, 4)}
        if made:
            info.update(lattice_couples=made[0].lattice_couples,
                        lattice_thickness_mm=round(1e3 * made[0].lattice_thickness, 2),
                        lattice_fit=round(made[0].lattice_fit, 3))
        m = measure(sheet, probes, rest, H.cache_file(args.cache, sheet.name + ".pc2"), 24.0)
        world, ignite = m.pop("world"), m.pop("ignite")
        info.update(m)
        if args.scene == "curtain":
            info.update(measure_curtain(sheet, rest, world, ignite))
        if args.dump:
            np.savez_compressed(args.dump, rest=rest, world=world, ignite=ignite, edges=H.mesh_edges(sheet))
        print(json.dumps(info, indent=1))
        if args.camera:
            cam = (tuple(args.camera[:3]), tuple(args.camera[3:]))
        if args.render:
            lamp = (dict(lamp_at=(-1.4, -1.0, 1.8), energy=60.0, size=1.0, lamp_target=(0.0, 0.0, 0.68))
                    if args.scene == "curtain" else {})  # a raking light across the pleats
            camera_and_world(cam, args.width, args.samples, **lamp)
            name = args.name or ("blender_pleated" if args.scene == "curtain" else f"blender_{args.scene}")
            render_frames(args.render, lambda frame: args.out / f"{name}_{frame:03d}.png")
    finally:
        shutil.rmtree(user, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
