"""A scene exported from Blender (File > Export > ThinBurn Scene) and baked outside it gives
what the add-on's own bake gives: igniters of every kind and their timing, collision objects,
keyframed motion parameters, painted maps, Heat Ignites, Burn Duration, a moving sheet; and
what a scene file cannot hold is said (ExportWarning), not dropped."""
from __future__ import annotations

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytestmark = pytest.mark.blender

from blender_helpers import (cache_file, make_igniter, make_sheet, point_attribute,  # noqa: E402
                             setup_bake)

FRAMES = 16


def _keyframe(owner, path, values: dict) -> None:
    """Keyframe ``owner.path`` (a dotted property path) at {frame: value}."""
    head, _, attr = path.rpartition(".")
    target = owner.path_resolve(head) if head else owner
    for frame, value in values.items():
        setattr(target, attr, value)
        owner.keyframe_insert(path, frame=frame)


def _move_to(collection, ob) -> None:
    for c in list(ob.users_collection):
        c.objects.unlink(ob)
    collection.objects.link(ob)


def _cube(location, scale, name):
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=location)
    ob = bpy.context.active_object
    ob.name, ob.scale = name, scale
    bpy.context.view_layer.update()
    return ob


def _bake_both(addon, sheet, tmp_path):
    """(the add-on's bake, the exported file's bake outside Blender), each as (positions in
    the sheet's object space per frame (float32), ignition frames, burnout frames)."""
    from thinburn import scenefile, wedge
    bpy.context.view_layer.objects.active = sheet
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    _, pc2 = addon.cache.read_pc2(cache_file(tmp_path / "cache", "Sheet.pc2"))
    inside = (pc2, point_attribute(sheet, "thinburn_ignite_time"),
              point_attribute(sheet, "thinburn_burnout_time"))
    spec = scenefile.load_scene(addon.scene_export.write_scene(sheet, str(tmp_path / "scene.npz")))
    sim, _, fps, frames = wedge.simulation_for(spec, {})
    inv = np.linalg.inv(np.array(sheet.matrix_world if spec.to_world is None else _start_matrix(sheet)))
    out = []
    wedge.run_frames(sim, spec, fps, frames,
                     lambda k, s: out.append(s.vertex_positions() @ inv[:3, :3].T + inv[:3, 3]))
    start = float(sheet.thinburn.frame_start)
    outside = (np.asarray(out, dtype=np.float32),
               addon.cache.seconds_to_frames(sim.vertex_ignition_times(), start, fps),
               addon.cache.seconds_to_frames(sim.vertex_burnout_times(), start, fps))
    return spec, inside, outside


def _start_matrix(sheet):
    scene = bpy.context.scene
    now = scene.frame_current
    scene.frame_set(sheet.thinburn.frame_start)
    m = np.array(sheet.matrix_world)
    scene.frame_set(now)
    return m


def _assert_same(inside, outside, atol=0.0):
    """Positions within ``atol`` (m), ignition and burnout frames of every vertex equal."""
    for a, b, tol in zip(inside, outside, (atol, 0.0, 0.0)):
        np.testing.assert_allclose(b, a, rtol=0.0, atol=tol)


def test_igniters_of_every_kind_keyframed_motion_maps_and_heat_bake_alike(addon, tmp_path):
    sheet = make_sheet(n=17, size=0.2, z=0.0)
    s = setup_bake(sheet, frames=FRAMES, cells=16, cache_dir=tmp_path / "cache")
    s.heat_ignites = True
    s.burn_duration = 3.0  # s: the whole burn's target (finish_within)
    _keyframe(sheet, "thinburn.buoyancy", {1: 1.0, 8: 4.0})       # keyframed motion parameters
    _keyframe(sheet, "thinburn.crumple_gain", {1: 1.0, 10: 2.5})
    fast = sheet.vertex_groups.new(name="fast")    # a painted Speed map: the left half at half speed
    for i, v in enumerate(sheet.data.vertices):
        fast.add([i], 1.0 if v.co.x > 0.0 else 0.5, "REPLACE")
    s.speed_map = "fast"
    spark = sheet.vertex_groups.new(name="spark")                 # a painted Ignite map
    spark.add([i for i, v in enumerate(sheet.data.vertices)       # the corner (-0.1, 0.1)
               if v.co.x < -0.07 and v.co.y > 0.07], 1.0, "REPLACE")
    s.ignite_map, s.ignite_frame = "spark", 7
    # An Empty that moves while lit, from frame 3 (ignitions along its path).
    torch = make_igniter(sheet, (-0.1, -0.1, 0.0), lit_from=3, radius=0.03, name="Torch")
    _keyframe(torch, "location", {3: (-0.1, -0.1, 0.0), 7: (0.0, -0.1, 0.0)})
    coll = s.igniter_collection
    # A mesh igniter, a bar over the far edge, lit from frame 5 and moving.
    bar = _cube((0.1, 0.0, 0.01), (0.02, 0.06, 0.01), "Bar")
    _move_to(coll, bar)
    bar.thinburn_igniter.radius = 0.005
    _keyframe(bar, "thinburn_igniter.strength", {4: 0.0, 5: 1.0})
    _keyframe(bar, "location", {5: (0.1, 0.0, 0.01), 12: (0.1, 0.05, 0.01)})
    # A Flame under the middle, lit from frame 2 to 11.
    candle = make_igniter(sheet, (0.0, 0.0, -0.01), lit_from=2, radius=0.01, name="Candle")
    candle.thinburn_igniter.kind = "FLAME"
    _keyframe(candle, "thinburn_igniter.strength", {11: 1.0, 12: 0.0})

    spec, inside, outside = _bake_both(addon, sheet, tmp_path)
    # Measured: bit-identical (the same core calls in the same order), so the tolerance is 0.
    assert spec.heat_ignites and spec.finish_within == 3.0 and spec.ignite_frame == 6
    assert set(spec.maps) == {"speed_map", "ignite_map"}
    assert spec.surfaces and spec.surfaces[0]["time"] == pytest.approx(4 / 24)  # frame 5
    assert sum(len(rows) > 0 for rows in spec.flames) == 10                     # frames 2-11
    assert spec.dynamics[-1]["buoyancy"] == 4.0 and spec.dynamics[0]["crumple_gain"] == 1.0
    lit = inside[1] < addon.cache.NEVER_FRAME
    assert lit[0] and lit[16 * 17] and lit.sum() > 20  # the torch's corner, the painted spark
    assert np.ptp(inside[0][-1][:, 2]) > 1e-4  # it moves (curls), so positions say something
    _assert_same(inside, outside)


def test_a_collision_object_wind_and_a_moving_sheet_bake_alike(addon, tmp_path):
    sheet = make_sheet(n=17, size=0.2, z=0.06)
    s = setup_bake(sheet, frames=FRAMES, cells=16, cache_dir=tmp_path / "cache", floor=False)
    s.material = "cloth"
    _keyframe(sheet, "location", {1: (0.0, 0.0, 0.0), FRAMES: (0.03, 0.0, 0.0)})  # carried along x
    make_igniter(sheet, (-0.1, -0.1, 0.06), lit_from=1, radius=0.03)
    # A closed box under the sheet that it falls on, sliding along y, its friction keyframed.
    box = _cube((0.0, 0.0, 0.0), (0.12, 0.12, 0.08), "Box")
    box.modifiers.new("Collision", "COLLISION")
    box.collision.thickness_outer = 0.002
    _keyframe(box, "location", {1: (0.0, 0.0, 0.0), FRAMES: (0.0, 0.02, 0.0)})
    _keyframe(box, "collision.cloth_friction", {1: 50.0, 8: 10.0})
    # A uniform wind (Wind: no falloff, no noise) along +x.
    bpy.ops.object.effector_add(type="WIND", rotation=(0.0, np.pi / 2, 0.0))
    bpy.context.active_object.field.strength = 0.5

    spec, inside, outside = _bake_both(addon, sheet, tmp_path)
    assert [c["name"] for c in spec.colliders] == ["Box"]
    box_y = [t[1] for t in spec.colliders[0]["translation"]]
    assert box_y[0] == pytest.approx(0.0) and box_y[-1] == pytest.approx(0.02, abs=1e-6)
    assert spec.colliders[0]["friction"][0] == pytest.approx(0.5)
    assert spec.colliders[0]["friction"][-1] == pytest.approx(0.1)
    assert spec.to_world is not None and spec.to_world[-1][0][3] == pytest.approx(0.03)
    assert spec.wind_field and np.linalg.norm(spec.wind[0]) > 0.1
    # The sheet falls onto the box (top 4 cm) and rides on it: in the sheet's own frame the box
    # slides by (-3, +2) cm, the sheet's middle by (-2.8, +2.2) cm (measured), at 5.2-5.4 cm.
    middle = inside[0][-1][8 * 17 + 8]
    assert 0.04 < middle[2] < 0.058
    np.testing.assert_allclose(middle[:2], (-0.03, 0.02), atol=0.005)
    # Measured: positions differ by at most 7.5e-9 m (one float32 step at 6 cm, from frame 7
    # on) and the frames not at all; without the wind they are bit-identical. The bake blows
    # the wind per lattice vertex and takes their mean, the file holds the one vector, which
    # rounds differently. Tolerance 5e-8 m, the frames exact.
    _assert_same(inside, outside, atol=5e-8)


def test_what_a_scene_file_cannot_hold_is_said(addon, tmp_path):
    sheet = make_sheet(n=9, size=0.2, z=0.0)
    s = setup_bake(sheet, frames=6, cells=16, cache_dir=tmp_path / "cache")
    make_igniter(sheet, (-0.1, -0.1, 0.0), lit_from=1)
    s.heat_ignites = True
    other = make_sheet(name="Other", n=9, size=0.2, z=0.01)  # close enough to be heated
    setup_bake(other, frames=6, cells=16).heat_ignites = True
    bpy.ops.object.effector_add(type="WIND", location=(0.3, 0.0, 0.0))
    gust = bpy.context.active_object
    gust.name = "Gust"
    gust.field.noise = 2.0
    # A collision object that swells (a keyframed Displace): the file holds one shape.
    blob = _cube((0.0, 0.0, -0.2), (0.1, 0.1, 0.1), "Blob")
    blob.modifiers.new("Swell", "DISPLACE")
    _keyframe(blob, 'modifiers["Swell"].strength', {1: 0.0, 6: 0.5})
    blob.modifiers.new("Collision", "COLLISION")
    bpy.context.view_layer.objects.active = sheet
    with pytest.warns(addon.scene_export.ExportWarning) as caught:
        addon.scene_export.write_scene(sheet, str(tmp_path / "scene.json"))
    texts = [str(w.message) for w in caught]
    assert any("Wind 'Gust' varies across the sheet" in t for t in texts), texts
    assert any("bakes together with 'Other'" in t and "holds 'Sheet' alone" in t for t in texts), texts
    assert any("Collision 'Blob' changes shape during the bake" in t for t in texts), texts
    # The operator writes the file and reports the same lines as warnings.
    assert bpy.ops.thinburn.export_scene(filepath=str(tmp_path / "op.json")) == {"FINISHED"}
    assert (tmp_path / "op.json").exists()
