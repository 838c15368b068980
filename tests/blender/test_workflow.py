"""The artist's workflow (issue #14): Quick Burn, Bake All, caches per file and per object,
warnings for what the bake ignores, names in an artist's words."""
from __future__ import annotations

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytestmark = pytest.mark.blender

from blender_helpers import (evaluated_colours, evaluated_positions, make_igniter,  # noqa: E402
                             make_sheet, make_table, modal_harness, point_attribute, setup_bake,
                             worker_busy)

FRAMES = 24


def _quick_scene(tmp_path, name="Sheet", z=0.75, location=(0.0, 0.0, 0.0)):
    """A saved file with a 0.2 m sheet (small settings, so the test is quick) on a table."""
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "shot.blend"))
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, FRAMES
    table = bpy.data.objects.get("Cube") or make_table(0.75)
    sheet = make_sheet(name, z=z, location=location)
    sheet.thinburn.cells = 16
    sheet.thinburn.threads = 1
    return table, sheet


def test_quick_burn_is_in_the_object_menu_beside_quick_smoke(addon):
    menu = bpy.types.VIEW3D_MT_object_quick_effects
    assert addon.quick._menu in menu._dyn_ui_initialize()


def _select(*objects):
    for o in bpy.context.scene.objects:
        o.select_set(o in objects)
    bpy.context.view_layer.objects.active = objects[0]


def test_quick_burn_lights_the_point_nearest_the_cursor_floors_bakes_and_plays(addon, tmp_path):
    table, sheet = _quick_scene(tmp_path)
    bpy.context.scene.cursor.location = (0.3, 0.3, 1.0)  # beyond the (+x, +y) corner
    bpy.context.scene.frame_set(9)
    _select(sheet)
    assert bpy.ops.thinburn.quick_burn() == {"FINISHED"}
    s = sheet.thinburn
    assert s.enabled and (s.frame_start, s.frame_end) == (1, FRAMES)
    igniters = list(s.igniter_collection.objects)
    assert len(igniters) == 1
    np.testing.assert_allclose(igniters[0].location, (0.1, 0.1, 0.75), atol=1e-6)
    anim = igniters[0].animation_data  # Strength is keyframed, as igniters are
    assert anim is not None and anim.action is not None
    assert s.floor_mode == "OBJECT" and s.floor_object == table  # it lies on the table
    assert s.cache_dir.startswith("//")  # beside the .blend, relative
    assert (tmp_path / "thinburn_cache").is_dir()
    # Baked: the corner under the cursor catches first, and it plays from the first frame.
    ignite = point_attribute(sheet, "thinburn_ignite_time")
    assert ignite[-1] == ignite.min() < ignite[0]
    assert bpy.context.scene.frame_current == 1
    rest = evaluated_positions(sheet, 1)
    assert np.abs(evaluated_positions(sheet, FRAMES) - rest).max() > 1e-4  # the sheet moves
    brightness = [evaluated_colours(sheet, f)[:, :3].sum(axis=1).mean() for f in (1, 12, FRAMES)]
    assert brightness[0] > brightness[1] > brightness[2]  # char spreads frame after frame
    z = evaluated_positions(sheet, FRAMES)[:, 2]
    assert z.min() >= 0.75  # never into the table


def test_quick_burn_in_edit_mode_lights_the_selected_vertices(addon, tmp_path):
    _, sheet = _quick_scene(tmp_path)
    bpy.context.scene.cursor.location = (0.3, 0.3, 1.0)  # the cursor is not used
    _select(sheet)
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="DESELECT")
    import bmesh
    bm = bmesh.from_edit_mesh(sheet.data)
    bm.verts.ensure_lookup_table()
    bm.verts[0].select = True  # the (-x, -y) corner
    bmesh.update_edit_mesh(sheet.data)
    assert bpy.ops.thinburn.quick_burn() == {"FINISHED"}
    assert sheet.mode == "OBJECT"
    (igniter,) = sheet.thinburn.igniter_collection.objects
    np.testing.assert_allclose(igniter.location, (-0.1, -0.1, 0.75), atol=1e-6)
    ignite = point_attribute(sheet, "thinburn_ignite_time")
    assert ignite[0] == ignite.min() < ignite[-1]


def test_quick_burn_again_moves_the_fire_and_keeps_a_floor_already_set(addon, tmp_path):
    _, sheet = _quick_scene(tmp_path, z=0.9)  # above the table: nothing under it to lie on
    bpy.context.scene.frame_end = 3
    _select(sheet)
    bpy.context.scene.cursor.location = (0.1, 0.1, 0.9)
    assert bpy.ops.thinburn.quick_burn() == {"FINISHED"}
    assert sheet.thinburn.floor_mode == "NONE"
    bpy.context.scene.cursor.location = (-0.1, -0.1, 0.9)
    assert bpy.ops.thinburn.quick_burn() == {"FINISHED"}
    (igniter,) = sheet.thinburn.igniter_collection.objects  # the first one went
    np.testing.assert_allclose(igniter.location, (-0.1, -0.1, 0.9), atol=1e-6)


def _undo():
    with bpy.context.temp_override(window=bpy.context.window_manager.windows[0]):
        bpy.ops.ed.undo()


def test_undo_takes_quick_burn_back(addon, tmp_path):
    _, sheet = _quick_scene(tmp_path)
    bpy.context.scene.frame_end = 4
    _select(sheet)
    collections = set(bpy.data.collections.keys())
    objects = set(bpy.data.objects.keys())
    bpy.ops.ed.undo_push(message="before Quick Burn")
    # As from a menu: the operator pushes its own undo step ('undo' is bpy.ops' second argument).
    with bpy.context.temp_override(window=bpy.context.window_manager.windows[0]):
        assert bpy.ops.thinburn.quick_burn("EXEC_DEFAULT", True) == {"FINISHED"}
    assert bpy.data.objects["Sheet"].modifiers and set(bpy.data.objects.keys()) > objects
    _undo()
    sheet = bpy.data.objects["Sheet"]  # undo reloads the data: fetch it again
    assert not sheet.thinburn.enabled
    assert not sheet.modifiers
    assert sheet.thinburn.igniter_collection is None and sheet.thinburn.floor_mode == "NONE"
    assert set(bpy.data.objects.keys()) == objects
    assert set(bpy.data.collections.keys()) == collections
    assert "thinburn_ignite_time" not in sheet.data.attributes


def test_bake_all_bakes_every_enabled_sheet_with_progress(addon, tmp_path, capfd):
    a = make_sheet("A", location=(0.0, 0.0, 0.0))
    b = make_sheet("B", location=(1.0, 0.0, 0.0))
    off = make_sheet("Off", location=(2.0, 0.0, 0.0))
    for sheet in (a, b):
        setup_bake(sheet, frames=4, cells=16, cache_dir=tmp_path)
        make_igniter(sheet, (sheet.location.x, 0.0, 0.5), name=f"Ig {sheet.name}")
    setup_bake(off, frames=4, cells=16, cache_dir=tmp_path).enabled = False
    assert bpy.ops.thinburn.bake_all() == {"FINISHED"}
    assert a.modifiers.get("ThinBurn Cache") and b.modifiers.get("ThinBurn Cache")
    assert not off.modifiers
    err = capfd.readouterr().err
    assert "ThinBurn: 'A' frame" in err and "ThinBurn: 'B' frame" in err


def test_bake_all_from_the_ui_bakes_one_sheet_after_another(addon, tmp_path):
    import time
    sheets = [make_sheet(name, location=(x, 0.0, 0.0)) for name, x in (("A", 0.0), ("B", 1.0))]
    for sheet in sheets:
        setup_bake(sheet, frames=4, cells=16, cache_dir=tmp_path)
        make_igniter(sheet, (sheet.location.x, 0.0, 0.5), name=f"Ig {sheet.name}")
    send, reports, status = modal_harness(addon, addon.job.BakeJob(bpy.context, sheets[0]),
                                          queue=["B"])
    seen = set()
    try:
        while (result := send("TIMER")) == {"RUNNING_MODAL"}:
            job = addon.operators.running_job(bpy.context.scene)
            seen.add(job.obj_name)
            if not worker_busy(job):
                break
            time.sleep(0.001)
    finally:
        addon.operators._running.clear()
    assert result == {"FINISHED"}, reports
    # The timer may first look after A has already finished (a 4-frame bake on a fast machine),
    # so the polled names need only hold B; the reports name both bakes, A first.
    assert "B" in seen and seen <= {"A", "B"}
    assert all(s.modifiers.get("ThinBurn Cache") for s in sheets)
    baked = [t for _, t in reports if "baked" in t]
    assert len(baked) == 2 and "'A'" in baked[0] and "'B'" in baked[1]
    assert any("'B'" in s for s in status if s) and status[-1] is None


def test_bake_all_goes_on_past_a_sheet_that_cannot_bake_and_names_it(addon, tmp_path):
    good = make_sheet("Good")
    setup_bake(good, frames=3, cells=16, cache_dir=tmp_path)
    make_igniter(good, (0.0, 0.0, 0.5))
    bad = make_sheet("Bad", location=(1.0, 0.0, 0.0))
    setup_bake(bad, frames=3, cells=16, cache_dir=tmp_path)  # no igniters
    with pytest.raises(RuntimeError) as info:
        bpy.ops.thinburn.bake_all()
    assert "'Bad': no igniters" in str(info.value)
    assert good.modifiers.get("ThinBurn Cache") and not bad.modifiers


def test_bake_all_with_nothing_enabled_says_what_to_do(addon):
    make_sheet()
    with pytest.raises(RuntimeError, match="has ThinBurn enabled"):
        bpy.ops.thinburn.bake_all()


# --- caches you can trust ------------------------------------------------------------------------
def _baked_sheet(frames=6):
    sheet = make_sheet()
    setup_bake(sheet, frames=frames, cells=16)  # the default folder, //thinburn_cache/
    make_igniter(sheet, (0.0, 0.0, 0.5), lit_from=1, radius=0.05)
    bpy.context.view_layer.objects.active = sheet
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    return sheet


def _files(folder):
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())


def test_save_as_makes_a_file_of_its_own_and_free_there_keeps_the_originals_cache(addon, tmp_path):
    # Issue #14: //thinburn_cache/<object>.pc2 was shared, and Free in one file deleted the other's.
    a, b = tmp_path / "a.blend", tmp_path / "b.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(a))
    sheet = _baked_sheet()
    cache = tmp_path / "thinburn_cache"
    made = _files(cache)
    assert "a/Sheet.pc2" in made and all(f.startswith("a/") for f in made)
    # Relative paths stay relative: the modifiers and the record.
    assert sheet.modifiers["ThinBurn Cache"].filepath == "//thinburn_cache/a/Sheet.pc2"
    assert all(item.path.startswith("//thinburn_cache/a/") for item in sheet.thinburn.baked_files)
    assert len(sheet.thinburn.baked_files) == len(made)
    original = (cache / "a" / "Sheet.pc2").read_bytes()
    bpy.ops.wm.save_mainfile()
    bpy.ops.wm.save_as_mainfile(filepath=str(b))
    sheet = bpy.data.objects["Sheet"]
    bpy.context.view_layer.objects.active = sheet
    assert bpy.ops.thinburn.free_bake() == {"FINISHED"}
    assert not sheet.modifiers and "ThinBurn Fire Sheet" not in bpy.data.objects
    assert _files(cache) == made  # a.blend's cache is all there
    # A bake in b.blend goes to b's folder; a's bytes do not change.
    make_igniter(sheet, (0.1, 0.1, 0.5), lit_from=1, radius=0.05, name="Igniter B")
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    assert sheet.modifiers["ThinBurn Cache"].filepath == "//thinburn_cache/b/Sheet.pc2"
    assert (cache / "a" / "Sheet.pc2").read_bytes() == original
    bpy.ops.wm.save_mainfile()
    # Back in a.blend: it still plays its cache, and Free there deletes exactly its files.
    bpy.ops.wm.open_mainfile(filepath=str(a))
    sheet = bpy.data.objects["Sheet"]
    _, data = addon.cache.read_pc2(cache / "a" / "Sheet.pc2")
    np.testing.assert_allclose(evaluated_positions(sheet, 6), data[5], atol=1e-6)
    bpy.context.view_layer.objects.active = sheet
    assert bpy.ops.thinburn.free_bake() == {"FINISHED"}
    assert not [f for f in _files(cache) if f.startswith("a/")]
    assert "b/Sheet.pc2" in _files(cache)


def test_a_bake_made_before_the_first_save_belongs_to_the_file_it_is_saved_as(addon, tmp_path):
    sheet = make_sheet()
    setup_bake(sheet, frames=4, cells=16, cache_dir=tmp_path / "cache")
    make_igniter(sheet, (0.0, 0.0, 0.5), lit_from=1)
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    assert (tmp_path / "cache" / "untitled" / "Sheet.pc2").exists()
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "a.blend"))
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "b.blend"))
    bpy.context.view_layer.objects.active = bpy.data.objects["Sheet"]
    assert bpy.ops.thinburn.free_bake() == {"FINISHED"}
    assert (tmp_path / "cache" / "untitled" / "Sheet.pc2").exists()  # b is a copy: kept
    bpy.ops.wm.open_mainfile(filepath=str(tmp_path / "a.blend"))
    bpy.context.view_layer.objects.active = bpy.data.objects["Sheet"]
    assert bpy.ops.thinburn.free_bake() == {"FINISHED"}
    assert not (tmp_path / "cache" / "untitled" / "Sheet.pc2").exists()


def test_free_after_a_rename_removes_every_file_and_object_the_bakes_made(addon, tmp_path):
    # Issue #14: Free after a rename left the fire object and its file behind.
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "shot.blend"))
    sheet = _baked_sheet()
    cache = tmp_path / "thinburn_cache"
    made = [o.name for o in bpy.data.objects if o.name.startswith("ThinBurn ")]
    assert "ThinBurn Fire Sheet" in made and "shot/Sheet_fire.pc2" in _files(cache)
    sheet.name = "Paper"
    assert bpy.ops.thinburn.bake() == {"FINISHED"}  # baked again under the new name
    # The old name's objects went with the new bake; its files wait for Free.
    assert not [n for n in made if n in bpy.data.objects]
    assert "ThinBurn Fire Paper" in bpy.data.objects and "shot/Sheet.pc2" in _files(cache)
    sheet.name = "Letter"  # and renamed once more, without a bake
    assert bpy.ops.thinburn.free_bake() == {"FINISHED"}
    assert _files(cache) == []
    assert not [o.name for o in bpy.data.objects if o.name.startswith("ThinBurn ")]
    assert not sheet.modifiers and len(sheet.thinburn.baked_files) == 0


def test_a_rebake_keeps_the_cache_the_saved_file_plays_until_the_file_is_saved(addon, tmp_path, capfd):
    # Re-baking a saved file wrote over the cache that file plays: reopening it without saving
    # (or after a crash) played the new bake's motion under the old bake's char and fire.
    blend = tmp_path / "shot.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    sheet = _baked_sheet()
    cache = tmp_path / "thinburn_cache"
    bpy.ops.wm.save_mainfile()
    made = _files(cache)
    assert "shot/Sheet.pc2" in made
    first = (cache / "shot" / "Sheet.pc2").read_bytes()
    ignite = point_attribute(sheet, "thinburn_ignite_time").copy()
    bpy.data.objects["Igniter"].location = (0.1, 0.1, 0.5)  # another bake
    capfd.readouterr()
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    assert ("the saved 'shot.blend' still plays Sheet.pc2 until you save it (this bake: Sheet.2.pc2)"
            in capfd.readouterr().out)
    assert sheet.modifiers["ThinBurn Cache"].filepath == "//thinburn_cache/shot/Sheet.2.pc2"
    assert not np.array_equal(point_attribute(sheet, "thinburn_ignite_time"), ignite)
    assert (cache / "shot" / "Sheet.pc2").read_bytes() == first
    # Baked again before a save: the unsaved bake is written over, not kept beside.
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    versions = [f.replace("Sheet", "Sheet.2") for f in made]
    assert _files(cache) == sorted(made + versions)
    # The saved file, reopened, plays its own bake: the first cache under the first char.
    bpy.ops.wm.open_mainfile(filepath=str(blend))
    sheet = bpy.data.objects["Sheet"]
    np.testing.assert_array_equal(point_attribute(sheet, "thinburn_ignite_time"), ignite)
    _, data = addon.cache.read_pc2(cache / "shot" / "Sheet.pc2")
    np.testing.assert_allclose(evaluated_positions(sheet, 6), data[5], atol=1e-6)
    # Re-baked and saved: the file plays the new bake, and the one it replaced is deleted.
    bpy.data.objects["Igniter"].location = (0.1, 0.1, 0.5)
    bpy.context.view_layer.objects.active = sheet
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    assert _files(cache) == sorted(made + versions)
    bpy.ops.wm.save_mainfile()
    assert _files(cache) == versions
    assert sorted(item.path for item in sheet.thinburn.baked_files) == [
        "//thinburn_cache/" + f for f in versions]
    # The next re-bake of the saved file takes the freed name.
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    assert sheet.modifiers["ThinBurn Cache"].filepath == "//thinburn_cache/shot/Sheet.pc2"
    assert bpy.ops.thinburn.free_bake() == {"FINISHED"}
    assert _files(cache) == []


# --- warnings for what the bake ignores --------------------------------------------------------
def test_the_bake_report_warns_of_fields_it_ignores_not_of_a_moving_sheet_or_wind_noise(
        addon, tmp_path, capfd):
    sheet = make_sheet()
    setup_bake(sheet, frames=6, cells=16, cache_dir=tmp_path, floor=False)
    make_igniter(sheet, (0.0, 0.0, 0.5))
    still = addon.operators.bake_now(bpy.context, sheet)
    assert still.warnings == []  # nothing ignored, nothing said
    sheet.keyframe_insert("location", frame=1)
    sheet.location.x = 0.5
    sheet.keyframe_insert("location", frame=6)  # a letter thrown across the table: followed
    bpy.ops.object.effector_add(type="WIND")
    bpy.context.active_object.field.noise = 1.0  # used (tests/blender/test_scene.py)
    bpy.context.view_layer.objects.active = sheet
    assert addon.operators.bake_now(bpy.context, sheet).warnings == []
    bpy.ops.object.effector_add(type="FORCE")
    bpy.context.view_layer.objects.active = sheet
    capfd.readouterr()
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    out = capfd.readouterr().out
    assert "Warning: ThinBurn: 'Force' (a Force field) does not act on ThinBurn sheets" in out
    assert "moves in the scene" not in out and "Noise" not in out
    # The same from the command line: headless prints the warnings with the bake's message.
    import importlib
    import io
    headless = importlib.import_module(f"{addon.__name__}.headless")
    text = headless.bake_object(sheet, stream=io.StringIO())
    assert "ThinBurn: warning: 'Force' (a Force field) does not act" in text


def test_a_mesh_too_coarse_for_its_fire_detail_is_told_to_subdivide(addon, tmp_path):
    sheet = make_sheet(n=3)  # 9 vertices
    setup_bake(sheet, frames=2, cells=32, cache_dir=tmp_path)
    make_igniter(sheet, (0.0, 0.0, 0.5))
    (text,) = addon.operators.bake_now(bpy.context, sheet).warnings
    assert "'Sheet' has 9 vertices for 32×32 fire cells" in text and "Subdivide" in text
    sheet.thinburn.cells = 8  # a vertex every 4 cells is fine
    assert addon.operators.bake_now(bpy.context, sheet).warnings == []


def test_quick_burn_says_when_the_fire_would_stay_a_small_spot(addon, tmp_path):
    """The artists' trial: Quick Burn on paper at its own 3.5 mm/s lit 71 of an A4 sheet's
    3721 vertices in a 5 s shot, and nothing said why. Its report notes a fire that reaches less
    than a quarter of the sheet's size from Start to End, and the two settings that change it;
    not with a Burn Duration, nor at a Spread Speed that reaches that far."""
    table, sheet = _quick_scene(tmp_path)  # a 0.2 m sheet (20 cm across), 24 frames: 1 s at 24 fps
    settings = sheet.thinburn
    scene = bpy.context.scene
    notes = addon.quick.setup(bpy.context, sheet, [(0.0, 0.0, 0.75)], scene_range=True, exclude={sheet.name})
    slow = [n for n in notes if "Spread Speed" in n]
    # 23 frames at 24 fps: 0.96 s, 3.4 mm at paper's 3.5 mm/s
    assert len(slow) == 1 and "3.5 mm/s" in slow[0] and "0.3 cm" in slow[0] and "20 cm across" in slow[0], notes
    assert "Burn Duration" in slow[0]
    settings.burn_duration = 1.0
    assert addon.quick.slow_fire_note(sheet, settings, scene) is None
    settings.burn_duration = 0.0
    settings.mat_V0 = 80.0  # 77 mm in the shot, beyond a quarter of 20 cm
    assert addon.quick.slow_fire_note(sheet, settings, scene) is None


def test_quick_burn_takes_the_scenes_range_unless_the_sheet_has_its_own(addon, tmp_path):
    """An artist's trial ticked the ThinBurn box first (docs/blender.md's steps say so), set
    the scene to 1-150 and ran Quick Burn: it baked 1-250, the box's defaults, without a word.
    A sheet whose Start and End are still the defaults takes the scene's range; a range set on
    the sheet is kept, and the report says it differs from the scene's."""
    _, sheet = _quick_scene(tmp_path)
    scene = bpy.context.scene
    settings = sheet.thinburn
    settings.enabled = True  # ticked first: Start, End still 1, 250
    scene.frame_start, scene.frame_end = 1, 150
    notes = addon.quick.setup(bpy.context, sheet, [(0.0, 0.0, 0.75)], scene_range=True, exclude={sheet.name})
    assert (settings.frame_start, settings.frame_end) == (1, 150)
    assert not [n for n in notes if "its own frames" in n], notes
    settings.frame_start, settings.frame_end = 10, 40  # the artist's own range
    notes = addon.quick.setup(bpy.context, sheet, [(0.0, 0.0, 0.75)], scene_range=True, exclude={sheet.name})
    assert (settings.frame_start, settings.frame_end) == (10, 40)
    assert [n for n in notes if "'Sheet' bakes its own frames 10–40, not the scene's 1–150" in n], notes
