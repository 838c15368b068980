"""Sheets that heat each other bake together (issue #14 item 3): two separate objects with Heat
Ignites within heat's reach bake as one simulation, each into its own cache."""
from __future__ import annotations

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytestmark = pytest.mark.blender

from blender_helpers import cache_file, make_sheet, make_stack, point_attribute, setup_bake  # noqa: E402

N = 17          # vertices per side of each 15 cm sheet
FRAMES = 48     # 2 s at 24 fps
CELLS = 32


def _sheet(name, z, tmp_path):
    sheet = make_sheet(name=name, n=N, size=0.15, z=z)
    s = setup_bake(sheet, frames=FRAMES, cells=CELLS, cache_dir=tmp_path / "cache")
    s.floor_height = 0.0  # one floor for both: the group bakes with the first sheet's
    s.heat_ignites = True
    return sheet


def _igniters(sheet, name, strength):
    coll = bpy.data.collections.new(name)
    bpy.context.scene.collection.children.link(coll)
    sheet.thinburn.igniter_collection = coll
    empty = bpy.data.objects.new(name + " Empty", None)
    coll.objects.link(empty)
    empty.location = sheet.matrix_world @ sheet.data.vertices[N * N // 2].co  # its centre
    empty.thinburn_igniter.radius = 0.008  # this sheet only: the other is 1 cm or more away
    empty.thinburn_igniter.strength = strength
    return empty


def _pin_all(sheet):
    group = sheet.vertex_groups.new(name="pins")
    group.add(list(range(len(sheet.data.vertices))), 1.0, "REPLACE")
    sheet.thinburn.pin_group = "pins"


def _pair(tmp_path, gap, upper_heat=True):
    """A lit lower sheet at z = 0 and a pinned upper one ``gap`` m above it, separate objects;
    the upper has an igniter of its own that never lights (so it can bake alone)."""
    lower = _sheet("Lower", 0.0, tmp_path)
    _igniters(lower, "Lower Igniters", 1.0)
    upper = _sheet("Upper", gap, tmp_path)
    upper.thinburn.heat_ignites = upper_heat
    _pin_all(upper)
    _igniters(upper, "Upper Igniters", 0.0)
    return lower, upper


def _bake(addon, obj):
    return addon.operators.bake_now(bpy.context, obj)


def _pc2(addon, tmp_path, name):
    return addon.cache.read_pc2(cache_file(tmp_path / "cache", name + ".pc2"))


def _solo_lower(addon, tmp_path, upper):
    """The lower sheet baked alone (the upper switched off), its PC2 samples."""
    upper.thinburn.enabled = False
    job = _bake(addon, bpy.data.objects["Lower"])
    upper.thinburn.enabled = True
    assert job.members == ["Lower"]
    return _pc2(addon, tmp_path, "Lower")[1].copy()


def test_sheets_1cm_apart_bake_together(addon, tmp_path):
    lower, upper = _pair(tmp_path, 0.01)
    job = _bake(addon, lower)
    assert job.members == ["Lower", "Upper"]
    assert "together with 'Upper'" in job.message
    for obj in (lower, upper):  # each its own cache, its own vertex count, its own attributes
        head, samples = _pc2(addon, tmp_path, obj.name)
        assert head["points"] == N * N and samples.shape == (FRAMES, N * N, 3)
        assert obj.thinburn.baked_file.endswith(obj.name + ".pc2")
    # the upper sheet's cache holds it where it is (pinned, 1 cm up), in its own object space
    assert np.allclose(_pc2(addon, tmp_path, "Upper")[1][-1, :, 2], 0.01, atol=1e-6)
    up = point_attribute(upper, "thinburn_ignite_time")
    # Measured: the upper sheet first lights at frame 9 (its own igniter never lights).
    assert (up < addon.cache.NEVER_FRAME).any()
    assert 5 <= up.min() <= 15, up.min()
    # The reference: the same two sheets joined into one mesh (the stack Heat Ignites already
    # burns as one object) bake bit for bit the same, positions and ignition times.
    together = np.concatenate([_pc2(addon, tmp_path, n)[1] for n in ("Lower", "Upper")], axis=1)
    times = np.concatenate([point_attribute(o, "thinburn_ignite_time") for o in (lower, upper)])
    stack = _joined_stack(tmp_path)
    _bake(addon, stack)
    assert np.array_equal(_pc2(addon, tmp_path, "Stack")[1], together)
    assert np.array_equal(point_attribute(stack, "thinburn_ignite_time"), times)


def _joined_stack(tmp_path):
    """The pair as one mesh (lower sheet's vertices first), the pair switched off."""
    for name in ("Lower", "Upper"):
        bpy.data.objects[name].thinburn.enabled = False
    stack = make_stack(name="Stack", size=0.15, gap=0.01, sheets=2, n=N, shift=0.0)
    s = setup_bake(stack, frames=FRAMES, cells=CELLS, cache_dir=tmp_path / "cache")
    s.floor_height, s.heat_ignites = 0.0, True
    z = np.array([v.co.z for v in stack.data.vertices])
    pins = stack.vertex_groups.new(name="pins")
    pins.add([int(i) for i in np.flatnonzero(z > 0.005)], 1.0, "REPLACE")
    s.pin_group = "pins"
    s.igniter_collection = bpy.data.collections["Lower Igniters"]
    return stack


def test_a_bake_from_either_sheet_bakes_the_group(addon, tmp_path):
    lower, upper = _pair(tmp_path, 0.01)
    upper.thinburn.cells = 24
    job = _bake(addon, upper)
    assert job.members == ["Upper", "Lower"]  # the upper's settings: its Fire Detail 24
    assert job.shape["cells"] == 24 * 24
    assert any("'Lower' burns together with 'Upper'" in w and "Fire Detail" in w
               for w in job.warnings), job.warnings
    for obj in (lower, upper):
        assert obj.thinburn.baked_file.endswith(obj.name + ".pc2")
    bpy.context.view_layer.objects.active = lower
    assert bpy.ops.thinburn.free_bake() == {"FINISHED"}  # Free is per object
    assert not lower.thinburn.baked_file and upper.thinburn.baked_file
    assert cache_file(tmp_path / "cache", "Upper.pc2").exists()
    assert not cache_file(tmp_path / "cache", "Lower.pc2").exists()


@pytest.mark.parametrize("gap, upper_heat", [(0.5, True), (0.01, False)])
def test_sheets_out_of_reach_bake_alone(addon, tmp_path, gap, upper_heat):
    """50 cm apart, or 1 cm apart with the upper's Heat Ignites off: not grouped; the lower's
    bake is bit-for-bit its bake alone, and the upper never catches."""
    lower, upper = _pair(tmp_path, gap, upper_heat)
    alone = _solo_lower(addon, tmp_path, upper)
    assert bpy.ops.thinburn.bake_all() == {"FINISHED"}
    assert np.array_equal(_pc2(addon, tmp_path, "Lower")[1], alone)
    assert (point_attribute(lower, "thinburn_ignite_time") < addon.cache.NEVER_FRAME).any()
    assert (point_attribute(upper, "thinburn_ignite_time") >= addon.cache.NEVER_FRAME).all()


def test_bake_all_from_the_ui_bakes_a_group_once(addon, tmp_path):
    """The modal Bake All with both sheets queued: the group bakes from the first, and the
    second, baked with it, is not baked again."""
    import time
    from blender_helpers import modal_harness
    lower, upper = _pair(tmp_path, 0.01)
    send, reports, _ = modal_harness(addon, addon.job.BakeJob(bpy.context, lower), queue=["Upper"])
    try:
        for _ in range(100000):
            if (result := send("TIMER")) != {"RUNNING_MODAL"}:
                break
            time.sleep(0.001)
    finally:
        addon.operators._running.clear()
    assert result == {"FINISHED"}, reports
    baked = [t for _, t in reports if "baked" in t]
    assert len(baked) == 1 and "'Lower' together with 'Upper'" in baked[0], baked
    assert lower.thinburn.baked_file and upper.thinburn.baked_file


def test_a_moving_sheet_of_a_group_is_refused_by_name(addon, tmp_path):
    lower, upper = _pair(tmp_path, 0.01)
    upper.keyframe_insert("location", frame=1)
    upper.location.x += 0.01
    upper.keyframe_insert("location", frame=10)
    with pytest.raises(addon.inputs.BakeError, match="'Upper' bakes together with 'Lower'.*cannot move"):
        _bake(addon, lower)
    assert not lower.thinburn.baked_file  # nothing written, nothing hooked
    assert not cache_file(tmp_path / "cache", "Lower.pc2.partial").exists()
