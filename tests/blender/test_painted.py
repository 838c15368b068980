"""Direct control in real Blender (issue #14): painted speed, fuel and firebreak maps, ignition
from a vertex group, a painted attribute, or a mesh igniter's surface."""
from __future__ import annotations

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytestmark = pytest.mark.blender

from blender_helpers import make_sheet, point_attribute, setup_bake  # noqa: E402

N = 21        # vertices per side: 1 cm apart on a 20 cm sheet
FAST = 100.0  # mm/s: the fire crosses the sheet in 2 s (48 frames)


def _sheet(tmp_path, frames=48):
    sheet = make_sheet(n=N, size=0.2, z=0.0)
    s = setup_bake(sheet, frames=frames, cells=40, cache_dir=tmp_path / "cache", floor=False)
    s.crumple = False  # the fire only: these tests are about where and when it burns
    s.mat_V0, s.mat_speed_noise, s.mat_duration_noise = FAST, 0.0, 0.0
    return sheet


def _x(sheet):
    return np.array([v.co.x for v in sheet.data.vertices])


def _group(sheet, name, weights):
    g = sheet.vertex_groups.new(name=name)
    for i, w in enumerate(weights):
        if w > 0:
            g.add([i], float(w), "REPLACE")
    return g


def _attribute(sheet, name, values, kind="FLOAT"):
    attr = sheet.data.attributes.new(name, kind, "POINT")
    attr.data.foreach_set("value", np.asarray(values, dtype=np.float32 if kind == "FLOAT" else bool))
    return attr


def _corner_igniter(sheet):
    coll = bpy.data.collections.new("Igniters")
    bpy.context.scene.collection.children.link(coll)
    sheet.thinburn.igniter_collection = coll
    empty = bpy.data.objects.new("Igniter", None)
    coll.objects.link(empty)
    empty.location = (-0.1, -0.1, 0.0)
    empty.thinburn_igniter.radius = 0.02
    return empty


def test_firebreak_group_stops_the_fire(addon, tmp_path):
    sheet = _sheet(tmp_path)
    x = _x(sheet)
    _group(sheet, "speed", np.where(np.abs(x) < 0.004, 0.0, 1.0))  # the middle column painted 0
    sheet.thinburn.speed_map = "speed"
    _corner_igniter(sheet)
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    ignite = point_attribute(sheet, "thinburn_ignite_time")
    never = addon.cache.NEVER_FRAME
    # The near half burns within 48 frames (0.1 m at 0.1 m/s: 1 s); behind the break, nothing.
    assert (ignite[x < -0.015] < never).all()
    assert (ignite[x > 0.015] >= never).all()


def test_fuel_attribute_lengthens_burning(addon, tmp_path):
    sheet = _sheet(tmp_path, frames=60)
    x = _x(sheet)
    _attribute(sheet, "fuel", np.where(x > 0.0, 3.0, 1.0))
    sheet.thinburn.fuel_map_from = "ATTRIBUTE"
    sheet.thinburn.fuel_map = "fuel"
    sheet.thinburn.mat_burn_duration = 0.25  # s: 6 frames; 18 on the painted half
    _corner_igniter(sheet)
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    ignite = point_attribute(sheet, "thinburn_ignite_time")
    burning = point_attribute(sheet, "thinburn_burnout_time") - ignite
    fps = bpy.context.scene.render.fps
    lit = ignite < addon.cache.NEVER_FRAME
    assert lit[x < -0.015].all() and lit[x > 0.015].mean() > 0.9
    # Exactly the material's time, and three times it where painted 3 (float32 frames).
    np.testing.assert_allclose(burning[lit & (x < -0.015)], 0.25 * fps, rtol=1e-4)
    np.testing.assert_allclose(burning[lit & (x > 0.015)], 0.75 * fps, rtol=1e-4)


@pytest.mark.parametrize("source", ["GROUP", "ATTRIBUTE"])
def test_ignite_map_lights_the_painted_spot(addon, tmp_path, source):
    sheet = _sheet(tmp_path, frames=12)
    co = np.array([v.co for v in sheet.data.vertices])
    spot = np.linalg.norm(co[:, :2] - [0.05, 0.05], axis=1) < 0.015
    if source == "GROUP":
        _group(sheet, "start", spot.astype(float))
    else:
        _attribute(sheet, "start", spot, kind="BOOLEAN")
    s = sheet.thinburn
    s.ignite_map_from, s.ignite_map, s.ignite_frame = source, "start", 4
    assert bpy.ops.thinburn.bake() == {"FINISHED"}  # no igniter collection needed
    ignite = point_attribute(sheet, "thinburn_ignite_time")
    np.testing.assert_allclose(ignite[spot], 4.0, atol=1e-4)  # lit at the Ignite Frame itself
    # The rest later, by the front's travel from the painted spot's edge (0.1 m/s: 2.4 frames
    # a cm); measured within 1.37 frames of the closed form: the painted edge lies somewhere
    # between vertices 1 cm apart (the map's 0.5 level), +-0.5 cm = +-1.2 frames.
    dist = np.linalg.norm(co[:, :2] - [0.05, 0.05], axis=1)
    lit = (ignite < addon.cache.NEVER_FRAME) & ~spot
    expect = 4.0 + (dist[lit] - 0.015) / (FAST / 1000) * 24
    np.testing.assert_allclose(ignite[lit], expect, atol=1.5)


def test_mesh_igniter_lights_the_cells_near_its_surface(addon, tmp_path):
    sheet = _sheet(tmp_path, frames=10)
    coll = bpy.data.collections.new("Igniters")
    bpy.context.scene.collection.children.link(coll)
    sheet.thinburn.igniter_collection = coll
    # A 4 cm x 2 cm bar lying 5 mm above the sheet's middle, lit from frame 5.
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.0, 0.0, 0.015))
    bar = bpy.context.active_object
    bar.scale = (0.04, 0.02, 0.02)
    bpy.context.view_layer.update()
    for c in list(bar.users_collection):
        c.objects.unlink(bar)
    coll.objects.link(bar)
    bar.thinburn_igniter.radius = 0.008
    bar.thinburn_igniter.strength = 0.0
    bar.keyframe_insert("thinburn_igniter.strength", frame=4)
    bar.thinburn_igniter.strength = 1.0
    bar.keyframe_insert("thinburn_igniter.strength", frame=5)
    bpy.context.view_layer.objects.active = sheet
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    ignite = point_attribute(sheet, "thinburn_ignite_time")
    co = np.array([v.co for v in sheet.data.vertices])
    under = (np.abs(co[:, 0]) <= 0.02) & (np.abs(co[:, 1]) <= 0.01)
    np.testing.assert_allclose(ignite[under], 5.0, atol=1e-4)  # within 8 mm of its bottom face
    # Nothing before it lit, and the corners (7 cm and more from it) not before frame 5 + 7 cm / v.
    assert (ignite >= 5.0 - 1e-4).all()
    # Farther out, lit by the front from the bar's footprint (8 mm beyond its edges).
    gap = np.hypot(np.maximum(np.abs(co[:, 0]) - 0.02, 0), np.maximum(np.abs(co[:, 1]) - 0.01, 0))
    lit = (ignite < addon.cache.NEVER_FRAME) & (gap > 0.012)
    expect = 5.0 + (gap[lit] - 0.008) / (FAST / 1000) * 24
    # Measured within 0.72 frame of the closed form (a 5 mm cell is 1.2 frames).
    assert lit.sum() > 20
    np.testing.assert_allclose(ignite[lit], expect, atol=1.0)


@pytest.mark.parametrize("case,message", [
    ("group_missing", "Speed map: 'nope' is not a vertex group of 'Sheet'"),
    ("attribute_missing", "Fuel map: 'Sheet' has no attribute 'nope'"),
    ("attribute_negative", "Speed map: attribute 'neg' holds -1"),
    ("ignite_frame", "Ignite Frame 99 is outside the bake's frames 1–12"),
])
def test_map_errors_name_the_setting(addon, tmp_path, case, message):
    sheet = _sheet(tmp_path, frames=12)
    _corner_igniter(sheet)
    s = sheet.thinburn
    if case == "group_missing":
        s.speed_map = "nope"
    elif case == "attribute_missing":
        s.fuel_map_from, s.fuel_map = "ATTRIBUTE", "nope"
    elif case == "attribute_negative":
        _attribute(sheet, "neg", np.full(N * N, -1.0))
        s.speed_map_from, s.speed_map = "ATTRIBUTE", "neg"
    else:
        _group(sheet, "start", np.ones(N * N))
        s.ignite_map, s.ignite_frame = "start", 99
    with pytest.raises(RuntimeError) as info:
        bpy.ops.thinburn.bake()
    assert message in str(info.value)
    assert "Traceback" not in str(info.value)


@pytest.mark.parametrize("target,crumple", [(1.5, True), (3.0, False)])
def test_burn_duration_times_the_whole_burn(addon, tmp_path, target, crumple):
    # Paper at its own 3.5 mm/s would take over a minute to cross 20 cm; asked for 1.5 s (or 3 s)
    # from the first flame, the last cell burns out then (the issue: within 10 %).
    sheet = make_sheet(n=N, size=0.2, z=0.0)
    s = setup_bake(sheet, frames=int(target * 24 * 1.5), cells=32, cache_dir=tmp_path / "cache")
    s.crumple = crumple
    s.burn_duration = target
    _corner_igniter(sheet).thinburn_igniter.radius = 0.01
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    ignite = point_attribute(sheet, "thinburn_ignite_time")
    burnout = point_attribute(sheet, "thinburn_burnout_time")
    assert (ignite < addon.cache.NEVER_FRAME).all()
    fps = bpy.context.scene.render.fps
    taken = (burnout.max() - ignite.min()) / fps
    # Measured 0.983 (1.5 s, moving) and 0.982 (3 s, fire only) of the target.
    assert taken / target == pytest.approx(0.99, abs=0.04)


def test_cycles_render_shows_the_firebreak(addon, tmp_path):
    """A 160x120 Cycles frame (4 samples) of a sheet with a painted firebreak down its middle:
    char on the lit half, the far half as clean as before the fire."""
    sheet = make_sheet(n=41, size=0.2, z=0.0)
    s = setup_bake(sheet, frames=60, cells=48, cache_dir=tmp_path / "cache")
    s.crumple = False  # the shading is the point: keep the sheet flat in the camera
    s.burnt = "ASH"    # burnt-out parts stay as black char
    s.mat_V0, s.mat_burn_duration, s.mat_duration_noise = FAST, 0.5, 0.0
    x = _x(sheet)
    _group(sheet, "speed", np.where(np.abs(x) < 0.003, 0.0, 1.0))
    s.speed_map = "speed"
    _corner_igniter(sheet)
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    scene = bpy.context.scene
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.data.type, cam.data.ortho_scale, cam.location = "ORTHO", 0.2, (0.0, 0.0, 2.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 3.0
    scene.collection.objects.link(sun)
    scene.world = bpy.data.worlds.new("World")
    r = scene.render
    r.engine, r.resolution_x, r.resolution_y, r.resolution_percentage = "CYCLES", 160, 120, 100
    r.image_settings.file_format = "PNG"
    scene.view_settings.view_transform = "Standard"
    scene.cycles.device, scene.cycles.samples, scene.cycles.use_denoising = "CPU", 4, False

    def luminance(name, frame):
        scene.frame_set(frame)
        r.filepath = str(tmp_path / name)
        bpy.ops.render.render(write_still=True)
        img = bpy.data.images.load(r.filepath)
        px = np.array(img.pixels[:], dtype=np.float32).reshape(img.size[1], img.size[0], 4)[::-1, :, :3]
        bpy.data.images.remove(img)
        return px @ np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)

    before, after = luminance("before.png", 1), luminance("after.png", 60)
    lit_half = (slice(30, 90), slice(20, 60))   # x < -0.025 m (the camera sees 0.2 m in 160 px)
    far_half = (slice(30, 90), slice(100, 140))  # x > 0.025 m, behind the firebreak
    # Measured: the lit half 0.911 -> 0.196 (black char), the far half 0.911 -> 0.911 (pictures
    # in tmp_path: before.png, after.png).
    assert after[lit_half].mean() < 0.3 * before[lit_half].mean(), tmp_path
    assert after[far_half].mean() == pytest.approx(before[far_half].mean(), rel=0.01), tmp_path


@pytest.mark.parametrize("heat", [True, False])
def test_heat_ignites_climbs_a_stack(addon, tmp_path, heat):
    """Two 15 cm paper sheets 1 cm apart in one mesh, the upper one pinned: lit at the lower
    one's centre, the heat lights the upper one (Heat Ignites), or nothing crosses the gap."""
    from blender_helpers import make_stack
    sheet = make_stack(name="Sheet", size=0.15, gap=0.01, sheets=2, n=17, shift=0.0)
    s = setup_bake(sheet, frames=60, cells=24, cache_dir=tmp_path / "cache")
    z = np.array([v.co.z for v in sheet.data.vertices])
    pins = sheet.vertex_groups.new(name="pins")
    pins.add([int(i) for i in np.flatnonzero(z > 0.005)], 1.0, "REPLACE")
    s.pin_group = "pins"
    s.heat_ignites = heat
    coll = bpy.data.collections.new("Igniters")
    bpy.context.scene.collection.children.link(coll)
    s.igniter_collection = coll
    empty = bpy.data.objects.new("Igniter", None)
    coll.objects.link(empty)
    empty.thinburn_igniter.radius = 0.008  # the lower sheet only (the upper is 1 cm away)
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    ignite = point_attribute(sheet, "thinburn_ignite_time")
    upper_lit = ignite[z > 0.005] < addon.cache.NEVER_FRAME
    if heat:
        # Measured: the upper sheet's first vertex lights at frame 28 (the core alone: 1.17 s).
        assert upper_lit.any() and ignite[z > 0.005].min() < 1 + 2.5 * 24
    else:
        assert not upper_lit.any()


@pytest.mark.parametrize("source", ["GROUP", "ATTRIBUTE"])
def test_painted_panel_draws_its_maps(addon, source):
    from test_addon import _Context, _Layout
    sheet = make_sheet()
    s = sheet.thinburn
    s.enabled = True
    for key in ("speed_map", "fuel_map", "ignite_map"):
        setattr(s, key + "_from", source)
    drawn = []
    panel = addon.panels.PHYSICS_PT_thinburn_painted
    assert panel.poll(_Context(sheet))
    panel.draw(type("P", (), {"layout": _Layout(drawn)})(), _Context(sheet))
    addon.panels.PHYSICS_PT_thinburn.draw(type("P", (), {"layout": _Layout(drawn)})(), _Context(sheet))
    for name in ("speed_map", "speed_map_from", "fuel_map", "fuel_map_from", "ignite_map",
                 "ignite_map_from", "ignite_frame", "burn_duration", "heat_ignites"):
        assert name in drawn, name


@pytest.mark.parametrize("candle_x", [0.0, 0.65])
def test_a_flame_igniter_lights_a_curtain(addon, tmp_path, candle_x):
    """A 30 cm curtain hanging from its top edge with Heat Ignites, and an Empty of Kind Flame
    (a candle, 1 cm wide) 3 cm under its bottom edge's middle, or 50 cm beside it."""
    from blender_helpers import link_mesh
    n = 25
    xs = np.linspace(-0.15, 0.15, n)
    zs = np.linspace(0.10, 0.40, n)
    verts = [(x, 0.0, z) for z in zs for x in xs]
    faces = [(j * n + i, j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i)
             for j in range(n - 1) for i in range(n - 1)]
    curtain = link_mesh("Sheet", verts, faces)
    s = setup_bake(curtain, frames=120, cells=32, cache_dir=tmp_path / "cache", floor=False)
    s.material = "curtain"
    top = curtain.vertex_groups.new(name="top")
    top.add(list(range(n * (n - 1), n * n)), 1.0, "REPLACE")
    s.pin_group = "top"
    s.heat_ignites = True
    candle = _corner_igniter(curtain)
    candle.location = (candle_x, 0.0, 0.07)
    candle.thinburn_igniter.kind = "FLAME"
    candle.thinburn_igniter.radius = 0.005
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    ignite = point_attribute(curtain, "thinburn_ignite_time")
    lit = ignite < addon.cache.NEVER_FRAME
    if candle_x == 0.0:
        # Measured: first lit at frame 74 (3.04 s; the core alone: 3.08 s).
        assert lit.any() and 1 + 2 * 24 < ignite.min() < 1 + 5 * 24
    else:
        assert not lit.any()
