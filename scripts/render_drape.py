"""Soft cloth in real Blender, as an artist sets it up (issue #12, item 1): bake, render, measure.

    python scripts/render_drape.py [--scenes drape curtain] [--width 320] [--samples 16]

``drape``: a 40 cm cloth (preset Cloth, Motion Detail 16) 2 cm above a UV sphere (r = 10 cm,
Blender's Collision modifier) that stands on a table, lit at a corner from frame 1, so that it
burns while it drapes. ``curtain``: a 30 x 40 cm curtain (preset Curtain) pinned along its top
(vertex group "top", Pin Group), its hem 10 cm above a table, lit at the middle of its hem.
Each is baked with the add-on from this checkout (bpy as a module, throwaway user folders, as
tests/blender does), rendered in Cycles at the --render frames, and measured from the cache:
the lowest and highest rim height, the cache vertices inside the sphere, the pinned vertices'
largest motion, the largest edge strain. Writes docs/images/drape_<scene>_<frame>.png.

An artist's trial (docs/blender.md): ``table`` (A4 paper on a cube with Collision physics, no
Floor; ``--table-floor`` makes the cube its Floor Object instead), ``silk`` (a silk curtain
pinned along its top in a Wind field, with ``--stretch-limit``), ``lantern`` (a cylinder
without caps lit at its bottom), ``rod`` (cloth dropped over a thin cylinder with Collision),
``pile`` (cloth let go upright on a table: it folds into a pile), ``corners`` (a 60 cm silk held
at its two top corners, Motion Detail --lattice). ``--without-addon`` then
saves the .blend, disables the add-on, reopens it, renders the same frames again and prints
the largest pixel difference.
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

from blender_session import ADDON_NAME, ROOT, enable_addon  # scripts/ is on the path when a script runs
from render_shells import camera_and_world, render_frames
from walkthrough import _material

sys.path.insert(0, str(ROOT / "tests" / "blender"))
import blender_helpers as H  # noqa: E402  (the scene builders the tests use)

R, CENTRE = 0.1, (0.0, 0.0, 0.1)  # the sphere stands on the table (z = 0)


def _unburnt_p99(sheet, rest, world, ignite):
    """Every 24th frame (k = 0, 24, ...; Blender frame k + 1), the p99 of |l/L - 1| over the
    edges neither of whose vertices had caught fire by that frame."""
    edges = H.mesh_edges(sheet)
    l0 = np.linalg.norm(rest[edges[:, 0]] - rest[edges[:, 1]], axis=1)
    out = []
    for k in range(0, len(world), 24):
        keep = np.all(ignite[edges] > k + 1, axis=1)
        f = world[k]
        strain = np.abs(np.linalg.norm(f[edges[keep, 0]] - f[edges[keep, 1]], axis=1) / l0[keep] - 1.0)
        out.append(round(float(np.percentile(strain, 99)), 4) if strain.size else None)
    return out


def _common(sheet, table, args, material):
    s = H.setup_bake(sheet, frames=args.frames, cells=args.cells, cache_dir=args.cache, floor=False)
    s.threads = 0
    s.material = material
    s.lattice = args.lattice
    s.floor_mode, s.floor_object = "OBJECT", table
    s.mat_V0 = args.v0
    s.flame_intensity, s.flame_temperature = 2.0, 1700.0  # as render_shells.py's pictures
    return s


def drape(args):
    """(sheet, camera, measure(rest, world frames) -> dict)."""
    import bpy
    table = H.make_box_table(top=0.0, size=1.2)
    table.data.materials.append(_material("Table", (0.12, 0.08, 0.05)))
    sphere = H.make_uv_sphere(radius=R, segments=64, rings=32, centre=CENTRE)
    bpy.ops.object.shade_smooth()
    sphere.data.materials.append(_material("Ball", (0.25, 0.32, 0.45)))
    sphere.modifiers.new("Collision", "COLLISION")
    sphere.collision.cloth_friction = 50.0   # Coulomb 0.5 (docs/blender.md)
    sphere.collision.thickness_outer = 0.001
    n = args.n
    top = CENTRE[2] + R
    sheet = H.make_sheet(name="Cloth", n=n, size=0.4, z=top + 0.02)
    sheet.data.materials.append(_material("Cotton", (0.7, 0.62, 0.5)))
    bpy.context.view_layer.objects.active = sheet
    bpy.ops.object.shade_smooth()
    _common(sheet, table, args, "cloth")
    H.make_igniter(sheet, (0.2, 0.2, top + 0.02), lit_from=1, radius=args.radius)
    # Facets of a 64 x 32 UV sphere lie at most R (1 - cos(180/64 deg)) = 0.12 mm inside the
    # true sphere (its rings: 180/32 deg, 0.48 mm): "inside" is nearer the centre than R - 0.5 mm.
    facet = R * (1.0 - math.cos(math.pi / 32))

    def measure(rest, world):
        rim = np.max(np.abs(rest[:, :2]), axis=1) > 0.2 - 1e-6
        r = np.linalg.norm(world - np.asarray(CENTRE), axis=2)
        middle = int(np.argmin(np.linalg.norm(rest[:, :2], axis=1)))
        corners = [0, n - 1, n * n - n, n * n - 1]  # (-x -y), (+x -y), (-x +y), (+x +y)
        return {"rim_lowest_m_last": float(world[-1, rim, 2].min()),
                "rim_highest_m_last": float(world[-1, rim, 2].max()),
                "corners_z_m_last": [round(float(world[-1, k, 2]), 4) for k in corners],
                "rim_highest_m_per_12_frames": [round(float(f[rim, 2].max()), 4) for f in world[11::12]],
                "middle_above_top_mm_last": round(1e3 * float(world[-1, middle, 2] - top), 2),
                "nearest_to_centre_minus_R_mm": round(1e3 * float(r.min() - R), 2),
                "inside_sphere_vertex_frames": int(np.count_nonzero(r < R - facet)),
                "below_table_vertex_frames": int(np.count_nonzero(world[..., 2] < 0.0))}
    return sheet, ((0.42, -0.5, 0.42), (0.0, 0.0, 0.1)), measure


def _upright_sheet(name, xs, zs):
    """A grid sheet in the xz-plane (y = 0) over xs by zs, rows of xs from the lowest z up."""
    nx, nz = len(xs), len(zs)
    verts = [(x, 0.0, z) for z in zs for x in xs]
    faces = [(j * nx + i, j * nx + i + 1, (j + 1) * nx + i + 1, (j + 1) * nx + i)
             for j in range(nz - 1) for i in range(nx - 1)]
    return H.link_mesh(name, verts, faces)


def curtain(args):
    table = H.make_box_table(top=0.0, size=1.2)
    table.data.materials.append(_material("Table", (0.12, 0.08, 0.05)))
    nx, nz = 49, 65
    sheet = _upright_sheet("Curtain", np.linspace(-0.15, 0.15, nx), np.linspace(0.10, 0.50, nz))
    sheet.data.materials.append(_material("Linen", (0.75, 0.7, 0.62)))
    pinned = list(range(nx * (nz - 1), nx * nz))
    sheet.vertex_groups.new(name="top").add(pinned, 1.0, "REPLACE")
    s = _common(sheet, table, args, "curtain")
    s.pin_group = "top"
    H.make_igniter(sheet, (0.0, 0.0, 0.10), lit_from=1, radius=args.radius)
    edges = H.mesh_edges(sheet)

    def measure(rest, world):
        hem = np.arange(nx)
        strain = H.edge_strain(rest, world, edges)
        return {"pinned_largest_motion_mm": round(1e3 * float(np.linalg.norm(
                    world[:, pinned] - rest[pinned], axis=2).max()), 3),
                "hem_lowest_m_last": float(world[-1, hem, 2].min()),
                "largest_off_plane_mm": round(1e3 * float(np.abs(world[..., 1]).max()), 2),
                "max_edge_strain": round(float(strain.max()), 4),
                "max_edge_strain_frame": int(np.argmax(strain)) + 1}
    return sheet, ((0.35, -0.7, 0.4), (0.0, 0.0, 0.28)), measure


# --- an artist's trial (the four scenes of the Blender trial, docs/blender.md "An artist's trial") ---
def _collision(ob, friction=50.0):
    """Blender's Collision physics as an artist adds it (Friction 50 = Coulomb 0.5)."""
    ob.modifiers.new("Collision", "COLLISION")
    ob.collision.cloth_friction = friction
    ob.collision.thickness_outer = 0.001
    return ob


def table(args):
    """A4 paper lying on a cube table that has Collision physics (no floor), lit at a corner."""
    import bpy
    top = 0.0
    desk = H.make_box_table(top=top, size=0.6)
    if not args.table_floor:  # else the cube is the Floor Object, to compare
        _collision(desk)
    desk.data.materials.append(_material("Table", (0.12, 0.08, 0.05)))
    sheet = H.make_rect(name="Paper", nx=43, ny=61, z=top + 0.003)
    sheet.data.materials.append(_material("Paper", (0.85, 0.83, 0.78)))
    s = H.setup_bake(sheet, frames=args.frames, cells=args.cells, cache_dir=args.cache, floor=False)
    s.threads, s.material, s.mat_V0 = 0, "paper", args.v0
    s.flame_intensity, s.flame_temperature = 2.0, 1700.0
    if args.table_floor:
        s.floor_mode, s.floor_object = "OBJECT", desk
    H.make_igniter(sheet, (0.105, 0.1485, top + 0.003), lit_from=1, radius=args.radius)

    def measure(rest, world):
        z = world[..., 2] - top
        return {"lowest_above_top_mm_per_25_frames": [round(1e3 * float(f.min()), 2) for f in z[::25]],
                "highest_above_top_mm_per_25_frames": [round(1e3 * float(f.max()), 2) for f in z[::25]],
                "below_top_vertex_frames": int(np.count_nonzero(z < 0.0))}
    return sheet, ((0.3, -0.35, 0.3), (0.0, 0.0, 0.0)), measure


def silk(args):
    """A 30 x 40 cm silk curtain pinned along its top, in a Blender Wind field along +y,
    with a Stretch Limit, lit at the middle of its hem."""
    import bpy
    nx, nz = 31, 41
    xs, zs = np.linspace(-0.15, 0.15, nx), np.linspace(0.10, 0.50, nz)
    verts = [(x, 0.0, z) for z in zs for x in xs]
    faces = [(j * nx + i, j * nx + i + 1, (j + 1) * nx + i + 1, (j + 1) * nx + i)
             for j in range(nz - 1) for i in range(nx - 1)]
    sheet = H.link_mesh("Silk", verts, faces)
    sheet.data.materials.append(_material("Silk", (0.6, 0.15, 0.2)))
    pinned = list(range(nx * (nz - 1), nx * nz))
    sheet.vertex_groups.new(name="top").add(pinned, 1.0, "REPLACE")
    s = H.setup_bake(sheet, frames=args.frames, cells=args.cells, cache_dir=args.cache, floor=False)
    s.threads, s.material, s.mat_V0 = 0, "silk", args.v0
    s.flame_intensity, s.flame_temperature = 2.0, 1700.0
    s.pin_group = "top"
    s.mat_strain_limit = args.stretch_limit
    bpy.ops.object.effector_add(type="WIND", location=(0.0, -0.3, 0.3), rotation=(-math.pi / 2, 0.0, 0.0))
    bpy.context.active_object.field.strength = args.wind
    bpy.context.view_layer.objects.active = sheet
    H.make_igniter(sheet, (0.0, 0.0, 0.10), lit_from=1, radius=args.radius)
    edges = H.mesh_edges(sheet)

    def measure(rest, world):
        strain = H.edge_strain(rest, world, edges)
        return {"max_edge_strain": round(float(strain.max()), 4),
                "max_edge_strain_frame": int(np.argmax(strain)) + 1,
                "edge_strain_per_24_frames": [round(float(x), 4) for x in strain[::24]],
                "largest_downwind_mm": round(1e3 * float(world[..., 1].max()), 1),
                "pinned_largest_motion_mm": round(1e3 * float(np.linalg.norm(
                    world[:, pinned] - rest[pinned], axis=2).max()), 3)}
    return sheet, ((0.55, -0.75, 0.35), (0.0, 0.05, 0.28)), measure


def lantern(args):
    """A paper lantern: Blender's cylinder without caps standing on a table, lit at its bottom
    on the +x side (the camera looks at that side)."""
    desk = H.make_box_table(top=0.0, size=1.2)
    desk.data.materials.append(_material("Table", (0.12, 0.08, 0.05)))
    import bpy
    sheet = H.make_lantern(radius=0.1, depth=0.3, segments=64, cuts=23)
    sheet.data.materials.append(_material("Paper", (0.85, 0.83, 0.78)))
    bpy.context.view_layer.objects.active = sheet
    bpy.ops.object.shade_smooth()  # as an artist would: flat, its 64 faces showed as vertical bands
    s = H.setup_bake(sheet, frames=args.frames, cells=args.cells, cache_dir=args.cache, floor=False)
    s.threads, s.material, s.mat_V0 = 0, "paper", args.v0
    s.flame_intensity, s.flame_temperature = 2.0, 1700.0
    s.floor_mode, s.floor_object = "OBJECT", desk
    H.make_igniter(sheet, (0.1, 0.0, 0.0), lit_from=1, radius=args.radius)
    probes = {"lit": (0.1, 0.0, 0.0), "lit_up10": (0.1, 0.0, 0.1), "side": (0.0, 0.1, 0.0),
              "far": (-0.1, 0.0, 0.0)}

    def measure(rest, world):
        ignite = H.point_attribute(sheet, "thinburn_ignite_time")
        out = {}
        for name, p in probes.items():
            k = int(np.argmin(np.linalg.norm(rest - np.asarray(p), axis=1)))
            out[f"ignite_frame_{name}"] = round(float(ignite[k]), 2) if ignite[k] < 1e8 else None
        lit = ignite < 1e8
        out["ignited_mean_x_m"] = round(float(rest[lit, 0].mean()), 4) if lit.any() else None
        return out
    return sheet, ((0.55, -0.2, 0.3), (0.0, 0.0, 0.12)), measure


def rod(args):
    """A 40 cm cloth dropped from 2 cm above a thin rod (a 1 cm cylinder with Collision) above a table."""
    import bpy
    desk = H.make_box_table(top=0.0, size=1.2)
    desk.data.materials.append(_material("Table", (0.12, 0.08, 0.05)))
    bpy.ops.mesh.primitive_cylinder_add(vertices=24, radius=0.01, depth=0.6, location=(0.0, 0.0, 0.3),
                                        rotation=(0.0, math.pi / 2, 0.0))
    bar = _collision(bpy.context.active_object)
    bar.name = "Rod"
    bar.data.materials.append(_material("Metal", (0.3, 0.3, 0.32)))
    sheet = H.make_sheet(name="Cloth", n=args.n, size=0.4, z=0.33)
    sheet.data.materials.append(_material("Cotton", (0.7, 0.62, 0.5)))
    bpy.context.view_layer.objects.active = sheet
    bpy.ops.object.shade_smooth()
    s = _common(sheet, desk, args, "cloth")
    H.make_igniter(sheet, (0.2, 0.2, 0.33), lit_from=1, radius=args.radius)

    def measure(rest, world):
        d = np.linalg.norm(world[..., 1:] - (0.0, 0.3), axis=2)  # distance from the rod's axis
        return {"nearest_to_axis_minus_r_mm": round(1e3 * float(d.min() - 0.01), 2),
                "inside_rod_vertex_frames": int(np.count_nonzero((d < 0.01) & (np.abs(world[..., 0]) < 0.3))),
                "lowest_z_m_per_24_frames": [round(float(f[:, 2].min()), 4) for f in world[::24]],
                "middle_z_m_last": round(float(world[-1, np.argmin(np.linalg.norm(rest[:, :2], axis=1)), 2]), 4)}
    return sheet, ((0.5, -0.55, 0.45), (0.0, 0.0, 0.2)), measure


def pile(args):
    """A 40 cm cloth standing upright on the table, let go: it collapses into folds (the mesh
    follows the lattice's couples where they fold, docs/lattice.md), lit at a bottom corner."""
    table = H.make_box_table(top=0.0, size=1.2)
    table.data.materials.append(_material("Table", (0.12, 0.08, 0.05)))
    n = args.n
    sheet = _upright_sheet("Cloth", np.linspace(-0.2, 0.2, n), np.linspace(0.02, 0.42, n))
    sheet.data.materials.append(_material("Cotton", (0.7, 0.62, 0.5)))
    import bpy
    bpy.ops.object.shade_smooth()
    _common(sheet, table, args, "cloth")
    H.make_igniter(sheet, (-0.2, 0.0, 0.02), lit_from=1, radius=args.radius)
    edges = H.mesh_edges(sheet)

    def measure(rest, world):
        l0 = np.linalg.norm(rest[edges[:, 0]] - rest[edges[:, 1]], axis=1)
        strain = [np.abs(np.linalg.norm(f[edges[:, 0]] - f[edges[:, 1]], axis=1) / l0 - 1.0) for f in world]
        return {"highest_m_per_24_frames": [round(float(f[:, 2].max()), 4) for f in world[::24]],
                "edge_strain_p99_per_24_frames": [round(float(np.percentile(s_, 99)), 4) for s_ in strain[::24]],
                "max_edge_strain": round(float(max(s_.max() for s_ in strain)), 4),
                "below_table_vertex_frames": int(np.count_nonzero(world[..., 2] < 0.0))}
    return sheet, ((0.55, -0.6, 0.35), (0.0, 0.0, 0.08)), measure


def corners(args):
    """A 60 cm silk held at its two top corners (vertex group "corners", Pin Group), Motion
    Detail --lattice, lit at the middle of its hem: the lattice's pinned corners (docs/dynamics.md
    §3.4, "Corners")."""
    import bpy
    n = args.n
    xs, zs = np.linspace(-0.3, 0.3, n), np.linspace(0.2, 0.8, n)
    sheet = _upright_sheet("Silk", xs, zs)
    sheet.data.materials.append(_material("Silk", (0.6, 0.15, 0.2)))
    bpy.context.view_layer.objects.active = sheet
    bpy.ops.object.shade_smooth()
    pins = [n * (n - 1), n * n - 1]
    sheet.vertex_groups.new(name="corners").add(pins, 1.0, "REPLACE")
    s = H.setup_bake(sheet, frames=args.frames, cells=args.cells, cache_dir=args.cache, floor=False)
    s.threads, s.material, s.lattice, s.mat_V0 = 0, "silk", args.lattice, args.v0
    s.flame_intensity, s.flame_temperature = 2.0, 1700.0
    s.pin_group = "corners"
    H.make_igniter(sheet, (0.0, 0.0, 0.2), lit_from=1, radius=args.radius)
    edges = H.mesh_edges(sheet)
    quads = np.array([list(p.vertices) for p in sheet.data.polygons])
    # The quads' sides and both diagonals: Blender renders each quad as two triangles.
    pairs = np.concatenate([edges, quads[:, [0, 2]], quads[:, [1, 3]]])

    def measure(rest, world):
        strain = H.edge_strain(rest, world, edges)  # per frame, the largest |l / L - 1|
        mid = 0.5 * (rest[pairs[:, 0]] + rest[pairs[:, 1]])
        near = np.linalg.norm(mid[:, None, :] - rest[pins][None, :, :], axis=2).min(axis=1) < 0.03
        length = lambda x: np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1)  # noqa: E731
        base = length(rest)
        by_pins = max(float(np.abs(length(f)[near] / base[near] - 1.0).max()) for f in world)
        return {"max_edge_strain": round(float(strain.max()), 4),
                "max_strain_within_3cm_of_the_pins_sides_and_diagonals": round(by_pins, 4),
                "pinned_largest_motion_mm": round(1e3 * float(np.linalg.norm(world[:, pins] - rest[pins], axis=2).max()), 3)}
    return sheet, ((0.0, -1.6, 0.5), (0.0, 0.0, 0.5)), measure


SCENES = {"drape": drape, "curtain": curtain, "table": table, "silk": silk, "lantern": lantern,
          "rod": rod, "pile": pile, "corners": corners}


def bake_and_measure(name, args):
    import bpy
    addon = sys.modules[ADDON_NAME]
    sheet, cam, measure = SCENES[name](args)
    rest = H.world_vertices(sheet)
    t0 = time.perf_counter()
    job = addon.job.BakeJob(bpy.context, sheet)
    job.run()
    info = {"scene": name, "frames": args.frames, "cells": args.cells, "lattice": args.lattice,
            "vertices": len(rest), "bake_s": round(time.perf_counter() - t0, 1),
            "message": job.message, "warnings": list(job.warnings),
            "colliders": list(getattr(job, "colliders", [])),
            # the bake's stretch meter: edges past 1 % measured along the surface (docs/blender.md)
            "max_strain_meter": None if job.max_strain is None else round(float(job.max_strain), 4),
            "max_strain_meter_frame": job.max_strain_frame}
    _, frames = addon.cache.read_pc2(H.cache_file(args.cache, sheet.name + ".pc2"))
    mw = np.array(sheet.matrix_world, dtype=np.float64)
    world = frames.astype(np.float64) @ mw[:3, :3].T + mw[:3, 3]
    ignite = H.point_attribute(sheet, "thinburn_ignite_time")
    info["ignited"] = int(np.count_nonzero(ignite < 1e8))
    info.update(measure(rest, world))
    info["unburnt_edge_strain_p99_per_24_frames"] = _unburnt_p99(sheet, rest, world, ignite)
    if args.export_scene is not None:  # the scene as a file: python scripts/replay_strain.py FILE
        args.export_scene.mkdir(parents=True, exist_ok=True)
        info["scene_file"] = addon.scene_export.write_scene(sheet, str(args.export_scene / f"{name}.npz"))
    print(json.dumps(info, indent=1), flush=True)
    return cam


def render_without_addon(name, args, work):
    """Save the .blend, disable the add-on, reopen the file and render again: what the bake
    leaves must render in a Blender that does not have ThinBurn."""
    import addon_utils
    import bpy
    path = work / f"{name}.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    addon_utils.disable(ADDON_NAME, default_set=True)
    try:
        bpy.ops.wm.open_mainfile(filepath=str(path))
        render_frames(args.render, lambda frame: args.out / f"drape_{name}{args.suffix}_noaddon_{frame:03d}.png")
    finally:
        addon_utils.enable(ADDON_NAME, default_set=True)
    for frame in args.render:
        print(f"frame {frame}: largest pixel difference without the add-on "
              f"{_pixel_difference(args.out, f'{name}{args.suffix}', frame)} (of 255)", flush=True)


def _pixel_difference(folder, stem, frame) -> int:
    from PIL import Image
    with_addon, without = (np.asarray(Image.open(folder / f"drape_{stem}{tag}_{frame:03d}.png"), dtype=np.int16)
                           for tag in ("", "_noaddon"))
    return int(np.abs(with_addon - without).max())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "images")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--samples", type=int, default=16)
    ap.add_argument("--frames", type=int, default=144, help="frames to bake (24 fps)")
    ap.add_argument("--stretch-limit", type=float, default=2.0, help="silk: Stretch Limit, %%")
    ap.add_argument("--wind", type=float, default=2.0, help="silk: the Wind field's Strength")
    ap.add_argument("--table-floor", action="store_true",
                    help="table: the cube is the sheet's Floor Object instead of a Collision object")
    ap.add_argument("--export-scene", type=Path, default=None, metavar="DIR",
                    help="also write each scene as a scene file DIR/<scene>.npz (thinburn.scenefile)")
    ap.add_argument("--without-addon", action="store_true",
                    help="also save, disable the add-on, reopen and render (drape_<scene>_noaddon_<frame>)")
    ap.add_argument("--render", type=int, nargs="*", default=[12, 48, 144], help="frames to render")
    ap.add_argument("--cells", type=int, default=48, help="Fire Detail")
    ap.add_argument("--lattice", type=int, default=16, help="Motion Detail")
    ap.add_argument("--n", type=int, default=61, help="the drape's cloth: n x n vertices")
    ap.add_argument("--v0", type=float, default=25.0, help="spread speed, mm/s (paper: 3.5)")
    ap.add_argument("--suffix", default="", help="added to the pictures' names (drape_<scene><suffix>_<frame>)")
    ap.add_argument("--radius", type=float, default=0.02, help="igniter radius, m")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix="thinburn-drape-"))
    args.cache = work / "cache"
    try:
        enable_addon(work / "user")
        import bpy
        for name in args.scenes:
            bpy.ops.wm.read_homefile(use_empty=True)
            cam = bake_and_measure(name, args)
            if not args.render:
                continue
            camera_and_world(cam, args.width, args.samples)
            render_frames(args.render, lambda frame: args.out / f"drape_{name}{args.suffix}_{frame:03d}.png")
            if args.without_addon:
                render_without_addon(name, args, work)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
