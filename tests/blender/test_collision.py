"""Blender's own Collision physics holds a ThinBurn sheet (issue #12, item 6): a cloth plane
dropped on a UV sphere with a Collision modifier drapes over it."""
from __future__ import annotations

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytestmark = pytest.mark.blender

from blender_helpers import (cache_file, make_box_table, make_igniter, make_rect, make_sheet,  # noqa: E402
                             make_uv_sphere, setup_bake)

R, TOP = 0.1, 0.2  # the sphere's radius and top (centre at z = 0.1)


def _scene(tmp_path, frames):
    sphere = make_uv_sphere(radius=R, segments=32, rings=16, centre=(0.0, 0.0, TOP - R))
    sphere.modifiers.new("Collision", "COLLISION")
    sphere.collision.cloth_friction = 50.0   # Coulomb 0.5
    sphere.collision.thickness_outer = 0.001
    sphere.collision.damping = 0.5            # ignored: warned about
    sheet = make_sheet(n=41, size=0.4, z=TOP + 0.02)
    s = setup_bake(sheet, frames=frames, cells=32, cache_dir=tmp_path / "cache", floor=False)
    s.material = "cloth"
    s.lattice = 16
    make_igniter(sheet, (0.19, 0.19, TOP + 0.02), lit_from=1000)  # never lit: the motion alone
    return sheet, sphere


def test_a_sheet_drapes_over_a_sphere_with_collision(addon, tmp_path):
    sheet, sphere = _scene(tmp_path, frames=36)
    job = addon.job.BakeJob(bpy.context, sheet)
    job.run()
    assert job.colliders == ["Sphere"]
    assert any("Damping" in w and "Sphere" in w for w in job.warnings), job.warnings
    _, data = addon.cache.read_pc2(cache_file(tmp_path / "cache", "Sheet.pc2"))
    last = data[-1].astype(np.float64)  # the sheet's local frame is the world's here
    r = np.linalg.norm(last - (0.0, 0.0, TOP - R), axis=1)
    # Outside the sphere: the UV sphere's facets lie up to R (1 - cos(11.25 deg)) = 1.9 mm inside
    # the true sphere; measured: no cache vertex nearer the centre than R + 5.7 mm (frame 36).
    assert r.min() > R - 0.002
    centre = np.argmin(np.linalg.norm(last[:, :2], axis=1))
    rim = np.max(np.abs(data[0][:, :2].astype(np.float64)), axis=1) > 0.19  # the sheet's edge at rest
    # Lower at the rim than at the top: measured, the highest rim vertex 0.132 m (the top 0.2 m;
    # 0.1744 m when the cloth bent with its lattice's own rigidity, docs/dynamics.md §1.1), the
    # middle 5.6 mm above the top (margin + half the lattice thickness + Outer thickness).
    assert last[rim, 2].max() < TOP - 0.05
    assert TOP < last[centre, 2] < TOP + 0.01


def test_an_open_collision_mesh_is_warned_about_and_left_out(addon, tmp_path):
    sheet, sphere = _scene(tmp_path, frames=2)
    plane = make_sheet(name="Ground", n=3, size=1.0, z=0.0)
    plane.modifiers.new("Collision", "COLLISION")
    job = addon.job.BakeJob(bpy.context, sheet)
    job.cancel()
    assert job.colliders == ["Sphere"]
    assert any("Ground" in w and "not a closed mesh" in w for w in job.warnings), job.warnings


def test_a_thick_outer_is_named_in_the_report(addon, tmp_path):
    """The artists' trial: paper on a Collision table with Blender's default Outer thickness
    (2 cm) hovered 3 cm above it and nothing said why. The report names the Outer thickness of
    a collider above 5 mm, and the setting that changes it; not at 1 mm (the draping scene)."""
    sheet, sphere = _scene(tmp_path, frames=2)
    job = addon.job.BakeJob(bpy.context, sheet)
    job.cancel()
    assert not any("Outer thickness (" in w for w in job.warnings), job.warnings
    sphere.collision.thickness_outer = 0.02
    job = addon.job.BakeJob(bpy.context, sheet)
    job.cancel()
    named = [w for w in job.warnings if "Outer thickness (20 mm)" in w]
    assert len(named) == 1 and "'Sphere'" in named[0] and "Softbody & Cloth" in named[0], job.warnings
    # Outer is not the whole gap: the note says the lattice adds its thickness, and that a
    # table top is best made the Floor Object (with Outer at 1 mm, A4 paper hovered 7.5 mm up).
    assert "motion lattice about its thickness more" in named[0] and "Floor Object" in named[0]


def test_blender_default_collision_settings_are_not_warned_about(addon):
    """A new Collision modifier has Damping 0.1 and Single Sided on; warning about those warned
    on every bake with a Collision object. The panel's note says what is used instead."""
    sheet = make_sheet(n=5, size=0.2, z=0.3)
    setup_bake(sheet, frames=2, cells=16, floor=False)
    box = make_uv_sphere(radius=0.05, segments=8, rings=4, centre=(0.0, 0.0, 0.1))
    box.modifiers.new("Collision", "COLLISION")
    inputs = addon.inputs
    assert inputs.collision_warnings(bpy.context.view_layer, sheet.name, shell=True) == []
    assert "Friction and Outer thickness" in inputs.collision_note(bpy.context.view_layer, sheet.name)
    box.collision.damping = 0.5
    box.collision.use_culling = False  # both sides, as ThinBurn: nothing to warn about
    warned = inputs.collision_warnings(bpy.context.view_layer, sheet.name, shell=True)
    assert len(warned) == 1 and "Damping not used" in warned[0], warned


def test_no_collision_note_without_a_collision_object(addon):
    sheet = make_sheet(n=5, size=0.2, z=0.3)
    assert addon.inputs.collision_note(bpy.context.view_layer, sheet.name) is None


def test_paper_rests_on_a_collision_table_without_sinking(addon, tmp_path):
    """A4 paper 3 mm above a cube with Collision (the artist's table, no Floor) settles on it:
    never below its top, and at the gap docs/blender.md gives ("A table top: prefer Floor:
    Object"): the lattice's bottom layer a margin off the top, the mesh half a thickness above."""
    table = make_box_table(top=0.0, size=0.6)
    table.modifiers.new("Collision", "COLLISION")
    table.collision.cloth_friction = 50.0
    table.collision.thickness_outer = 0.001
    sheet = make_rect(name="Sheet", z=0.003)
    setup_bake(sheet, frames=30, cells=32, cache_dir=tmp_path / "cache", floor=False)
    make_igniter(sheet, (0.1, 0.14, 0.003), lit_from=1000)  # never lit: the motion alone
    job = addon.job.BakeJob(bpy.context, sheet)
    job.run()
    assert job.colliders == ["Table"]
    assert not any("Table" in w for w in job.warnings), job.warnings  # Blender's defaults elsewhere
    _, data = addon.cache.read_pc2(cache_file(tmp_path / "cache", "Sheet.pc2"))
    z = data[-1][:, 2].astype(np.float64)
    # Measured (frame 30, unlit): lowest 11.00 mm, as render_drape.py's burning table at frames 25-150
    # (10.94-10.99 mm); tolerance 1 mm each way: a change of the contact's margin shows here.
    assert 0.010 < z.min() < 0.012, z.min()


def test_the_panel_notes_which_collision_settings_are_used(addon):
    from test_addon import _Context, _Layout
    sheet = make_sheet(n=5, size=0.2, z=0.3)
    sheet.thinburn.enabled = True
    make_uv_sphere(radius=0.05, segments=8, rings=4, centre=(0.0, 0.0, 0.1)).modifiers.new("Collision", "COLLISION")
    drawn = []
    addon.panels.PHYSICS_PT_thinburn.draw(type("P", (), {"layout": _Layout(drawn)})(), _Context(sheet))
    text = " ".join(d[len("label: "):] for d in drawn if d.startswith("label: "))
    assert "Friction and Outer thickness" in text and "ignores Damping" in text, text


def test_a_floor_object_with_collision_is_the_floor_only(addon, tmp_path):
    """Quick Burn makes the Collision cube a plane lies on its Floor Object; as a collider as
    well, with Blender's default Outer thickness (2 cm), it lifted the sheet 26 mm off it."""
    table = make_box_table(top=0.0, size=0.6)
    table.modifiers.new("Collision", "COLLISION")  # Blender's defaults: Outer thickness 0.02 m
    sheet = make_rect(name="Sheet", width=0.2, height=0.2, nx=21, ny=21, z=0.003)
    s = setup_bake(sheet, frames=12, cells=32, cache_dir=tmp_path / "cache", floor=False)
    s.floor_mode, s.floor_object = "OBJECT", table
    make_igniter(sheet, (0.1, 0.1, 0.003), lit_from=1000)  # never lit: the motion alone
    job = addon.job.BakeJob(bpy.context, sheet)
    job.run()
    assert job.colliders == []
    assert any("Floor Object and has Collision" in w for w in job.warnings), job.warnings
    assert not any("Outer thickness (" in w for w in job.warnings), job.warnings  # not a collider now
    _, data = addon.cache.read_pc2(cache_file(tmp_path / "cache", "Sheet.pc2"))
    # Measured: 0.5 mm (the floor's margin) from frame 2 on; 26.2 mm with the cube a collider too.
    assert abs(float(data[-1][:, 2].min()) - 0.0005) < 2e-4


def test_a_drape_that_folds_the_lattice_sharply_is_noted(addon, tmp_path):
    """The bake's worker measures the lattice's largest turn between unburnt couples each frame
    (worker.CoreWorker.lattice_turn): the 40 cm cloth over the ball at Motion Detail 9 folds its
    lattice past 40 degrees (the tent's ridges: 129 degrees measured, at frame 12), and the
    report says its folds show as creases and names Motion Detail 18."""
    sheet, _ = _scene(tmp_path, frames=24)
    sheet.thinburn.lattice = 9
    job = addon.job.BakeJob(bpy.context, sheet)
    job.run()
    noted = [w for w in job.warnings if "folded sharply on its motion lattice" in w]
    assert len(noted) == 1 and "Motion Detail (now 9) higher, e.g. 18" in noted[0], job.warnings
    assert job.stretch.turn > 40.0
