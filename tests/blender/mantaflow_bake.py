"""Bake a burning sheet, then Mantaflow fire from it (Add Mantaflow Fire), in this process.

Run by tests/blender/test_mantaflow.py in a subprocess (Mantaflow in bpy-as-a-module can abort
the process it runs in; the test must survive that): it prints one JSON line with what the
test checks. Needs BLENDER_USER_RESOURCES with the add-on linked (tests/blender/conftest.py
sets it up and the subprocess inherits it). Usage: python mantaflow_bake.py CACHE_DIR
"""
from __future__ import annotations

import json
import os
import sys

import numpy as np

import bpy

from blender_helpers import enable_legacy, make_igniter, make_sheet, point_attribute, setup_bake

FRAMES = 24
RESOLUTION = 32
BAKE_FROM = 6  # the fluid bakes frames BAKE_FROM..FRAMES (the fire has a band by then)
MID = 14  # a frame between, to see the flames move with the band
FAR = 0.05  # m: "far from the fire" = this far from every vertex lit so far
IGNITED = np.array([-0.1, -0.1])  # the igniter's corner of the sheet


def _grid(domain, name, frame):
    bpy.context.scene.frame_set(frame)
    ds = domain.evaluated_get(bpy.context.evaluated_depsgraph_get()).modifiers["Fluid"].domain_settings
    res = np.array(ds.domain_resolution)
    return np.array(getattr(ds, name), dtype=np.float64).reshape(res[2], res[1], res[0]), res


def main(cache_dir):
    addon = enable_legacy()
    bpy.ops.wm.read_homefile(use_empty=True)
    sheet = make_sheet(n=17, size=0.2, z=0.0)
    settings = setup_bake(sheet, frames=FRAMES, cells=32, cache_dir=cache_dir)
    settings.crumple = False
    settings.mat_V0 = 20.0
    settings.mat_burn_duration = 0.5
    settings.mantaflow_resolution = RESOLUTION
    make_igniter(sheet, (-0.1, -0.1, 0.0), lit_from=1, radius=0.06)
    bpy.context.view_layer.objects.active = sheet
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    manta = sys.modules.get("manta")  # imported with bpy in bpy-as-a-module
    whole_before = hasattr(getattr(manta, "LevelsetGrid", None), "setConst")
    assert bpy.ops.thinburn.add_mantaflow_fire() == {"FINISHED"}
    domain = settings.mantaflow_domain
    name = domain.name
    flow = sheet.modifiers["ThinBurn Flow"].flow_settings
    ds = domain.modifiers["Fluid"].domain_settings
    ds.cache_frame_start = BAKE_FROM
    corners = np.array([domain.matrix_world @ v.co for v in domain.data.vertices])
    out = {
        "flow": [flow.flow_type, flow.flow_source, flow.use_plane_init, flow.density_vertex_group],
        "stack": [md.name for md in sheet.modifiers],
        "domain_low": corners.min(axis=0).tolist(), "domain_high": corners.max(axis=0).tolist(),
        "cache": bpy.path.abspath(ds.cache_directory), "resolution": ds.resolution_max,
        "whole_before": whole_before,
        "whole_after": hasattr(getattr(manta, "LevelsetGrid", None), "setConst"),
        "mended_again": addon.mantaflow.prepare_solver(bpy.context.scene),
    }
    addon.mantaflow.bake(domain, bpy.context.scene)
    out["files"] = sorted(os.listdir(os.path.join(out["cache"], "data")))
    # the flame and smoke over the burning band vs over the sheet far from the fire
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    verts = np.array([v.co for v in sheet.data.vertices])
    ignite = point_attribute(sheet, "thinburn_ignite_time")
    burnout = point_attribute(sheet, "thinburn_burnout_time")
    for frame in (MID, FRAMES):
        flame, res = _grid(domain, "flame_grid", frame)
        density, _ = _grid(domain, "density_grid", frame)
        cell = (hi - lo) / res
        band = (ignite <= frame) & (frame < burnout)
        lit = verts[ignite <= frame]
        gap = np.linalg.norm(verts[:, None, :] - lit[None, :, :], axis=2).min(axis=1)
        far = gap > FAR
        ij = np.floor((verts[:, :2] - lo[:2]) / cell[:2]).astype(int)
        k0 = int((verts[0, 2] - lo[2]) / cell[2])
        columns = lambda g, m: g[k0:k0 + 4, ij[m, 1], ij[m, 0]]  # noqa: E731  4 voxels up from the sheet
        xyz = np.argwhere(flame > 0.1 * flame.max())[:, ::-1]  # (x, y, z) voxels of the flames
        centre = lo[:2] + (xyz[:, :2].mean(axis=0) + 0.5) * cell[:2]
        out[str(frame)] = dict(
            band=int(band.sum()), far=int(far.sum()),
            flame_band=float(columns(flame, band).max()), flame_far=float(columns(flame, far).max()),
            density_band=float(columns(density, band).max()),
            density_far=float(columns(density, far).max()),
            flame_from_corner=float(np.linalg.norm(centre - IGNITED)),
            band_from_corner=float(np.linalg.norm(verts[band, :2] - IGNITED, axis=1).mean()))
    bpy.context.view_layer.objects.active = sheet
    assert bpy.ops.thinburn.free_bake() == {"FINISHED"}
    out["after_free"] = {"domain": name in bpy.data.objects,
                         "cache": os.path.isdir(out["cache"]),
                         "flow": "ThinBurn Flow" in sheet.modifiers}
    bpy.ops.wm.read_homefile(use_empty=True)  # free the solvers before Python shuts down
    print("RESULT " + json.dumps(out), flush=True)


if __name__ == "__main__":
    main(sys.argv[1])
