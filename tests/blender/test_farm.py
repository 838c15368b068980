"""Farm paths of the add-on: headless bakes (python -m thinburn bake), USD and scene export."""
from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytestmark = pytest.mark.blender

from blender_helpers import cache_file, make_igniter, make_sheet, setup_bake  # noqa: E402

FRAMES = 12


def _shot(tmp_path, name="shot.blend"):
    """A saved .blend: a 9×9 sheet on a floor, lit at a corner from frame 2, cache next to it."""
    sheet = make_sheet(n=9, size=0.2, z=0.0)
    make_igniter(sheet, (-0.1, -0.1, 0.0), lit_from=2, radius=0.04)
    setup_bake(sheet, frames=FRAMES, cells=16, cache_dir="//cache/")
    path = str(tmp_path / name)
    bpy.ops.wm.save_as_mainfile(filepath=path)
    return path


def _headless(*args):
    """python -m thinburn bake ... in a fresh process (the add-on is found through the user
    folder the conftest set up in BLENDER_USER_RESOURCES, inherited here)."""
    return subprocess.run([sys.executable, "-m", "thinburn", "bake", *args], capture_output=True,
                          text=True, timeout=300, env=dict(os.environ))


def _read(path):
    with open(path, "rb") as f:
        return f.read()


def test_headless_bakes_are_bit_identical_and_a_failure_keeps_the_cache(addon, tmp_path):
    shot = _shot(tmp_path)
    cache = tmp_path / "cache" / "shot"  # a folder per .blend
    first = _headless(shot, "--object", "Sheet")
    assert first.returncode == 0, first.stderr
    assert f"({FRAMES}/{FRAMES}, 100.0 %)" in first.stderr and "ETA" in first.stderr
    assert "saved" in first.stderr
    pc2, fire = _read(cache / "Sheet.pc2"), _read(cache / "Sheet_fire.pc2")
    head, samples = addon.cache.read_pc2(cache / "Sheet.pc2")
    assert head["samples"] == FRAMES and np.ptp(samples[:, :, 2]) > 0  # it curls
    # The saved file carries the bake: reopen it and find the modifier and attributes.
    bpy.ops.wm.open_mainfile(filepath=shot)
    sheet = bpy.data.objects["Sheet"]
    assert sheet.modifiers.get("ThinBurn Cache") is not None
    assert sheet.thinburn.baked_file == "//cache/shot/Sheet.pc2"
    assert "thinburn_ignite_time" in sheet.data.attributes

    # A second bake of the same .blend (a second machine) writes the same bytes.
    second = _headless(shot)  # every enabled sheet
    assert second.returncode == 0, second.stderr
    assert _read(cache / "Sheet.pc2") == pc2 and _read(cache / "Sheet_fire.pc2") == fire

    # The operator (the UI's Bake, here from a script) writes the same bytes too.
    bpy.ops.wm.open_mainfile(filepath=shot)
    sheet = bpy.data.objects["Sheet"]
    sheet.thinburn.cache_dir = str(tmp_path / "ui")
    bpy.context.view_layer.objects.active = sheet
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    assert _read(tmp_path / "ui" / "shot" / "Sheet.pc2") == pc2

    # A failing bake: non-zero exit, the error's text, the previous cache and .blend untouched.
    bpy.ops.wm.open_mainfile(filepath=shot)
    coll = bpy.data.objects["Sheet"].thinburn.igniter_collection
    for ob in list(coll.objects):
        coll.objects.unlink(ob)
    bad = str(tmp_path / "shot_bad.blend")
    bpy.ops.wm.save_as_mainfile(filepath=bad)
    stamp = os.path.getmtime(bad)
    failed = _headless(bad, "--object", "Sheet")
    assert failed.returncode == 1
    assert "ThinBurn: error: 'Sheet': no igniters: the collection 'Igniters' is empty" in failed.stderr
    assert _read(cache / "Sheet.pc2") == pc2 and _read(cache / "Sheet_fire.pc2") == fire
    assert os.path.getmtime(bad) == stamp
    missing = _headless(shot, "--object", "Nope")
    assert missing.returncode == 1 and "there is no object 'Nope'" in missing.stderr


def test_headless_module_main_parses_args_after_the_double_dash(addon, tmp_path, monkeypatch):
    """blender -b shot.blend --python-expr "...; h.main()" -- --object Sheet --no-save"""
    _shot(tmp_path)
    monkeypatch.setattr(sys, "argv", ["blender", "-b", "shot.blend", "--python-expr", "x", "--",
                                      "--object", "Sheet", "--no-save", "--usd", str(tmp_path / "usd")])
    import importlib
    headless = importlib.import_module(f"{addon.__name__}.headless")
    with pytest.raises(SystemExit) as stop:
        headless.main()
    assert stop.value.code == 0
    assert (tmp_path / "cache" / "shot" / "Sheet.pc2").exists()
    assert (tmp_path / "usd" / "Sheet.usda").exists()


def test_usd_export_of_a_baked_sheet(addon, tmp_path):
    from pxr import Usd, UsdGeom
    sheet = make_sheet(n=9, size=0.2, z=0.0, location=(1.0, 2.0, 0.0))
    make_igniter(sheet, (0.9, 1.9, 0.0), lit_from=1, radius=0.04)
    setup_bake(sheet, frames=10, cells=16, cache_dir=tmp_path / "cache")
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    menu = {getattr(f, "__module__", "") for f in bpy.types.TOPBAR_MT_file_export._dyn_ui_initialize()}
    assert {f"{addon.__name__}.usd_export", f"{addon.__name__}.scene_export"} <= menu  # File > Export
    path = str(tmp_path / "sheet.usda")
    assert bpy.ops.thinburn.export_usd(filepath=path) == {"FINISHED"}
    head, samples = addon.cache.read_pc2(cache_file(tmp_path / "cache", "Sheet.pc2"))
    stage = Usd.Stage.Open(path)
    assert stage.GetTimeCodesPerSecond() == bpy.context.scene.render.fps
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (1.0, 10.0)
    prim = stage.GetPrimAtPath("/ThinBurn/Sheet")
    mesh = UsdGeom.Mesh(prim)
    assert list(mesh.GetFaceVertexCountsAttr().Get()) == [4] * 64  # the quads, not triangles
    for frame in (1, 5, 10):
        got = np.array(mesh.GetPointsAttr().Get(Usd.TimeCode(frame)))
        np.testing.assert_array_equal(got, samples[frame - 1])
    xf = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode(1))
    assert tuple(xf.ExtractTranslation()) == (1.0, 2.0, 0.0)
    api = UsdGeom.PrimvarsAPI(mesh)
    ign = api.GetPrimvar("ignitionTime")
    assert ign.GetInterpolation() == UsdGeom.Tokens.vertex
    attr = sheet.data.attributes["thinburn_ignite_time"]
    want = np.empty(len(attr.data), np.float32)
    attr.data.foreach_get("value", want)
    np.testing.assert_array_equal(np.array(ign.Get()), want)
    char = api.GetPrimvar("char")
    assert char.GetInterpolation() == UsdGeom.Tokens.vertex
    c1, c10 = np.array(char.Get(Usd.TimeCode(1))), np.array(char.Get(Usd.TimeCode(10)))
    assert np.all(c1 == 0) and c10.max() > 0 and np.all(c10 <= 1)
    fire = UsdGeom.Points(stage.GetPrimAtPath("/ThinBurn/Sheet_fire"))
    assert fire
    temp = UsdGeom.PrimvarsAPI(fire).GetPrimvar("temperature")
    assert temp.GetInterpolation() == UsdGeom.Tokens.vertex
    assert len(temp.Get(Usd.TimeCode(10))) == len(fire.GetPointsAttr().Get(Usd.TimeCode(10)))


def test_usd_export_of_a_moving_sheet_follows_its_transform(addon, tmp_path):
    """The cache is in object space; the USD places it with each frame's matrix, as Blender
    does (it was the matrix of the frame the export ran at, for every frame)."""
    from pxr import Usd, UsdGeom
    sheet = make_sheet(n=9, size=0.2, z=0.0)
    make_igniter(sheet, (-0.1, -0.1, 0.0), lit_from=1, radius=0.04)
    setup_bake(sheet, frames=10, cells=16, cache_dir=tmp_path / "cache")
    for frame, x in ((1, 0.0), (10, 0.3)):
        sheet.location = (x, 0.0, 0.0)
        sheet.keyframe_insert("location", frame=frame)
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    bpy.context.scene.frame_set(4)
    path = str(tmp_path / "moving.usda")
    assert bpy.ops.thinburn.export_usd(filepath=path) == {"FINISHED"}
    stage = Usd.Stage.Open(path)
    prim = stage.GetPrimAtPath("/ThinBurn/Sheet")
    for frame in (1, 7, 10):
        bpy.context.scene.frame_set(frame)
        want = float(sheet.matrix_world.translation.x)
        got = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode(frame)).ExtractTranslation()
        assert got[0] == pytest.approx(want, abs=1e-7) and (frame == 1) == (want == 0.0)


def test_scene_export_bakes_outside_blender_as_the_addon_does(addon, tmp_path):
    from thinburn import scenefile, wedge
    sheet = make_sheet(n=9, size=0.2, z=0.0)
    ig = make_igniter(sheet, (-0.1, -0.1, 0.0), lit_from=3, radius=0.04)
    ig.location = (-0.1, -0.1, 0.0)
    ig.keyframe_insert("location", frame=3)
    ig.location = (0.0, -0.1, 0.0)  # it moves while lit: ignitions along its path
    ig.keyframe_insert("location", frame=6)
    setup_bake(sheet, frames=FRAMES, cells=16, cache_dir=tmp_path / "cache")
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    _, pc2 = addon.cache.read_pc2(cache_file(tmp_path / "cache", "Sheet.pc2"))
    path = addon.scene_export.write_scene(sheet, str(tmp_path / "scene.json"))
    spec = scenefile.load_scene(path)
    assert spec.frames == FRAMES and spec.cells == 16 and spec.floor == pytest.approx(0.0)
    times = sorted(g["time"] for g in spec.igniters)
    assert len(times) > 3 and times[0] == pytest.approx(2 / 24)  # frame 3 is t = 2/24 s
    sim, _, fps, frames = wedge.simulation_for(spec, {})
    out = []
    wedge.run_frames(sim, spec, fps, frames, lambda k, s: out.append(s.vertex_positions()))
    np.testing.assert_array_equal(np.asarray(out, dtype=np.float32), pc2)


def test_a_bake_that_fails_midway_keeps_the_previous_cache_and_file(addon, tmp_path, monkeypatch):
    import importlib
    import io

    import thinburn
    headless = importlib.import_module(f"{addon.__name__}.headless")
    shot = _shot(tmp_path)
    assert headless.bake_file(shot, stream=io.StringIO()) == 0
    cache = tmp_path / "cache" / "shot"  # a folder per .blend
    pc2, stamp = _read(cache / "Sheet.pc2"), os.path.getmtime(shot)
    real_step, calls = thinburn.Simulation.step, []

    def failing_step(self, dt):
        calls.append(dt)
        if len(calls) == 5:
            raise RuntimeError("the core gave up at step 5")
        return real_step(self, dt)

    monkeypatch.setattr(thinburn.Simulation, "step", failing_step)
    log = io.StringIO()
    assert headless.bake_file(shot, stream=log) == 1
    text = log.getvalue()
    assert "ThinBurn: error: 'Sheet': the simulation failed: RuntimeError: the core gave up at step 5" in text
    assert "saved" not in text and os.path.getmtime(shot) == stamp
    assert _read(cache / "Sheet.pc2") == pc2 and not (cache / "Sheet.pc2.partial").exists()
    assert addon.operators.running_job(bpy.context.scene) is None
