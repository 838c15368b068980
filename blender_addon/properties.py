"""Settings stored on objects: ``obj.thinburn`` (a sheet) and ``obj.thinburn_igniter``.

Only properties that the bake reads frame by frame are animatable (igniter strength, radius
and transform, the wind scale); the rest are read once at the bake's first frame and are
not offered for keyframing, so the UI never suggests an animation the bake would ignore.
"""
import math

import bpy
import thinburn
from thinburn.params import FIELDS as PARAM_FIELDS
from bpy.props import (BoolProperty, CollectionProperty, EnumProperty, FloatProperty, IntProperty,
                       PointerProperty, StringProperty)

STATIC = set()  # options=STATIC: not animatable (read once per bake)
# Blender 4.5+ warns about '//' in path properties that do not declare they accept it.
RELATIVE_PATH = {"PATH_SUPPORTS_BLEND_RELATIVE"} if bpy.app.version >= (4, 5, 0) else set()

# Material fields the panel exposes (thinburn.Material), with their UI text.
MATERIAL_FIELDS = {
    "mass": ("Mass", "Areal density in Table 1's unit of 0.1 kg/m² (paper 0.45 = 45 g/m²)", 0.001, 100.0),
    "V0": ("Spread Speed", "How fast the fire spreads over a flat, level sheet, mm/s (Table 1, V0 of eq. 1)", 0.001, 1000.0),
    "Cv": ("Slows on Curves", "How much a curved or tilted sheet slows the fire: V = V0·(1 − Cv·grad²) (the paper's slope factor Cv, eq. 1)", 0.0, 10.0),
    "burn_duration": ("Burn Time per Cell", "Seconds a spot of the sheet keeps burning after the front reaches it (a fire cell's burn duration)", 0.01, 600.0),
    "speed_noise": ("Speed Noise", "Random per-cell jitter of the spread speed, relative; breaks up grid-aligned fronts", 0.0, 0.9),
    "duration_noise": ("Duration Noise", "Random per-cell jitter of the burn duration, relative", 0.0, 0.9),
    "ash_fraction": ("Ash Fraction", "Share of its mass a burnt cell keeps as ash", 0.0, 1.0),
    "Cp": ("Shrink When Burning", "How strongly burning material shrinks and curls (pyrolysis: Table 1, Cp of eq. 3)", 0.0, 100.0),
    "C_damping": ("Damping", "Damping of the sheet's motion (Table 1, eq. 12)", 0.0, 100.0),
    "K_structure": ("Stretch Stiffness", "How hard the sheet resists stretching (the lattice's structure springs, Table 1)", 0.0, 100.0),
    "K_shear": ("Shear Stiffness", "Stiffness of the lattice's shear springs (Table 1)", 0.0, 100.0),
    "K_flex": ("Flex Stiffness", "Stiffness of the lattice's two-apart springs (Table 1); with a Bending Rigidity set, the sheet bends with that instead", 0.0, 100.0),
    "flexural_rigidity": ("Bending Rigidity", "The sheet's own bending stiffness in µN·m (a plate's E·t³/12): cloth 5, silk 3, curtain 20. 0 bends with the lattice's own layers, about 100× a real paper's (the paper preset: a soft paper lifts off its table in a breeze)", 0.0, 1e6),
    "strain_limit": ("Stretch Limit", "The most, in %, that the unburnt sheet may stretch or squash: a heavy, soft fabric otherwise sags out of shape under its own weight. 0 lets the springs alone decide", 0.0, 99.0),
}
# Fields shown in another unit than the core's: the core's value is the panel's times this.
MATERIAL_UNITS = {"flexural_rigidity": 1e-6,  # µN·m in the panel, N·m in the core
                  "strain_limit": 0.01}  # % in the panel, a fraction in the core


def _default(group: str, key: str) -> float:
    """The core's default of a parameter (its table, thinburn.params)."""
    return float(PARAM_FIELDS[group][key].default)


def _high(key: str) -> float:
    """The core's upper bound of a fire parameter."""
    return PARAM_FIELDS["simulation"][key].high


# Motion parameters read every frame (keyframeable) and passed to Simulation.set_dynamics
# when they change; defaults are the core's (a test checks a paper Simulation's). Gravity comes from the scene.
DYNAMIC_PARAMS = {
    "buoyancy": ("Buoyancy", "Lift of hot material: N/kg per unit of heat, along world +Z", _default("dynamics", "buoyancy"), 0.0, 100.0),
    "wind_drag": ("Wind Drag", "How hard the wind pushes on the sheet, Pa·s/m (force per area per m/s of relative wind)", _default("dynamics", "wind_drag"), 0.0, 100.0),
    "friction": ("Friction", "Coulomb friction of the sheet on the floor", _default("dynamics", "friction"), 0.0, 10.0),
    "crumple_gain": ("Crumple Amount", "Multiplies how much the burn's bending turns into crumpling motion (the core's crumple_gain)", _default("dynamics", "crumple_gain"), 0.0, 10.0),
}

# Model scalars passed as Simulation(**params); defaults and upper bounds are the core's
# (a test checks a paper Simulation's defaults).
MODEL_PARAMS = {
    "v_floor": ("Slowest Spread", "The slowest the fire may spread on a steep fold, as a share of Spread Speed, so folds still burn (the core's v_floor)", _default("simulation", "v_floor"), 0.001, 1.0),
    "climb": ("Climb", "How much faster flames run uphill along the sheet; 0 is the paper's symmetric spread", _default("simulation", "climb"), 0.0, _high("climb")),
    "wind_spread": ("Wind Spread", "Extra push on the front per m/s of wind along the sheet", _default("simulation", "wind_spread"), 0.0, 100.0),
    "max_drive": ("Climb and Wind Limit", "Caps how much Climb and Wind Spread speed up the fire one way, so the fire never stalls on the other (the core's max_drive)", _default("simulation", "max_drive"), 0.0, _high("max_drive")),
}


# Where a painted map comes from (Physics > ThinBurn > Painted).
MAP_SOURCES = [("GROUP", "Vertex Group", "Weights painted in Weight Paint mode (unassigned vertices: 0)", 0),
               ("ATTRIBUTE", "Attribute", "A Float attribute on the vertices (Point domain)", 1)]


def _describe(name: str, m) -> str:
    fig = f", the paper's figure {m.figure}" if getattr(m, "figure", 0) else ""
    return (f"Table 1 preset '{name}'{fig}: mass {m.mass}, V0 {m.V0} mm/s, Cp {m.Cp}, "
            f"damping {m.C_damping}, stiffness {m.K_structure}/{m.K_shear}/{m.K_flex}")


_MATERIAL_ITEMS = [(name, name.replace("_", " ").title(), _describe(name, m), i)
                   for i, (name, m) in enumerate(thinburn.MATERIALS.items())]


def _preset_value(preset, field: str) -> float:
    return getattr(preset, field) / MATERIAL_UNITS.get(field, 1.0)


def edited_fields(settings, name: str) -> list:
    """The material fields whose values differ from preset ``name``'s: the artist's own. The
    fields are stored as single floats, so a value within a part in a million is the preset's."""
    preset = thinburn.MATERIALS[name]
    out = []
    for field in MATERIAL_FIELDS:
        if hasattr(preset, field):
            want = _preset_value(preset, field)
            if abs(getattr(settings, "mat_" + field) - want) > 1e-6 * max(abs(want), 1e-12):
                out.append(field)
    return out


def load_preset(settings, name: str, keep=()) -> None:
    """Copy a Table 1 preset into the sheet's material fields, all but those in ``keep``."""
    preset = thinburn.MATERIALS[name]
    for field in MATERIAL_FIELDS:
        if hasattr(preset, field) and field not in keep:
            setattr(settings, "mat_" + field, _preset_value(preset, field))
    settings.material_loaded = name


def _on_material(self, context):
    # A field the artist changed from the last preset's value (a Spread Speed set for the shot)
    # is kept when another preset is chosen; the panel lists those, and Reset to Preset loads
    # them all. Loaded over, a speed set before the preset was silently lost.
    load_preset(self, self.material, keep=edited_fields(self, _loaded_preset(self)))


def _loaded_preset(settings) -> str:
    """The preset the material fields were last loaded from. A sheet from a file saved before
    that was kept: the preset its fields match best (a new sheet's are paper's)."""
    if settings.material_loaded in thinburn.MATERIALS:
        return settings.material_loaded
    return min(thinburn.MATERIALS, key=lambda name: len(edited_fields(settings, name)))


def build_material(settings):
    """The thinburn.Material the bake uses: the preset with the panel's field values."""
    preset = thinburn.MATERIALS[settings.material]
    changes = {f: getattr(settings, "mat_" + f) * MATERIAL_UNITS.get(f, 1.0)
               for f in MATERIAL_FIELDS if hasattr(preset, f)}
    return preset.with_(**changes)


def _on_flame(self, context):
    from . import fire  # bpy-heavy; imported when a flame setting changes
    fire.sync_flame_settings(self.id_data)


def _on_burnt(self, context):
    from . import materials
    materials.sync_burnt(self.id_data)


def _crease_angle_default():
    """The core's crease_angle in radians; 180° (no creases) for a core from before them."""
    field = PARAM_FIELDS["simulation"].get("crease_angle")
    return math.radians(field.default) if field is not None else math.pi


def _field_props():
    props = {}
    default = thinburn.MATERIALS["paper"]
    for field, (label, desc, lo, hi) in MATERIAL_FIELDS.items():
        props["mat_" + field] = FloatProperty(
            name=label, description=desc,
            default=float(getattr(default, field, lo)) / MATERIAL_UNITS.get(field, 1.0),
            min=lo, soft_max=hi, options=STATIC)
    for key, (label, desc, value, lo, hi) in MODEL_PARAMS.items():
        props[key] = FloatProperty(name=label, description=desc, default=value, min=lo, max=hi,
                                   options=STATIC)
    for key, (label, desc, value, lo, hi) in DYNAMIC_PARAMS.items():
        props[key] = FloatProperty(name=label, description=desc + "; read every frame",
                                   default=value, min=lo, soft_max=hi)
    return props


class ThinBurnBakedFile(bpy.types.PropertyGroup):
    """A file a bake wrote (a path as the modifier has it: '//' stays relative)."""

    path: StringProperty(name="Path", subtype="FILE_PATH", options=RELATIVE_PATH,
                         description="A cache file the sheet's bake wrote; Free Bake deletes it")


class ThinBurnBakedObject(bpy.types.PropertyGroup):
    """An object a bake made (flames, their light, embers, ash flakes)."""

    object: PointerProperty(name="Object", type=bpy.types.Object,
                            description="An object the sheet's bake made; Free Bake removes it")


class ThinBurnSettings(bpy.types.PropertyGroup):
    """A burning sheet: what the Physics panel edits and the bake reads."""

    enabled: BoolProperty(
        name="ThinBurn", default=False, options=STATIC,
        description="Burn this mesh as a thin sheet with ThinBurn")
    material: EnumProperty(
        name="Burns Like", items=_MATERIAL_ITEMS, default="paper", update=_on_material, options=STATIC,
        description="What the sheet burns and moves like: a preset of Table 1 of Liu et al. 2009 "
                    "(the paper's 'material'); choosing one loads its values into Advanced > "
                    "Burns Like")
    material_loaded: StringProperty(
        name="Preset Loaded", default="", options={"HIDDEN"},
        description="The Burns Like preset whose values the material fields were last loaded "
                    "from: a field that differs from it is the artist's own and is kept")
    cells: IntProperty(
        name="Fire Detail", default=128, min=8, max=1024, soft_max=512, options=STATIC,
        description="How finely the fire spreads: a flat sheet is divided into this many fire "
                    "cells per side (the paper's N, 128 there); a curved shell (a lantern, a "
                    "sphere, a folded letter) gets about as many squared on its surface. More give "
                    "finer fronts and cost more")
    lattice: IntProperty(
        name="Motion Detail", default=0, min=0, max=257, soft_max=64, options=STATIC,
        description="How finely the sheet's motion is simulated: the lattice that carries it has "
                    "this many couples per side (the paper's M; on a curved shell about as many "
                    "squared over its surface); 0 chooses it from the sheet's size and the Fire "
                    "Detail")
    crease_angle: FloatProperty(
        name="Crease Angle", subtype="ANGLE", options=STATIC, min=0.0, max=math.pi,
        default=_crease_angle_default(),
        description="On a curved shell (a folded letter, a box), edges whose faces turn by more "
                    "than this are creases: hinges its motion keeps sharp, each side moving on its "
                    "own. 180°: none. A low-poly tube (12 sides: 30° at each edge) is a prism at "
                    "the default; raise it to keep such a tube round")
    crumple: BoolProperty(
        name="Crumple", default=True, options=STATIC,
        description="Simulate the sheet's motion (paper §4: heat, bending, gravity, wind, fire "
                    "particles). Off: only the fire runs and the sheet keeps its rest shape")
    integrator: EnumProperty(
        name="Solver", default="implicit", options=STATIC,
        description="How the sheet's motion is stepped in time (the integrator)",
        items=[("implicit", "Implicit", "Backward Euler: stable at frame-sized steps (default)", 0),
               ("symplectic", "Symplectic", "Symplectic Euler, substepped as stability needs", 1),
               ("explicit", "Explicit", "The paper's explicit scheme (eqs 13-15), substepped as stability needs", 2)])
    threads: IntProperty(
        name="Threads", default=0, min=0, max=1024, options=STATIC,
        description="Threads of the simulation core; 0 uses every core. The result is the same "
                    "for any count")
    seed: IntProperty(
        name="Seed", default=0, min=0, options=STATIC,
        description="Seeds the random jitter; the same settings and seed bake the same result")
    front: EnumProperty(
        name="Front", default="fmm", options=STATIC,
        description="How the fire front is advanced over the cells",
        items=[("fmm", "Fast Marching", "Second-order fast marching: smooth, converging fronts (default)", 0),
               ("fmm1", "Fast Marching (1st order)", "First-order fast marching", 1),
               ("cellular", "Cellular", "The paper's 8-neighbour cellular rule", 2),
               ("cellular16", "Cellular 16", "A 16-neighbour cellular rule: rounder fronts", 3)])

    speed_map: StringProperty(
        name="Speed", default="", options=STATIC,
        description="Painted spread speed: the fire runs this many times the material's speed "
                    "where painted (1: as the material says, 2: twice as fast, 0: a firebreak "
                    "that never burns; a vertex group's unassigned vertices are 0). Multiplies "
                    "V0 of eq. 1 per cell")
    speed_map_from: EnumProperty(items=MAP_SOURCES, name="Speed From", default="GROUP", options=STATIC,
                                 description="Where the Speed map is painted")
    fuel_map: StringProperty(
        name="Fuel", default="", options=STATIC,
        description="Painted fuel: flames stay this many times longer where painted (1: the "
                    "material's Burn Time per Cell, 0: nothing to burn, a firebreak; a vertex "
                    "group's unassigned vertices are 0)")
    fuel_map_from: EnumProperty(items=MAP_SOURCES, name="Fuel From", default="GROUP", options=STATIC,
                                description="Where the Fuel map is painted")
    ignite_map: StringProperty(
        name="Ignite", default="", options=STATIC,
        description="Painted ignition: wherever this map is 0.5 or more catches fire at the "
                    "Ignite Frame (no igniter needed)")
    ignite_map_from: EnumProperty(items=MAP_SOURCES, name="Ignite From", default="GROUP",
                                  options=STATIC, description="Where the Ignite map is painted")
    ignite_frame: IntProperty(
        name="Ignite Frame", default=1, min=0, options=STATIC,
        description="The frame the Ignite map lights the sheet (within the bake's Start to End)")
    burn_duration: FloatProperty(
        name="Burn Duration", default=0.0, min=0.0, soft_max=600.0, subtype="TIME_ABSOLUTE",
        unit="TIME_ABSOLUTE", options=STATIC,
        description="Seconds from the first flame until the whole sheet has burnt (or the fire "
                    "has stopped at a firebreak), whatever the sheet's curl does: the bake speeds "
                    "the fire up or slows it down to fit. 0: the material's own speed")

    heat_ignites: BoolProperty(
        name="Heat Ignites", default=False, options=STATIC,
        description="Parts of this mesh that are not yet burning catch fire when the flames' heat "
                    "(eq. 2, at each fire cell) passes the material's ignition temperature: fire "
                    "jumps gaps and climbs a stack of sheets, and separate sheets with Heat Ignites within "
                    "reach of each other bake together as one simulation. Needs Crumple")

    igniter_collection: PointerProperty(
        name="Igniters", type=bpy.types.Collection, options=STATIC,
        description="Objects in this collection light the sheet while their ThinBurn Igniter "
                    "strength is above 0: an Empty lights the cells within its radius of its "
                    "origin, a mesh (a match, a candle flame) those within its radius of its surface")
    wind_scale: FloatProperty(
        name="Wind Scale", default=1.0, min=0.0, soft_max=10.0,
        description="Wind speed in m/s per unit of a Wind force field's strength. The scene's Wind "
                    "fields blow along their object's Z axis; read every frame")

    pin_group: StringProperty(
        name="Pin Group", default="", options=STATIC,
        description="Vertex group whose vertices (weight above 0.5) are held in place")
    floor_mode: EnumProperty(
        name="Floor", default="NONE", options=STATIC,
        description="A horizontal floor the sheet cannot fall through",
        items=[("NONE", "None", "No floor", 0),
               ("HEIGHT", "Height", "A floor at a fixed world height", 1),
               ("OBJECT", "Object", "A floor at the world height of an object's origin (e.g. a plane)", 2)])
    floor_height: FloatProperty(
        name="Floor Height", default=0.0, subtype="DISTANCE", unit="LENGTH", options=STATIC,
        description="World height (Z) of the floor")
    floor_object: PointerProperty(
        name="Floor Object", type=bpy.types.Object, options=STATIC,
        description="The floor lies on this object's top (its bounding box's highest world Z at "
                    "the first frame), half a millimetre up so the sheet does not flicker on it")

    frame_start: IntProperty(
        name="Start", default=1, min=0, options=STATIC,
        description="First frame of the bake; the sheet is at rest here")
    frame_end: IntProperty(
        name="End", default=250, min=0, options=STATIC,
        description="Last frame of the bake")
    cache_dir: StringProperty(
        name="Cache Folder", default="//thinburn_cache/", subtype="DIR_PATH", options=RELATIVE_PATH,
        description="Folder of the bake's PC2 file; '//' means next to the .blend file")
    cache_step: IntProperty(
        name="Keep Every", default=1, min=1, soft_max=8, max=48, options=STATIC,
        description="Store the sheet's shape only every this many frames (1: every frame). "
                    "The Mesh Cache modifier blends linearly between the stored frames, so a "
                    "big mesh's cache shrinks this many times, at a small error in its motion "
                    "(docs/blender.md measures it). The fire's own files keep every frame")

    flame_height: FloatProperty(
        name="Flame Height", default=0.06, min=0.0, soft_max=0.5, subtype="DISTANCE", unit="LENGTH",
        update=_on_flame, options=STATIC,
        description="How far the flames reach above the hottest fire particles (the fire "
                    "object's modifier input; changes the baked fire without a new bake)")
    flame_intensity: FloatProperty(
        name="Flame Intensity", default=1.0, min=0.0, soft_max=20.0, update=_on_flame, options=STATIC,
        description="Brightness of the flames and of the light they cast on the sheet")
    flame_temperature: FloatProperty(
        name="Flame Temperature", default=2300.0, min=800.0, soft_max=4000.0, update=_on_flame,
        options=STATIC,
        description="Colour temperature of the hottest flames, kelvin: about 1200 is deep red, "
                    "1700 orange, 2300 (default) yellow-orange, 3000 and above yellow-white")

    burnt: EnumProperty(
        name="Burnt", default="HOLES", update=_on_burnt, options=STATIC,
        description="What burnt-out parts of the sheet become (changes the bake without a new one)",
        items=[("HOLES", "Burn Through", "Burnt-out areas become holes (the default)", 0),
               ("ASH", "Char (Ash)", "Burnt-out areas stay as black char, and keep their shape", 1)])
    flakes: FloatProperty(
        name="Ash Flakes", default=0.0, min=0.0, max=1.0, options=STATIC, subtype="FACTOR",
        description="Share of the burnt-out faces that break off as flakes of char, fall, "
                    "flutter and land on the floor (0: none); read by the bake")
    embers: FloatProperty(
        name="Embers", default=1.0, min=0.0, soft_max=10.0, options=STATIC,
        description="How many sparks the fire throws off (0: none); read by the bake")

    mantaflow_resolution: IntProperty(
        name="Smoke Resolution", default=64, min=8, soft_max=256, options=STATIC,
        description="Resolution of the Mantaflow domain that Add Mantaflow Fire makes: voxels "
                    "along its longest side (more: finer flames, slower bakes)")
    mantaflow_domain: PointerProperty(
        type=bpy.types.Object, name="Smoke Domain", options=STATIC,
        description="The Mantaflow domain Add Mantaflow Fire made for this sheet (Free Bake "
                    "removes it and its cache folder)")

    show_advanced: BoolProperty(name="Advanced", default=False, options=STATIC,
                                description="Show the material and model parameters")
    baked_file: StringProperty(
        name="Baked File", default="", options=STATIC,
        description="The PC2 file of the current bake (set by the bake, cleared by Free Bake)")
    baked_shape: StringProperty(
        name="Baked As", default="", options=STATIC,
        description="What the core made of the sheet in the current bake: a flat sheet (the "
                    "paper's grid) or a curved shell (cells on its surface); set by the bake")
    baked_strain: FloatProperty(
        name="Largest Strain", default=0.0, options=STATIC,
        description="The largest |length / rest length - 1| of an edge over the current bake "
                    "(Crumple on; set by the bake)")
    # What the bake wrote, so that Free removes all of it after a rename, and the file that made
    # it, so that Free in a copy made by Save As never deletes the original's cache.
    baked_files: CollectionProperty(
        type=ThinBurnBakedFile, name="Baked Files",
        description="Every cache file the current bake wrote (Free Bake deletes them)")
    baked_objects: CollectionProperty(
        type=ThinBurnBakedObject, name="Baked Objects",
        description="Every object the current bake made (Free Bake removes them)")
    baked_blend: StringProperty(
        name="Baked In", default="", options=STATIC,
        description="The .blend file the current bake was made in: only there does Free Bake "
                    "delete its cache files (a copy saved under another name keeps them)")

    __annotations__.update(_field_props())


class ThinBurnIgniter(bpy.types.PropertyGroup):
    """An object that sets a sheet alight."""

    strength: FloatProperty(
        name="Lit", default=1.0, min=0.0, soft_max=1.0,
        description="1 lights the sheet, 0 puts the igniter out (any value above 0 is lit; the "
                    "igniter's strength): cells within its radius catch fire at that frame. "
                    "Keyframe it to light the sheet at a chosen time")
    kind: EnumProperty(
        name="Kind", default="LIGHT", options=STATIC,
        description="What the igniter does while Lit",
        items=[("LIGHT", "Lights What It Touches", "Cells within its Radius catch fire (a match, "
                 "a torch): of an Empty's origin, of a mesh's surface", 0),
               ("FLAME", "Flame", "A flame that burns on its own (a candle, a burner): it emits fire "
                "particles from its origin, a flame twice its Radius wide, whose heat bends the "
                "sheet and, with the sheet's Heat Ignites, sets it alight", 1)])
    radius: FloatProperty(
        name="Radius", default=0.02, min=0.0, soft_max=1.0, subtype="DISTANCE", unit="LENGTH",
        description="Cells within this distance of the igniter catch fire: of an Empty's origin "
                    "(0: the nearest cell), of a mesh igniter's surface (0: half a fire cell)")


CLASSES = (ThinBurnBakedFile, ThinBurnBakedObject, ThinBurnSettings, ThinBurnIgniter)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Object.thinburn = PointerProperty(type=ThinBurnSettings)
    bpy.types.Object.thinburn_igniter = PointerProperty(type=ThinBurnIgniter)


def unregister():
    del bpy.types.Object.thinburn_igniter
    del bpy.types.Object.thinburn
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
