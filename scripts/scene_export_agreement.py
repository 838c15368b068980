#!/usr/bin/env python3
"""How far a bake of an exported scene file is from the add-on's own bake of the scene.

    python scripts/scene_export_agreement.py

Needs bpy (pip install bpy, CPython 3.11) and thinburn installed in the same environment.
Builds the two scenes of tests/blender/test_scene_export.py (tests/blender/export_scenes.py:
igniters of every kind with Heat Ignites, Burn Duration, keyframed motion and painted maps;
a moving cloth sheet on a sliding Collision box in a gusty Wind and a Turbulence), bakes each
with the
add-on, exports it, bakes the file with thinburn.wedge, and prints per scene the largest
position difference (m), the first frame index at which positions differ, and how many
vertices' ignition and burnout frames differ, and where the sheet's middle vertex ends (object
space, m); then the same second scene without its force fields (to show they move it).
"""
from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

from blender_session import ROOT, enable_addon


def without_fields(scene):
    def build(cache_dir):
        import bpy
        sheet = scene(cache_dir)
        for ob in [o for o in bpy.data.objects if o.field is not None and o.field.type != "NONE"]:
            bpy.data.objects.remove(ob)
        return sheet
    return build


def main() -> int:
    work = Path(tempfile.mkdtemp(prefix="thinburn-export-agreement-"))
    addon = enable_addon(work / "user")
    sys.path.insert(0, str(ROOT / "tests" / "blender"))  # the scenes the tests bake
    import bpy
    import export_scenes as scenes

    rows = {}
    for name, build in (("igniters", scenes.igniters_scene), ("collider", scenes.collider_scene),
                        ("collider without fields", without_fields(scenes.collider_scene))):
        bpy.ops.wm.read_homefile(use_empty=True)
        folder = work / name.replace(" ", "_")
        sheet = build(folder)
        _, inside, outside = scenes.bake_both(addon, sheet, folder)
        rows[name] = scenes.differences(inside, outside)
        rows[name]["middle_end_m"] = inside[0][-1][len(inside[0][-1]) // 2].astype(float).round(4).tolist()
        print(f"{name:24s} {json.dumps(rows[name])}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
