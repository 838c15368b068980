"""Scenes set up as an artist would, baked by the add-on and from their exported scene file
outside Blender (tests/blender/test_scene_export.py; scripts/scene_export_agreement.py prints
how far the two bakes are apart).

bpy is imported inside the functions: the caller sets Blender's user folders first.
"""
from __future__ import annotations

import numpy as np

from blender_helpers import cache_file, make_igniter, make_sheet, point_attribute, setup_bake

FRAMES = 16


def keyframe(owner, path, values: dict) -> None:
    """Keyframe ``owner.path`` (a dotted property path) at {frame: value}."""
    head, _, attr = path.rpartition(".")
    target = owner.path_resolve(head) if head else owner
    for frame, value in values.items():
        setattr(target, attr, value)
        owner.keyframe_insert(path, frame=frame)


def move_to(collection, ob) -> None:
    for c in list(ob.users_collection):
        c.objects.unlink(ob)
    collection.objects.link(ob)


def cube(location, scale, name):
    import bpy
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=location)
    ob = bpy.context.active_object
    ob.name, ob.scale = name, scale
    bpy.context.view_layer.update()
    return ob


def igniters_scene(cache_dir):
    """A sheet lit by a moving Empty, a moving mesh igniter and a Flame, with Heat Ignites,
    Burn Duration, keyframed Buoyancy and Crumple Amount, painted Speed and Ignite maps."""
    sheet = make_sheet(n=17, size=0.2, z=0.0)
    s = setup_bake(sheet, frames=FRAMES, cells=16, cache_dir=cache_dir)
    s.heat_ignites = True
    s.burn_duration = 3.0  # s: the whole burn's target (finish_within)
    keyframe(sheet, "thinburn.buoyancy", {1: 1.0, 8: 4.0})
    keyframe(sheet, "thinburn.crumple_gain", {1: 1.0, 10: 2.5})
    fast = sheet.vertex_groups.new(name="fast")  # a painted Speed map: the left half at half speed
    for i, v in enumerate(sheet.data.vertices):
        fast.add([i], 1.0 if v.co.x > 0.0 else 0.5, "REPLACE")
    s.speed_map = "fast"
    spark = sheet.vertex_groups.new(name="spark")  # a painted Ignite map: the corner (-0.1, 0.1)
    spark.add([i for i, v in enumerate(sheet.data.vertices) if v.co.x < -0.07 and v.co.y > 0.07],
              1.0, "REPLACE")
    s.ignite_map, s.ignite_frame = "spark", 7
    # An Empty that moves while lit, from frame 3 (ignitions along its path).
    torch = make_igniter(sheet, (-0.1, -0.1, 0.0), lit_from=3, radius=0.03, name="Torch")
    keyframe(torch, "location", {3: (-0.1, -0.1, 0.0), 7: (0.0, -0.1, 0.0)})
    # A mesh igniter, a bar over the far edge, lit from frame 5 and moving.
    bar = cube((0.1, 0.0, 0.01), (0.02, 0.06, 0.01), "Bar")
    move_to(s.igniter_collection, bar)
    bar.thinburn_igniter.radius = 0.005
    keyframe(bar, "thinburn_igniter.strength", {4: 0.0, 5: 1.0})
    keyframe(bar, "location", {5: (0.1, 0.0, 0.01), 12: (0.1, 0.05, 0.01)})
    # A Flame under the middle, lit from frame 2 to 11.
    candle = make_igniter(sheet, (0.0, 0.0, -0.01), lit_from=2, radius=0.01, name="Candle")
    candle.thinburn_igniter.kind = "FLAME"
    keyframe(candle, "thinburn_igniter.strength", {11: 1.0, 12: 0.0})
    return sheet


def collider_scene(cache_dir):
    """A cloth sheet carried along x by its keyframed location, falling onto a Collision box
    that slides along y with keyframed Friction, in a gusty Wind along +x and a Turbulence."""
    import bpy
    sheet = make_sheet(n=17, size=0.2, z=0.06)
    s = setup_bake(sheet, frames=FRAMES, cells=16, cache_dir=cache_dir, floor=False)
    s.material = "cloth"
    keyframe(sheet, "location", {1: (0.0, 0.0, 0.0), FRAMES: (0.03, 0.0, 0.0)})
    make_igniter(sheet, (-0.1, -0.1, 0.06), lit_from=1, radius=0.03)
    box = cube((0.0, 0.0, 0.0), (0.12, 0.12, 0.08), "Box")  # top at 4 cm
    box.modifiers.new("Collision", "COLLISION")
    box.collision.thickness_outer = 0.002
    keyframe(box, "location", {1: (0.0, 0.0, 0.0), FRAMES: (0.0, 0.02, 0.0)})
    keyframe(box, "collision.cloth_friction", {1: 50.0, 8: 10.0})
    bpy.ops.object.effector_add(type="WIND", rotation=(0.0, np.pi / 2, 0.0))  # along +x
    wind = bpy.context.active_object
    wind.field.strength, wind.field.noise = 0.5, 1.0  # a gusty wind: random per point and frame
    wind.field.seed = 1  # a new field draws its own seed: set, so every run bakes alike
    bpy.ops.object.effector_add(type="TURBULENCE", location=(0.0, 0.1, 0.1))
    turbulence = bpy.context.active_object
    turbulence.field.strength, turbulence.field.seed = 0.3, 2
    return sheet


def _start_matrix(sheet) -> np.ndarray:
    import bpy
    scene = bpy.context.scene
    now = scene.frame_current
    scene.frame_set(sheet.thinburn.frame_start)
    m = np.array(sheet.matrix_world, dtype=np.float64)
    scene.frame_set(now)
    return m


def bake_both(addon, sheet, folder):
    """(scene spec, the add-on's bake, the exported file's bake outside Blender), each bake as
    (positions in the sheet's object space per frame (float32), ignition frames, burnout
    frames) per vertex. ``folder`` is the sheet's Cache Folder; the file goes beside it."""
    import bpy
    from thinburn import scenefile, wedge
    bpy.context.view_layer.objects.active = sheet
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    _, pc2 = addon.cache.read_pc2(cache_file(folder, f"{sheet.name}.pc2"))
    inside = (pc2, point_attribute(sheet, "thinburn_ignite_time"),
              point_attribute(sheet, "thinburn_burnout_time"))
    spec = scenefile.load_scene(addon.scene_export.write_scene(sheet, str(folder / "scene.npz")))
    sim, _, fps, frames = wedge.simulation_for(spec, {})
    inv = np.linalg.inv(_start_matrix(sheet))  # the cache: the bake frame in object space
    out = []
    wedge.run_frames(sim, spec, fps, frames,
                     lambda k, s: out.append(s.vertex_positions() @ inv[:3, :3].T + inv[:3, 3]))
    start = float(sheet.thinburn.frame_start)
    outside = (np.asarray(out, dtype=np.float32),
               addon.cache.seconds_to_frames(sim.vertex_ignition_times(), start, fps),
               addon.cache.seconds_to_frames(sim.vertex_burnout_times(), start, fps))
    return spec, inside, outside


def differences(inside, outside) -> dict:
    """The largest position difference (m) and how many vertices' ignition and burnout frames
    differ, with the frame the positions first differ at (None: never)."""
    d = np.abs(inside[0].astype(np.float64) - outside[0].astype(np.float64))
    d = d.reshape(len(d), -1).max(axis=1)
    first = np.flatnonzero(d > 0)
    return {"positions_m": float(d.max()), "first_frame_index": int(first[0]) if len(first) else None,
            "ignition_differ": int(np.count_nonzero(inside[1] != outside[1])),
            "burnout_differ": int(np.count_nonzero(inside[2] != outside[2]))}
