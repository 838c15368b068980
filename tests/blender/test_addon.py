"""Registration, the properties' contract with the core, and the fire-particle output."""
from __future__ import annotations

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytestmark = pytest.mark.blender

from blender_helpers import ROOT, make_sheet  # noqa: E402


def test_registers_properties_operators_and_panels(addon):
    import thinburn
    obj = make_sheet()
    for name in ("material", "igniter_collection", "frame_start", "frame_end", "cache_dir",
                 "pin_group", "cells", "lattice", "enabled", "floor_mode"):
        assert hasattr(obj.thinburn, name), name
    assert hasattr(obj.thinburn_igniter, "strength") and hasattr(obj.thinburn_igniter, "radius")
    assert hasattr(bpy.ops.thinburn, "bake") and hasattr(bpy.ops.thinburn, "free_bake")
    assert hasattr(bpy.types, "PHYSICS_PT_thinburn")
    items = obj.thinburn.bl_rna.properties["material"].enum_items.keys()
    assert list(items) == list(thinburn.MATERIALS)
    assert obj.thinburn.cache_dir == "//thinburn_cache/"


def test_every_property_has_a_real_description(addon):
    for group in (addon.properties.ThinBurnSettings, addon.properties.ThinBurnIgniter):
        for prop in group.bl_rna.properties:
            if prop.identifier in {"rna_type", "name"}:
                continue
            assert len(prop.description) > 20, f"{group.__name__}.{prop.identifier}"


def test_only_per_frame_inputs_are_animatable(addon):
    props = addon.properties.ThinBurnSettings.bl_rna.properties
    animatable = {p.identifier for p in props if p.is_animatable and p.identifier != "rna_type"}
    assert animatable - {"name"} == {"wind_scale", *addon.properties.DYNAMIC_PARAMS}
    ig = addon.properties.ThinBurnIgniter.bl_rna.properties
    assert ig["strength"].is_animatable and ig["radius"].is_animatable


def test_material_preset_fills_the_fields_and_reaches_the_core(addon):
    import thinburn
    obj = make_sheet()
    obj.thinburn.material = "cloth"
    cloth = thinburn.MATERIALS["cloth"]
    assert obj.thinburn.mat_V0 == pytest.approx(cloth.V0)
    assert obj.thinburn.mat_burn_duration == pytest.approx(cloth.burn_duration)
    # Bending Rigidity shows µN·m: the cloth's 5e-6 N m is 5 in the panel.
    assert obj.thinburn.mat_flexural_rigidity == pytest.approx(cloth.flexural_rigidity * 1e6, rel=1e-6)
    obj.thinburn.mat_V0 = 7.0
    obj.thinburn.mat_flexural_rigidity = 60.0
    built = addon.properties.build_material(obj.thinburn)
    assert built.V0 == pytest.approx(7.0) and built.K_flex == pytest.approx(cloth.K_flex)
    assert built.flexural_rigidity == pytest.approx(6e-5, rel=1e-6)


def test_a_new_preset_keeps_the_fields_the_artist_set(addon):
    """A Spread Speed set for the shot survives a change of Burns Like; the other fields take
    the new preset's values, the panel names the kept one, and Reset to Preset loads it too."""
    import bpy
    import thinburn
    obj = make_sheet()
    s = obj.thinburn
    s.mat_V0 = 25.0  # paper's is 3.5 mm/s
    assert addon.properties.edited_fields(s, "paper") == ["V0"]
    s.material = "cloth"
    cloth = thinburn.MATERIALS["cloth"]
    assert s.mat_V0 == pytest.approx(25.0)
    assert s.mat_burn_duration == pytest.approx(cloth.burn_duration)
    assert s.mat_mass == pytest.approx(cloth.mass / addon.properties.MATERIAL_UNITS.get("mass", 1.0))
    assert addon.properties.edited_fields(s, "cloth") == ["V0"]
    drawn = []
    addon.panels.PHYSICS_PT_thinburn.draw(type("P", (), {"layout": _Layout(drawn)})(), _Context(obj))
    assert "label: Your own: Spread Speed (Advanced > Reset to Preset)" in drawn
    s.material = "silk"  # still the artist's, through a second change
    assert s.mat_V0 == pytest.approx(25.0)
    with bpy.context.temp_override(object=obj, active_object=obj):
        bpy.ops.thinburn.load_preset()
    assert s.mat_V0 == pytest.approx(thinburn.MATERIALS["silk"].V0)
    assert addon.properties.edited_fields(s, "silk") == []
    # A sheet from a file saved before the loaded preset was kept: its fields match cloth's.
    old = make_sheet()
    addon.properties.load_preset(old.thinburn, "cloth")
    old.thinburn.material_loaded = ""
    old.thinburn.material = "silk"
    assert addon.properties.edited_fields(old.thinburn, "silk") == []


def test_model_parameter_defaults_match_the_core(addon):
    import thinburn
    verts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=float)
    sim = thinburn.Simulation(verts, [[0, 1, 2], [1, 3, 2]], cells=8)
    obj = make_sheet()
    for key in addon.properties.MODEL_PARAMS:
        assert getattr(obj.thinburn, key) == pytest.approx(getattr(sim.params, key)), key
    for key in addon.properties.DYNAMIC_PARAMS:
        assert getattr(obj.thinburn, key) == pytest.approx(sim.params.dynamics[key]), key
    assert obj.thinburn.integrator == sim.params.dynamics["integrator"]


def test_manifest_and_bl_info(addon):
    import tomllib
    manifest = tomllib.loads((ROOT / "blender_addon" / "blender_manifest.toml").read_text())
    assert manifest["id"] == "thinburn" and manifest["type"] == "add-on"
    assert tuple(int(x) for x in manifest["blender_version_min"].split(".")) >= (4, 2, 0)
    assert addon.bl_info["blender"] >= (4, 2, 0)
    assert callable(addon.register) and callable(addon.unregister)


def _modifier_input(obj, name):
    md = obj.modifiers["ThinBurn Fire"]
    ident = {s.name: s.identifier for s in md.node_group.interface.items_tree
             if getattr(s, "in_out", "") == "INPUT"}
    return md, ident[name]


def test_fire_particles_become_flames_and_a_light(addon, tmp_path):
    """The output path for thinburn.Simulation.particles, fed with known particles: the fire
    object is a volume with density, tb_temperature and tb_flame grids; its Output 2 shows the
    hot particles as points carrying the core's temperature; the light object is glowing
    spheres hidden from the camera."""
    sheet = make_sheet()
    rng = np.random.default_rng(1)
    frames = []
    for k in (3, 0, 5):  # K above ambient; below MIN_TEMPERATURE a particle is left out
        frames.append((rng.uniform(-0.1, 0.1, size=(k, 3)).astype(np.float32),
                       np.linspace(100.0, 900.0, k, dtype=np.float32)))
    pc2 = str(tmp_path / "Sheet.pc2")
    addon.fire.apply_particles(sheet, pc2, frames, frame_start=1.0)
    fire = bpy.data.objects["ThinBurn Fire Sheet"]
    light = bpy.data.objects["ThinBurn Fire Light Sheet"]
    assert not light.visible_camera and not light.visible_shadow and light.data is fire.data
    head, data = addon.cache.read_pc2(tmp_path / "Sheet_fire.pc2")
    assert head["points"] == 10 and head["samples"] == 3
    md, output = _modifier_input(fire, "Output")
    for frame, (pos, temp) in enumerate(frames, start=1):
        glowing = temp >= addon.fire.MIN_TEMPERATURE
        pos, temp = pos[glowing], temp[glowing]
        bpy.context.scene.frame_set(frame)
        md[output] = 2
        fire.update_tag()
        dg = bpy.context.evaluated_depsgraph_get()
        geo = bpy.types.GeometrySet.from_evaluated_object(fire.evaluated_get(dg))
        cloud = geo.pointcloud
        count = 0 if cloud is None else len(cloud.points)
        assert count == len(temp)
        if count:
            got_t = np.empty(count, dtype=np.float32)
            cloud.attributes[addon.fire.ATTR_TEMPERATURE].data.foreach_get("value", got_t)
            got_p = np.empty(3 * count, dtype=np.float32)
            cloud.attributes["position"].data.foreach_get("vector", got_p)
            np.testing.assert_allclose(got_t, temp, rtol=1e-6)
            np.testing.assert_allclose(got_p.reshape(-1, 3), pos, atol=1e-6)
        md[output] = 0
        fire.update_tag()
        dg = bpy.context.evaluated_depsgraph_get()
        geo = bpy.types.GeometrySet.from_evaluated_object(fire.evaluated_get(dg))
        if count:
            assert {g.name for g in geo.volume.grids} >= {"density", "tb_temperature", "tb_flame"}
            assert geo.volume.materials[0].name == "ThinBurn Fire"
        lgeo = bpy.types.GeometrySet.from_evaluated_object(light.evaluated_get(dg))
        assert (lgeo.mesh is not None and len(lgeo.mesh.polygons) > 0) == bool(count)
    # the panel's flame settings reach both modifiers
    sheet.thinburn.flame_height = 0.1
    for obj in (fire, light):
        md, key = _modifier_input(obj, "Flame Height")
        assert md[key] == pytest.approx(0.1)
    assert addon.materials.free_bake(sheet)  # the fire objects and their file go with the bake
    assert "ThinBurn Fire Sheet" not in bpy.data.objects
    assert "ThinBurn Fire Light Sheet" not in bpy.data.objects
    assert not (tmp_path / "Sheet_fire.pc2").exists()


class _Layout:
    """Stands in for UILayout: records what a panel draws and checks each property exists."""

    def __init__(self, log):
        self.log = log

    def _sub(self, *args, **kwargs):
        return _Layout(self.log)

    row = column = box = split = _sub

    def prop(self, data, name, **kwargs):
        assert name in data.bl_rna.properties, f"panel draws a missing property {name!r}"
        self.log.append(name)

    def prop_search(self, data, name, search_data, search_name, **kwargs):
        assert name in data.bl_rna.properties and search_name in search_data.bl_rna.properties
        self.log.append(name)

    def operator(self, idname, **kwargs):
        category, op = idname.split(".")
        assert hasattr(getattr(bpy.ops, category), op), idname
        self.log.append(idname)

    def label(self, text="", **kwargs):
        self.log.append("label: " + text)

    def progress(self, **kwargs):
        pass


class _Context:
    def __init__(self, obj):
        self.object = obj
        self.active_object = obj
        self.scene = bpy.context.scene
        self.view_layer = bpy.context.view_layer


def _igniter_collection(sheet):
    coll = bpy.data.collections.new("Igniters")
    bpy.context.scene.collection.children.link(coll)
    sheet.thinburn.igniter_collection = coll
    empty = bpy.data.objects.new("Igniter", None)
    coll.objects.link(empty)
    return empty


def test_panels_draw_existing_properties_and_operators(addon):
    sheet = make_sheet()
    sheet.thinburn.enabled = True
    empty = _igniter_collection(sheet)
    drawn = []
    for obj in (sheet, empty):
        ctx = _Context(obj)
        for cls in addon.panels.CLASSES:
            if not cls.poll(ctx):
                continue
            fake = type("P", (), {"layout": _Layout(drawn)})()
            if hasattr(cls, "draw_header"):
                cls.draw_header(fake, ctx)
            cls.draw(fake, ctx)
    for name in ("enabled", "material", "cells", "lattice", "igniter_collection", "pin_group",
                 "frame_start", "frame_end", "cache_dir", "thinburn.bake", "thinburn.free_bake",
                 "mat_V0", "v_floor", "strength", "radius", "flame_height", "flame_intensity",
                 "flame_temperature", "embers", "thinburn.add_burn_to_material",
                 "thinburn.quick_burn", "thinburn.bake_all"):
        assert name in drawn, name


def test_embers_rise_cool_and_die_deterministically(addon):
    """ember_frames, fed with a steady line of fire particles: sparks are born at the fire,
    rise, cool and die; the same input and seed give the same sparks."""
    rng = np.random.default_rng(3)
    frames = []
    for _ in range(48):
        pos = np.c_[rng.uniform(-0.1, 0.1, 200), np.zeros(200), np.zeros(200)]
        frames.append((pos.astype(np.float32), np.full(200, 850.0, np.float32)))
    sparks = addon.fire.ember_frames(frames, 1 / 24, seed=5)
    again = addon.fire.ember_frames(frames, 1 / 24, seed=5)
    other = addon.fire.ember_frames(frames, 1 / 24, seed=6)
    for (p, t), (q, u) in zip(sparks, again):
        np.testing.assert_array_equal(p, q)
        np.testing.assert_array_equal(t, u)
    assert any(len(t) != len(u) or not np.array_equal(t, u) for (_, t), (_, u) in zip(sparks, other))
    # follow slot 0 from the first frame with a live spark
    start = next(i for i, (_, t) in enumerate(sparks) if len(t) and t[0] > 0)
    life = [(sparks[i][0][0], sparks[i][1][0]) for i in range(start, len(sparks))
            if len(sparks[i][1]) and sparks[i][1][0] > 0]
    born_at = sparks[start][0][0]
    assert abs(born_at[2]) < 1e-6 and abs(born_at[1]) < 1e-6  # on the line of fire
    seen = 1
    for (p0, t0), (p1, t1) in zip(life, life[1:]):
        if t1 > t0:  # the slot was reused by a new spark
            break
        seen += 1
    assert seen >= 10  # lives of 0.8 s and more: 19 frames at 24 fps
    heights = [p[2] for p, _ in life[:seen]]
    temps = [t for _, t in life[:seen]]
    assert heights[-1] > 0.05, heights  # it rose
    assert temps[-1] < 0.7 * temps[0]   # and cooled
    alive = [int((t > 0).sum()) for _, t in sparks]
    # about 200 young particles * 0.02 = 4 sparks a frame living ~1.4 s: 100-150 at once
    assert 40 < alive[-1] < 300, alive[-1]


def test_a_fire_group_and_material_from_an_older_add_on_are_replaced(addon, tmp_path):
    """A .blend baked with the first add-on has a "ThinBurn Fire" group without the Output
    input and a material reading `temperature`; a new bake must not reuse them."""
    old_group = bpy.data.node_groups.new("ThinBurn Fire", "GeometryNodeTree")
    old_mat = bpy.data.materials.new("ThinBurn Fire")
    sheet = make_sheet()
    frames = [(np.zeros((2, 3), np.float32), np.full(2, 800.0, np.float32))]
    addon.fire.apply_particles(sheet, str(tmp_path / "Sheet.pc2"), frames, frame_start=1.0)
    fire = bpy.data.objects["ThinBurn Fire Sheet"]
    md = fire.modifiers["ThinBurn Fire"]
    assert md.node_group is not old_group and old_group.name == "ThinBurn Fire (old)"
    assert md.node_group.name == "ThinBurn Fire"
    assert old_mat.name == "ThinBurn Fire (old)"
    assert addon.fire.fire_material() is not old_mat


def test_panels_appear_only_where_they_apply(addon):
    # Issue #14: ThinBurn panels showed on every mesh and every Empty.
    sheet = make_sheet()
    igniter = _igniter_collection(sheet)
    stray = bpy.data.objects.new("Stray", None)
    bpy.context.scene.collection.objects.link(stray)
    shown = lambda obj: {c.__name__ for c in addon.panels.CLASSES if c.poll(_Context(obj))}
    assert shown(sheet) == {"PHYSICS_PT_thinburn"}  # off: only the panel whose header enables it
    sheet.thinburn.enabled = True
    assert {"PHYSICS_PT_thinburn", "PHYSICS_PT_thinburn_cache"} <= shown(sheet)
    assert "OBJECT_PT_thinburn_igniter" not in shown(sheet)
    assert shown(igniter) == {"OBJECT_PT_thinburn_igniter"}
    assert shown(stray) == set()


def _panel_text(addon, obj) -> str:
    drawn = []
    ctx = _Context(obj)
    for cls in addon.panels.CLASSES:
        if cls.poll(ctx):
            cls.draw(type("P", (), {"layout": _Layout(drawn)})(), ctx)
    return " ".join(d[len("label: "):] for d in drawn if d.startswith("label: "))


def test_the_panel_warns_of_a_floor_under_a_moving_sheet_and_of_fields_it_ignores(addon):
    # Issue #14: an animated sheet never burnt, and a Wind field's falloff and noise were
    # ignored. Both are used now; what is left is said: a Floor the motion may not allow,
    # a field shape and field kinds that do not blow on sheets.
    sheet = make_sheet()
    sheet.thinburn.enabled = True
    sheet.keyframe_insert("location", frame=1)
    bpy.ops.object.effector_add(type="WIND")
    wind = bpy.context.active_object
    wind.name = "Breeze"
    wind.field.noise = 2.0
    wind.field.falloff_power = 1.5
    bpy.ops.object.effector_add(type="TURBULENCE")
    bpy.context.active_object.name = "Gusts"
    assert addon.panels.sheet_warnings(bpy.context, sheet) == []  # all of it is used
    sheet.thinburn.floor_mode = "HEIGHT"
    wall = make_sheet("Wall")  # a mesh's own field can blow from its surface: not used
    bpy.ops.object.forcefield_toggle()  # on the active object, the wall
    wall.field.type = "WIND"
    wall.field.shape = "SURFACE"
    bpy.context.view_layer.objects.active = sheet
    bpy.ops.object.effector_add(type="VORTEX")
    bpy.context.active_object.name = "Swirl"
    text = " ".join(_panel_text(addon, sheet).split())
    assert "'Sheet' moves in the scene (its location (animated)) and has a Floor" in text
    assert "set Floor to None" in text
    assert "Wind 'Wall': its Shape (Surface) is not used" in text
    assert "'Swirl' (a Vortex field) does not act on ThinBurn sheets" in text
    assert "Gusts" not in text


def test_settings_speak_an_artists_words_and_keep_the_papers_in_tooltips(addon):
    # Issue #14: "Material" meant a physics preset, "Strength" was on/off, "Slope Factor",
    # "Max Drive". The identifiers stay (saved files and keyframes use them); the labels change.
    props = addon.properties.ThinBurnSettings.bl_rna.properties
    igniter = addon.properties.ThinBurnIgniter.bl_rna.properties
    expect = {
        (props, "material"): ("Burns Like", "Table 1"),
        (props, "mat_Cv"): ("Slows on Curves", "slope factor Cv"),
        (props, "max_drive"): ("Climb and Wind Limit", "max_drive"),
        (props, "v_floor"): ("Slowest Spread", "v_floor"),
        (props, "cells"): ("Fire Detail", "fire cells"),
        (props, "lattice"): ("Motion Detail", "lattice"),
        (props, "mat_Cp"): ("Shrink When Burning", "Cp"),
        (igniter, "strength"): ("Lit", "strength"),
    }
    for (group, ident), (label, paper) in expect.items():
        assert group[ident].name == label, ident
        assert paper in group[ident].description, ident
