"""What *Keep Every* (the compact cache) saves and costs: bytes per frame of the sheet's PC2
file and the largest position error of what Blender plays (the Mesh Cache modifier blending the
kept frames) against the full cache, for a curtain that burns in a gusty wind.

    python scripts/compact_cache.py [--steps 1 2 4 8] [--frames 96] [--n 61]

Needs bpy and thinburn in one environment (as the Blender tests do). Prints one line per step
and a JSON summary; docs/blender.md quotes a run.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from blender_session import ROOT, enable_addon  # scripts/ is on the path when a script runs

sys.path.insert(0, str(ROOT / "tests" / "blender"))
import blender_helpers as H  # noqa: E402  (the scene builders the tests use)


def curtain(n: int, frames: int):
    """A 0.5 × 0.7 m curtain of n × (1.4 n) vertices pinned along its top, lit at a bottom
    corner, in a noisy Wind field with a Turbulence field."""
    import bpy
    sheet = H.make_rect("Curtain", width=0.5, height=0.7, nx=n, ny=int(1.4 * n), z=0.0)
    sheet.rotation_euler = (math.pi / 2, 0.0, 0.0)  # hanging in the XZ plane
    sheet.location = (0.0, 0.0, 0.1)
    bpy.context.view_layer.update()
    s = H.setup_bake(sheet, frames=frames, cells=64, floor=False)
    s.material = "curtain"
    s.mat_V0 = 0.03
    top = max((sheet.matrix_world @ v.co).z for v in sheet.data.vertices)
    group = sheet.vertex_groups.new(name="Top")
    group.add([v.index for v in sheet.data.vertices
               if (sheet.matrix_world @ v.co).z > top - 1e-6], 1.0, "REPLACE")
    s.pin_group = "Top"
    corner = min(sheet.data.vertices, key=lambda v: (sheet.matrix_world @ v.co).z
                 + (sheet.matrix_world @ v.co).x)
    H.make_igniter(sheet, tuple(sheet.matrix_world @ corner.co), lit_from=1, radius=0.03)
    bpy.ops.object.effector_add(type="WIND", location=(0.0, -0.5, 0.4),
                                rotation=(-math.pi / 2, 0.0, 0.0))  # blows along +y
    wind = bpy.context.active_object
    wind.field.strength, wind.field.noise, wind.field.shape = 1.5, 1.0, "POINT"
    bpy.ops.object.effector_add(type="TURBULENCE", location=(0.0, 0.0, 0.4))
    turb = bpy.context.active_object
    turb.field.strength, turb.field.size = 1.0, 0.2
    bpy.context.view_layer.objects.active = sheet
    return sheet


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, nargs="+", default=[1, 2, 4, 8])
    ap.add_argument("--frames", type=int, default=96)
    ap.add_argument("--n", type=int, default=61, help="vertices across the curtain")
    args = ap.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="thinburn-compact-"))
    enable_addon(work / "user")
    import bpy
    addon = sys.modules["thinburn_addon"]
    bpy.ops.wm.read_homefile(use_empty=True)
    sheet = curtain(args.n, args.frames)
    results, full = [], None
    for step in args.steps:
        sheet.thinburn.cache_dir = str(work / f"step{step}")
        sheet.thinburn.cache_step = step
        t0 = time.perf_counter()
        addon.operators.bake_now(bpy.context, sheet)
        bake_s = time.perf_counter() - t0
        path = work / f"step{step}" / "untitled" / "Curtain.pc2"
        if full is None:
            full = addon.cache.read_pc2(path)[1]  # the first step given is the reference
        played = np.stack([H.evaluated_positions(sheet, 1 + i) for i in range(args.frames)])
        err = np.linalg.norm(played - full, axis=2)
        moved = float(np.linalg.norm(full - full[0], axis=2).max())
        row = dict(step=step, vertices=len(sheet.data.vertices), frames=args.frames,
                   bytes=os.path.getsize(path), bytes_per_frame=os.path.getsize(path) / args.frames,
                   max_error_mm=1000 * float(err.max()), mean_error_mm=1000 * float(err.mean()),
                   max_motion_mm=1000 * moved, bake_s=round(bake_s, 1))
        results.append(row)
        print(f"Keep Every {step}: {row['bytes_per_frame']:.0f} bytes/frame, max error "
              f"{row['max_error_mm']:.2f} mm (mean {row['mean_error_mm']:.3f} mm; vertices move "
              f"up to {row['max_motion_mm']:.0f} mm), bake {bake_s:.1f} s", flush=True)
    print(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
