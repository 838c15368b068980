"""Fire particles of a bake (when the core has ``Simulation.particles``).

They become two objects that share one mesh, whose Mesh Cache plays ``<name>_fire.pc2``
and whose geometry nodes ("ThinBurn Fire") turn the cached points into flames. Both render
in Cycles and EEVEE without the add-on:

* "ThinBurn Fire <sheet>": the flames, a volume. Every hot particle becomes a tongue of a few
  puffs that rises up to *Flame Height* above it (a height of its own) and cools and narrows
  towards its tip; Points to Volume gives
  the ``density`` grid, and Field to Grid samples the nearest puff's ``tb_temperature``
  (colour temperature, K) and ``tb_flame`` (emission weight) onto grids of those names.
  Material "ThinBurn Fire": blackbody emission, seen by the camera only.
* "ThinBurn Fire Light <sheet>": the same puffs as small glowing spheres (material "ThinBurn
  Fire Light"), invisible to the camera, that cast the flames' light onto the sheet (Cycles
  samples emissive meshes directly, so this is not noisy at low samples).

Attribute names start with ``tb_``: Cycles resolves ``temperature`` to its own volume
attribute.
"""
from __future__ import annotations

import numpy as np

import bpy

from . import cache
from .nodes import ensure_modifier, interface_socket, new_group, node, set_input, socket, use_nodes

CACHE_MODIFIER = "ThinBurn Cache"
FIRE_GROUP = "ThinBurn Fire"
FIRE_MATERIAL = "ThinBurn Fire"
LIGHT_MATERIAL = "ThinBurn Fire Light"
ATTR_TEMPERATURE = "tb_particle_temperature"  # K above ambient, as the core gives it
ATTR_KELVIN = "tb_temperature"  # colour temperature, K (not "temperature": Cycles' own name)
ATTR_FLAME = "tb_flame"  # emission weight
ATTR_LICK = "tb_lick"  # a particle's tongue height, of Flame Height * T/T0
ATTR_RADIUS = "tb_radius"  # a flame puff's radius, m


def fire_object_name(obj) -> str:
    return f"ThinBurn Fire {obj.name}"


def _inputs(tree):
    interface_socket(tree, "Geometry", "INPUT", "NodeSocketGeometry")
    interface_socket(tree, "Count", "INPUT", "NodeSocketInt", 1, 0, desc="Particle slots in the cache")
    interface_socket(tree, "Radius", "INPUT", "NodeSocketFloat", FLAME_RADIUS, 0.0,
                     desc="Radius of the flame around one fire particle, m")
    interface_socket(tree, "Min Temperature", "INPUT", "NodeSocketFloat", MIN_TEMPERATURE, 0.0,
                     desc="Particles cooler than this (K above ambient) are left out: they no "
                          "longer glow, and fewer particles render faster")
    interface_socket(tree, "Flame Height", "INPUT", "NodeSocketFloat", FLAME_HEIGHT, 0.0,
                     desc="How far above each hot particle its flame reaches, m (at the "
                          "particle's birth temperature; cooler particles make shorter flames)")
    interface_socket(tree, "Intensity", "INPUT", "NodeSocketFloat", 1.0, 0.0,
                     desc="Brightness of the flames and of the light they cast")
    interface_socket(tree, "Flame Temperature", "INPUT", "NodeSocketFloat", FLAME_COLOR_K, 800.0,
                     desc="Colour temperature of the hottest flame, kelvin: about 1200 is deep "
                          "red, 1700 orange, 2300 yellow-orange, 3000 yellow-white")
    interface_socket(tree, "Voxel Size", "INPUT", "NodeSocketFloat", VOXEL_SIZE, 0.0001,
                     desc="Detail of the flame volume, m: smaller is finer and slower")
    interface_socket(tree, "Output", "INPUT", "NodeSocketInt", 0, 0, 2,
                     desc="0: flames (a volume), 1: light emitters (small glowing spheres, for "
                          "the camera-invisible light object), 2: the fire particles as points")
    interface_socket(tree, "Material", "INPUT", "NodeSocketMaterial")
    interface_socket(tree, "Geometry", "OUTPUT", "NodeSocketGeometry")


VERSION = 5  # of the groups and materials below; older ones (from an earlier add-on) are renamed


def _current(collection, name):
    """The datablock `name` if it is of this VERSION; an older one is renamed out of the way
    (objects still using it keep it) so that a fresh one is built."""
    block = collection.get(name)
    if block is not None and block.get("thinburn_version", 1) < VERSION:
        block.name = f"{name} (old)"
        block = None
    return block


def _stamp(block):
    block["thinburn_version"] = VERSION
    return block


def _store(tree, x, y, name, geometry, value):
    """A Store Named Attribute node (a float on points) writing `value` as `name` on `geometry`."""
    store = node(tree, "GeometryNodeStoreNamedAttribute", x, y, data_type="FLOAT", domain="POINT")
    set_input(store, "Name", name)
    tree.links.new(geometry, store.inputs["Geometry"])
    tree.links.new(value, socket(store.inputs, "Value"))
    return store


def fire_group():
    """Geometry node group "ThinBurn Fire" (see the module docstring). Point i < Count of the
    cached mesh is particle i's position; point Count + i carries (temperature, alive, lick)."""
    tree = _current(bpy.data.node_groups, FIRE_GROUP)
    if tree is not None:
        return tree
    tree, _ = new_group(FIRE_GROUP, "GeometryNodeTree")
    _stamp(tree)
    _inputs(tree)
    L = tree.links.new
    gi = node(tree, "NodeGroupInput", -1600, 0)
    go = node(tree, "NodeGroupOutput", 2200, 0)
    # --- the live, hot particles as points with tb_temperature --------------------------------
    index = node(tree, "GeometryNodeInputIndex", -1600, -300)
    pos = node(tree, "GeometryNodeInputPosition", -1600, -450)
    other = node(tree, "ShaderNodeMath", -1400, -300, operation="ADD")
    L(index.outputs[0], other.inputs[0])
    L(gi.outputs["Count"], other.inputs[1])
    sample = node(tree, "GeometryNodeSampleIndex", -1200, -200, data_type="FLOAT_VECTOR", domain="POINT")
    L(gi.outputs["Geometry"], sample.inputs["Geometry"])
    L(pos.outputs[0], socket(sample.inputs, "Value"))
    L(other.outputs[0], sample.inputs["Index"])
    split = node(tree, "ShaderNodeSeparateXYZ", -1000, -200)
    L(socket(sample.outputs, "Value"), split.inputs[0])
    first = node(tree, "FunctionNodeCompare", -1200, 100, data_type="INT", operation="LESS_THAN")
    L(index.outputs[0], socket(first.inputs, "A_INT"))
    L(gi.outputs["Count"], socket(first.inputs, "B_INT"))
    live = node(tree, "FunctionNodeCompare", -800, -200, data_type="FLOAT", operation="GREATER_THAN")
    L(split.outputs["Y"], live.inputs[0])
    set_input(live, "B", 0.5)
    hot = node(tree, "FunctionNodeCompare", -800, -400, data_type="FLOAT", operation="GREATER_EQUAL")
    L(split.outputs["X"], hot.inputs[0])
    L(gi.outputs["Min Temperature"], hot.inputs[1])
    glowing = node(tree, "FunctionNodeBooleanMath", -600, -300, operation="AND")
    L(live.outputs[0], glowing.inputs[0])
    L(hot.outputs[0], glowing.inputs[1])
    keep = node(tree, "FunctionNodeBooleanMath", -600, 0, operation="AND")
    L(first.outputs[0], keep.inputs[0])
    L(glowing.outputs[0], keep.inputs[1])
    store = _store(tree, -600, 250, ATTR_TEMPERATURE, gi.outputs["Geometry"], split.outputs["X"])
    # Per particle, its tongue's height: LICK_MIN..LICK_MAX of Flame Height, mostly short (u^2),
    # u the particle's own seed in [0, 1), fixed for its life (the cache's third column); and
    # its puffs' radius.
    skew = node(tree, "ShaderNodeMath", -650, 500, operation="POWER")
    L(split.outputs["Z"], skew.inputs[0])
    skew.inputs[1].default_value = 2.0
    spread = node(tree, "ShaderNodeMath", -500, 500, operation="MULTIPLY_ADD")
    L(skew.outputs[0], spread.inputs[0])
    spread.inputs[1].default_value = LICK_MAX - LICK_MIN
    spread.inputs[2].default_value = LICK_MIN
    store_lick = _store(tree, -450, 250, ATTR_LICK, store.outputs[0], spread.outputs[0])
    store_r = _store(tree, -300, 250, ATTR_RADIUS, store_lick.outputs[0], gi.outputs["Radius"])
    points = node(tree, "GeometryNodeMeshToPoints", -400, 100)
    L(store_r.outputs[0], points.inputs["Mesh"])
    L(keep.outputs[0], points.inputs["Selection"])
    L(gi.outputs["Radius"], points.inputs["Radius"])
    temp = node(tree, "GeometryNodeInputNamedAttribute", -400, -200, data_type="FLOAT")
    set_input(temp, "Name", ATTR_TEMPERATURE)
    # --- flames: each particle becomes a tongue of STREAK puffs rising Flame Height * T/T0 ----
    dup = node(tree, "GeometryNodeDuplicateElements", -200, 100, domain="POINT")
    L(points.outputs[0], dup.inputs["Geometry"])
    set_input(dup, "Amount", STREAK - 1)
    along = node(tree, "ShaderNodeMath", 0, -100, operation="DIVIDE")  # 0 at the base .. 1 at the tip
    L(dup.outputs["Duplicate Index"], along.inputs[0])
    along.inputs[1].default_value = STREAK - 1
    rel = node(tree, "ShaderNodeMath", 0, -250, operation="DIVIDE")
    L(temp.outputs["Attribute"], rel.inputs[0])
    rel.inputs[1].default_value = FLAME_K
    rise = node(tree, "ShaderNodeMath", 200, -250, operation="MULTIPLY")
    L(along.outputs[0], rise.inputs[0])
    L(gi.outputs["Flame Height"], rise.inputs[1])
    rise2 = node(tree, "ShaderNodeMath", 400, -250, operation="MULTIPLY")
    L(rise.outputs[0], rise2.inputs[0])
    L(rel.outputs[0], rise2.inputs[1])
    lick_now = node(tree, "GeometryNodeInputNamedAttribute", 200, -650, data_type="FLOAT")
    set_input(lick_now, "Name", ATTR_LICK)
    rise3 = node(tree, "ShaderNodeMath", 500, -400, operation="MULTIPLY")
    L(rise2.outputs[0], rise3.inputs[0])
    L(lick_now.outputs["Attribute"], rise3.inputs[1])
    up = node(tree, "ShaderNodeCombineXYZ", 600, -250)
    L(rise3.outputs[0], up.inputs["Z"])
    lift = node(tree, "GeometryNodeSetPosition", 600, 100)
    L(dup.outputs["Geometry"], lift.inputs["Geometry"])
    L(up.outputs[0], lift.inputs["Offset"])
    # the tongue cools towards its tip: T * (1 - 0.7 * along)
    cool = node(tree, "ShaderNodeMath", 200, -450, operation="MULTIPLY_ADD")
    L(along.outputs[0], cool.inputs[0])
    cool.inputs[1].default_value = -0.7
    cool.inputs[2].default_value = 1.0
    cooled = node(tree, "ShaderNodeMath", 400, -450, operation="MULTIPLY")
    L(temp.outputs["Attribute"], cooled.inputs[0])
    L(cool.outputs[0], cooled.inputs[1])
    tongue = _store(tree, 800, 100, ATTR_TEMPERATURE, lift.outputs[0], cooled.outputs[0])
    # and narrows: its puffs' radius Radius * (1 - TAPER * along), so it ends in a tip
    narrow = node(tree, "ShaderNodeMath", 600, -650, operation="MULTIPLY_ADD")
    L(along.outputs[0], narrow.inputs[0])
    narrow.inputs[1].default_value = -TAPER
    narrow.inputs[2].default_value = 1.0
    tip_r = node(tree, "ShaderNodeMath", 800, -650, operation="MULTIPLY")
    L(narrow.outputs[0], tip_r.inputs[0])
    L(gi.outputs["Radius"], tip_r.inputs[1])
    tapered = _store(tree, 900, 250, ATTR_RADIUS, tongue.outputs[0], tip_r.outputs[0])
    both = node(tree, "GeometryNodeJoinGeometry", 1000, 100)  # the particles and their tongues
    L(tapered.outputs[0], both.inputs[0])
    L(points.outputs[0], both.inputs[0])
    # what the shaders read: tb_temperature = the colour temperature in kelvin, tb_flame = the
    # emission weight Intensity * (T / T0)^4 (Stefan-Boltzmann)
    t_now = node(tree, "GeometryNodeInputNamedAttribute", 1000, -200, data_type="FLOAT")
    set_input(t_now, "Name", ATTR_TEMPERATURE)
    ratio = node(tree, "ShaderNodeMath", 1200, -200, operation="DIVIDE")
    L(t_now.outputs["Attribute"], ratio.inputs[0])
    ratio.inputs[1].default_value = FLAME_K
    span = node(tree, "ShaderNodeMath", 1200, -400, operation="SUBTRACT")
    L(gi.outputs["Flame Temperature"], span.inputs[0])
    span.inputs[1].default_value = AMBIENT_K
    kelvin = node(tree, "ShaderNodeMath", 1400, -300, operation="MULTIPLY_ADD")
    L(ratio.outputs[0], kelvin.inputs[0])
    L(span.outputs[0], kelvin.inputs[1])
    kelvin.inputs[2].default_value = AMBIENT_K
    fourth = node(tree, "ShaderNodeMath", 1400, -100, operation="POWER")
    L(ratio.outputs[0], fourth.inputs[0])
    fourth.inputs[1].default_value = 4.0
    weight = node(tree, "ShaderNodeMath", 1600, -100, operation="MULTIPLY")
    L(fourth.outputs[0], weight.inputs[0])
    L(gi.outputs["Intensity"], weight.inputs[1])
    store_k = _store(tree, 1200, 100, ATTR_KELVIN, both.outputs[0], kelvin.outputs[0])
    store_w = _store(tree, 1400, 100, ATTR_FLAME, store_k.outputs[0], weight.outputs[0])
    flames = store_w.outputs[0]
    # --- output 0: a volume (density from Points to Volume, the two grids sampled from the
    # nearest flame point); Blender's volume grids carry no point attributes by themselves
    to_volume = node(tree, "GeometryNodePointsToVolume", 1600, 400)
    L(flames, to_volume.inputs["Points"])
    set_input(to_volume, "Resolution Mode", "Size")
    L(gi.outputs["Voxel Size"], to_volume.inputs["Voxel Size"])
    puff_r = node(tree, "GeometryNodeInputNamedAttribute", 1400, 550, data_type="FLOAT")
    set_input(puff_r, "Name", ATTR_RADIUS)
    L(puff_r.outputs["Attribute"], to_volume.inputs["Radius"])
    set_input(to_volume, "Density", 1.0)
    density = node(tree, "GeometryNodeGetNamedGrid", 1800, 400, data_type="FLOAT")
    L(to_volume.outputs[0], density.inputs["Volume"])
    set_input(density, "Name", "density")
    set_input(density, "Remove", False)
    nearest = node(tree, "GeometryNodeSampleNearest", 1600, 700, domain="POINT")
    L(flames, nearest.inputs["Geometry"])
    L(node(tree, "GeometryNodeInputPosition", 1400, 700).outputs[0], nearest.inputs["Sample Position"])
    to_grid = node(tree, "GeometryNodeFieldToGrid", 2000, 600, data_type="FLOAT")
    L(density.outputs["Grid"], to_grid.inputs["Topology"])
    volume = density.outputs["Volume"]
    for k, name in enumerate((ATTR_KELVIN, ATTR_FLAME)):
        to_grid.grid_items.new("FLOAT", name)
        attr = node(tree, "GeometryNodeInputNamedAttribute", 1600, 900 + 150 * k, data_type="FLOAT")
        set_input(attr, "Name", name)
        pick = node(tree, "GeometryNodeSampleIndex", 1800, 900 + 150 * k, data_type="FLOAT", domain="POINT")
        L(flames, pick.inputs["Geometry"])
        L(attr.outputs["Attribute"], socket(pick.inputs, "Value"))
        L(nearest.outputs[0], pick.inputs["Index"])
        L(socket(pick.outputs, "Value"), to_grid.inputs[k + 1])
    for k, name in enumerate((ATTR_KELVIN, ATTR_FLAME)):
        keep_grid = node(tree, "GeometryNodeStoreNamedGrid", 2200 + 200 * k, 400, data_type="FLOAT")
        L(volume, keep_grid.inputs["Volume"])
        set_input(keep_grid, "Name", name)
        L(to_grid.outputs[k], keep_grid.inputs["Grid"])
        volume = keep_grid.outputs[0]
    # --- output 1: small glowing spheres that light the scene (Cycles samples emissive meshes
    # directly, so they light the sheet with little noise at low samples). Each is LIGHT_SIZE of
    # Radius, lifted LIGHT_LIFT Radius above its flame point: a sphere of the full Radius at a
    # particle on the sheet cut through the paper, and each cut lit a bright hollow ring on it
    # (a chain of rings along the burning front, seen from above).
    sphere = node(tree, "GeometryNodeMeshIcoSphere", 1600, -600)
    set_input(sphere, "Radius", 1.0)
    set_input(sphere, "Subdivisions", 1)
    lift_by = node(tree, "ShaderNodeMath", 1400, -800, operation="MULTIPLY")
    L(gi.outputs["Radius"], lift_by.inputs[0])
    lift_by.inputs[1].default_value = LIGHT_LIFT
    lift_up = node(tree, "ShaderNodeCombineXYZ", 1600, -800)
    L(lift_by.outputs[0], lift_up.inputs["Z"])
    raised = node(tree, "GeometryNodeSetPosition", 1600, -400)
    L(flames, raised.inputs["Geometry"])
    L(lift_up.outputs[0], raised.inputs["Offset"])
    size = node(tree, "ShaderNodeMath", 1600, -1000, operation="MULTIPLY")
    L(gi.outputs["Radius"], size.inputs[0])
    size.inputs[1].default_value = LIGHT_SIZE
    inst = node(tree, "GeometryNodeInstanceOnPoints", 1800, -400)
    L(raised.outputs[0], inst.inputs["Points"])
    L(sphere.outputs["Mesh"], inst.inputs["Instance"])
    L(size.outputs[0], inst.inputs["Scale"])
    real = node(tree, "GeometryNodeRealizeInstances", 2000, -400)
    L(inst.outputs[0], real.inputs[0])
    # --- pick the output ------------------------------------------------------------------
    choose = node(tree, "GeometryNodeIndexSwitch", 2400, 0, data_type="GEOMETRY")
    L(gi.outputs["Output"], choose.inputs["Index"])
    L(volume, choose.inputs[1])
    L(real.outputs[0], choose.inputs[2])
    choose.index_switch_items.new()
    L(points.outputs[0], choose.inputs[3])
    setmat = node(tree, "GeometryNodeSetMaterial", 2600, 0)
    L(choose.outputs[0], setmat.inputs["Geometry"])
    L(gi.outputs["Material"], setmat.inputs["Material"])
    L(setmat.outputs[0], go.inputs["Geometry"])
    return tree


AMBIENT_K = 293.15      # the core's particle temperatures are kelvin above ambient
FLAME_K = 900.0         # a particle's temperature at birth (the core's temperature0)
FLAME_COLOR_K = 2300.0  # the colour temperature shown for a particle at FLAME_K
FLAME_RADIUS = 0.010    # m, a flame puff around one particle
FLAME_HEIGHT = 0.06     # m, a tongue's rise above a particle at FLAME_K
VOXEL_SIZE = 0.0025     # m
MIN_TEMPERATURE = 350.0  # K above ambient: cooler particles barely glow (weight < 0.03)
STREAK = 9              # puffs per tongue, the particle's own included
LICK_MIN, LICK_MAX = 0.3, 1.6  # a tongue's height, of Flame Height * T/T0: min + (max - min) u^2
TAPER = 0.8             # a tongue's puffs shrink to 1 - TAPER * along of Radius towards its tip
FLAME_STRENGTH = 50.0   # volume emission of a flame point at FLAME_K and Intensity 1
LICK_SCALE = (60.0, 60.0, 20.0)  # 1/m: the noise that shapes the tongues
LIGHT_SIZE = 0.2        # a light sphere's radius, of Radius
LIGHT_LIFT = 1.0        # its centre above its flame point, in Radius: clear of the sheet below
# surface emission of a light sphere at FLAME_K and Intensity 1. The same 1 as when the spheres
# had the full Radius lights the paper next to the fire as they did (tests/blender/
# test_render.py::test_flames_light_the_sheet: red 0.40 then, 0.39-0.40 now): those ten
# spheres a particle overlapped hid most of each other's surface, and half of each was under
# the sheet. Kept at 1 / LIGHT_SIZE^2 (the area's ratio), the paper near the fire went to 0.99.
LIGHT_STRENGTH = 1.0


def _emission(tree, x, strength, camera_only):
    """Blackbody(tb_temperature) emission of strength tb_flame * strength."""
    kelvin = node(tree, "ShaderNodeAttribute", x - 800, 150, attribute_type="GEOMETRY",
                  attribute_name=ATTR_KELVIN)
    weight = node(tree, "ShaderNodeAttribute", x - 800, -100, attribute_type="GEOMETRY",
                  attribute_name=ATTR_FLAME)
    body = node(tree, "ShaderNodeBlackbody", x - 550, 150)
    tree.links.new(kelvin.outputs["Fac"], body.inputs["Temperature"])
    scale = node(tree, "ShaderNodeMath", x - 550, -100, operation="MULTIPLY")
    tree.links.new(weight.outputs["Fac"], scale.inputs[0])
    scale.inputs[1].default_value = strength
    last = scale
    if camera_only:  # the light object lights the scene: the volume only shows, no double light
        path = node(tree, "ShaderNodeLightPath", x - 800, -350)
        only = node(tree, "ShaderNodeMath", x - 350, -150, operation="MULTIPLY")
        tree.links.new(scale.outputs[0], only.inputs[0])
        tree.links.new(path.outputs["Is Camera Ray"], only.inputs[1])
        last = only
    emit = node(tree, "ShaderNodeEmission", x - 150, 50)
    tree.links.new(body.outputs[0], emit.inputs["Color"])
    tree.links.new(last.outputs[0], emit.inputs["Strength"])
    return emit


def _empty_material(name, clear=True):
    """(material, None) when the current stamped material of that name exists; else a new one,
    stamped, with nodes (cleared unless clear is False): (material, its node tree)."""
    mat = _current(bpy.data.materials, name)
    if mat is not None:
        return mat, None
    mat = _stamp(bpy.data.materials.new(name))
    use_nodes(mat)
    if clear:
        mat.node_tree.nodes.clear()
    return mat, mat.node_tree


def fire_material():
    """"ThinBurn Fire": the flame volume. Emission of the colour temperature tb_temperature,
    strength tb_flame (Intensity * (T / T0)^4) * density, shown to the camera only (the light
    object casts the flames' light)."""
    mat, tree = _empty_material(FIRE_MATERIAL)
    if tree is None:
        return mat
    emit = _emission(tree, 0, FLAME_STRENGTH, camera_only=True)
    dens = node(tree, "ShaderNodeAttribute", -800, -550, attribute_type="GEOMETRY", attribute_name="density")
    # licks: a noise stretched upwards breaks the glow into tongues
    where = node(tree, "ShaderNodeTexCoord", -1400, -800)
    stretch = node(tree, "ShaderNodeVectorMath", -1200, -800, operation="MULTIPLY")
    tree.links.new(where.outputs["Object"], stretch.inputs[0])
    stretch.inputs[1].default_value = LICK_SCALE
    noise = node(tree, "ShaderNodeTexNoise", -1000, -800)
    tree.links.new(stretch.outputs[0], noise.inputs["Vector"])
    set_input(noise, "Scale", 1.0)
    set_input(noise, "Detail", 3.0)
    licks = node(tree, "ShaderNodeMapRange", -800, -800, clamp=True, interpolation_type="SMOOTHSTEP")
    tree.links.new(noise.outputs["Fac"], licks.inputs["Value"])
    set_input(licks, "From Min", 0.35)
    set_input(licks, "From Max", 0.65)
    shaped = node(tree, "ShaderNodeMath", -550, -650, operation="MULTIPLY")
    tree.links.new(dens.outputs["Fac"], shaped.inputs[0])
    tree.links.new(licks.outputs["Result"], shaped.inputs[1])
    mul = node(tree, "ShaderNodeMath", -350, -450, operation="MULTIPLY")
    tree.links.new(emit.inputs["Strength"].links[0].from_socket, mul.inputs[0])
    tree.links.new(shaped.outputs[0], mul.inputs[1])
    tree.links.new(mul.outputs[0], emit.inputs["Strength"])
    out = node(tree, "ShaderNodeOutputMaterial", 200, 0)
    tree.links.new(emit.outputs[0], out.inputs["Volume"])
    if hasattr(mat, "cycles"):
        mat.cycles.volume_step_rate = 2.0  # emission only: coarser steps look the same
    return mat


def light_material():
    """"ThinBurn Fire Light": the glowing spheres of the light object."""
    mat, tree = _empty_material(LIGHT_MATERIAL)
    if tree is None:
        return mat
    emit = _emission(tree, 0, LIGHT_STRENGTH, camera_only=False)
    out = node(tree, "ShaderNodeOutputMaterial", 200, 0)
    tree.links.new(emit.outputs[0], out.inputs["Surface"])
    return mat


def particle_cache_rows(frames, licks=None) -> tuple:
    """Pack per-frame particles [(positions (k, 3), temperatures (k,))] into equal-size PC2
    samples: K = max k; rows 0..K-1 positions, rows K..2K-1 (temperature, alive, lick), lick
    the particle's tongue-height seed in [0, 1) (licks: per frame (k,), worker.lick_of; 0
    without)."""
    count = max([len(t) for _, t in frames] + [1])
    rows = []
    for f, (pos, temp) in enumerate(frames):
        k = len(temp)
        sample = np.zeros((2 * count, 3), dtype=np.float32)
        sample[:k] = pos
        if k:
            sample[k:count] = pos[0]  # idle slots sit on a live particle, hidden by alive = 0
        sample[count:count + k, 0] = temp
        sample[count:count + k, 1] = 1.0
        if licks is not None:
            sample[count:count + k, 2] = licks[f]
        rows.append(sample)
    return count, rows


def light_object_name(obj) -> str:
    return f"ThinBurn Fire Light {obj.name}"


# The panel's flame controls (obj.thinburn) -> the fire modifiers' inputs.
FLAME_SETTINGS = {"flame_height": "Flame Height", "flame_intensity": "Intensity",
                  "flame_temperature": "Flame Temperature"}


def _inputs_of(md):
    return {s.name: s.identifier for s in md.node_group.interface.items_tree
            if getattr(s, "in_out", "") == "INPUT"}


def sync_flame_settings(obj) -> None:
    """Copy the sheet's flame settings onto its fire and light objects' modifiers (and lamps)."""
    settings = getattr(obj, "thinburn", None)
    sync_lamps(obj)
    for name in (fire_object_name(obj), light_object_name(obj)):
        fire = bpy.data.objects.get(name)
        md = None if fire is None else fire.modifiers.get(FIRE_GROUP)
        if md is None or md.node_group is None:
            continue
        ident = _inputs_of(md)
        for prop, socket_name in FLAME_SETTINGS.items():
            if settings is not None and hasattr(settings, prop) and socket_name in ident:
                md[ident[socket_name]] = float(getattr(settings, prop))
        fire.update_tag()


def _particle_object(obj, name, mesh, path, frame_start, output, material):
    fire = bpy.data.objects.get(name)
    if fire is not None and (fire.type != "MESH" or fire.data is not mesh):
        bpy.data.objects.remove(fire)
        fire = None
    if fire is None:
        fire = bpy.data.objects.new(name, mesh)
        for coll in obj.users_collection:
            coll.objects.link(fire)
    fire.visible_shadow = False  # flames light the scene; they cast no shadow
    md = ensure_modifier(fire, CACHE_MODIFIER, "MESH_CACHE", 0)
    md.cache_format = "PC2"
    md.filepath = path
    md.frame_start = frame_start
    md.interpolation = "NONE"  # slots are reused by different particles from frame to frame
    gn = ensure_modifier(fire, FIRE_GROUP, "NODES", 1)
    gn.node_group = fire_group()
    ident = _inputs_of(gn)
    gn[ident["Output"]] = output
    gn[ident["Material"]] = material
    return fire, gn, ident


# --- embers -------------------------------------------------------------------------------------
EMBER_GROUP_MATERIAL = "ThinBurn Ember"
EMBER_CHANCE = 0.02    # per hot particle and frame, at Embers = 1
EMBER_K = 1000.0       # K above ambient at birth: a bright orange spark
EMBER_COOLING = 1.2    # 1/s: T falls to 1/e in 0.8 s
EMBER_LIFETIME = (0.8, 2.0)  # s
EMBER_BUOYANCY = 3.0   # m/s² at EMBER_K, upwards; gravity pulls 9.81 * EMBER_WEIGHT down
EMBER_WEIGHT = 0.15
EMBER_DRAG = 2.0       # 1/s
EMBER_KICK = 0.25      # m/s, rms of a spark's initial velocity
EMBER_FLUTTER = 0.3    # m/s², rms of the random push each frame
EMBER_RADIUS = 0.0010  # m


def ember_object_name(obj) -> str:
    return f"ThinBurn Embers {obj.name}"


def ember_frames(frames, dt: float, seed: int = 0, amount: float = 1.0, wind=(0.0, 0.0, 0.0)):
    """Sparks thrown off by the fire: [(positions (k, 3), temperatures (k,))] per frame.

    Each frame, every fire particle hotter than 0.6 T0 (young: it left the burning edge within
    about 60 ms) throws a spark with probability EMBER_CHANCE * amount. A spark starts at its
    particle, kicked in a random direction, rises by buoyancy against a little weight and drag,
    flutters, cools exponentially and dies at the end of its lifetime or below 150 K above
    ambient. Deterministic: the same particles, dt and seed give the same sparks. Each live
    spark keeps its slot (its index in the frame's arrays) for its whole life; a dead slot is
    reused, so the arrays are padded to the number of slots with temperature 0 (dead)."""
    rng = np.random.default_rng([int(seed), 0xE3BE])
    wind = np.asarray(wind, dtype=np.float64)
    pos = np.zeros((0, 3))
    vel = np.zeros((0, 3))
    temp = np.zeros(0)
    life = np.zeros(0)
    out = []
    for ppos, ptemp in frames:
        ppos = np.asarray(ppos, dtype=np.float64).reshape(-1, 3)
        ptemp = np.asarray(ptemp, dtype=np.float64).reshape(-1)
        # move and cool the live sparks over the frame
        alive = temp > 0
        if alive.any():
            lift = EMBER_BUOYANCY * temp[alive] / EMBER_K - 9.81 * EMBER_WEIGHT
            acc = -EMBER_DRAG * (vel[alive] - wind)
            acc[:, 2] += lift
            acc += EMBER_FLUTTER * rng.standard_normal((int(alive.sum()), 3))
            vel[alive] += acc * dt
            pos[alive] += vel[alive] * dt
            temp[alive] *= np.exp(-EMBER_COOLING * dt)
            life[alive] -= dt
            dead = alive & ((life <= 0) | (temp < 150.0))
            temp[dead] = 0.0
        # births from the young fire particles
        young = np.flatnonzero(ptemp > 0.6 * FLAME_K)
        draw = rng.random(len(young))
        born = young[draw < EMBER_CHANCE * amount]
        free = np.flatnonzero(temp <= 0)
        extra = len(born) - len(free)
        if extra > 0:
            pos = np.vstack([pos, np.zeros((extra, 3))])
            vel = np.vstack([vel, np.zeros((extra, 3))])
            temp = np.concatenate([temp, np.zeros(extra)])
            life = np.concatenate([life, np.zeros(extra)])
            free = np.flatnonzero(temp <= 0)
        slots = free[:len(born)]
        pos[slots] = ppos[born]
        kick = EMBER_KICK * rng.standard_normal((len(born), 3))
        kick[:, 2] = np.abs(kick[:, 2]) + 0.5 * EMBER_KICK  # thrown up and out
        vel[slots] = kick
        temp[slots] = EMBER_K
        life[slots] = rng.uniform(*EMBER_LIFETIME, size=len(born))
        out.append((pos.astype(np.float32), temp.astype(np.float32)))
    return out


def ember_material():
    """"ThinBurn Ember": blackbody emission of the spark's temperature, ~ (T / EMBER_K)^4."""
    mat, tree = _empty_material(EMBER_GROUP_MATERIAL)
    if tree is None:
        return mat
    temp = node(tree, "ShaderNodeAttribute", -800, 0, attribute_type="GEOMETRY",
                attribute_name=ATTR_TEMPERATURE)
    kelvin = node(tree, "ShaderNodeMath", -550, 150, operation="ADD")
    tree.links.new(temp.outputs["Fac"], kelvin.inputs[0])
    kelvin.inputs[1].default_value = AMBIENT_K
    body = node(tree, "ShaderNodeBlackbody", -350, 150)
    tree.links.new(kelvin.outputs[0], body.inputs["Temperature"])
    ratio = node(tree, "ShaderNodeMath", -550, -100, operation="DIVIDE")
    tree.links.new(temp.outputs["Fac"], ratio.inputs[0])
    ratio.inputs[1].default_value = EMBER_K
    power = node(tree, "ShaderNodeMath", -350, -100, operation="POWER")
    tree.links.new(ratio.outputs[0], power.inputs[0])
    power.inputs[1].default_value = 4.0
    scale = node(tree, "ShaderNodeMath", -150, -100, operation="MULTIPLY")
    tree.links.new(power.outputs[0], scale.inputs[0])
    scale.inputs[1].default_value = 40.0
    emit = node(tree, "ShaderNodeEmission", 50, 50)
    tree.links.new(body.outputs[0], emit.inputs["Color"])
    tree.links.new(scale.outputs[0], emit.inputs["Strength"])
    out = node(tree, "ShaderNodeOutputMaterial", 250, 0)
    tree.links.new(emit.outputs[0], out.inputs["Surface"])
    return mat


def apply_embers(obj, sheet_pc2_path: str, frames, frame_start: float) -> None:
    """Sparks from the baked fire particles: "ThinBurn Embers <sheet>", its own PC2 and a
    point cloud (the "ThinBurn Fire" group's point output) that glows by temperature."""
    settings = getattr(obj, "thinburn", None)
    amount = float(getattr(settings, "embers", 1.0))
    seed = int(getattr(settings, "seed", 0))
    scene = bpy.context.scene
    dt = scene.render.fps_base / scene.render.fps
    sparks = ember_frames(frames, dt, seed=seed, amount=amount)
    name = ember_object_name(obj)
    old = bpy.data.objects.get(name)
    if amount <= 0.0 or not any(len(t) for _, t in sparks):
        if old is not None:
            bpy.data.objects.remove(old)
        return
    count, rows = particle_cache_rows(sparks)
    abs_path = bpy.path.abspath(sheet_pc2_path)[:-len(".pc2")] + "_embers.pc2"
    with cache.PC2Writer(abs_path, 2 * count, start_frame=frame_start) as writer:
        for sample in rows:
            writer.append(sample)
    mesh = old.data if old is not None and old.type == "MESH" else None
    if mesh is None or len(mesh.vertices) != 2 * count:
        mesh = bpy.data.meshes.new(name)
        mesh.vertices.add(2 * count)
    path = sheet_pc2_path[:-len(".pc2")] + "_embers.pc2"
    embers, gn, ident = _particle_object(obj, name, mesh, path, frame_start, 2, ember_material())
    gn[ident["Count"]] = count
    gn[ident["Radius"]] = EMBER_RADIUS
    gn[ident["Min Temperature"]] = 1.0  # dead slots have 0


def apply_particles(obj, sheet_pc2_path: str, frames, frame_start: float, licks=None) -> None:
    """Write the fire particles to their own PC2, the flame object "ThinBurn Fire <sheet>"
    and the camera-invisible "ThinBurn Fire Light <sheet>" that lights the scene. licks: per
    frame, each particle's tongue-height seed (particle_cache_rows)."""
    count, rows = particle_cache_rows(frames, licks)
    abs_sheet = bpy.path.abspath(sheet_pc2_path)
    abs_fire = abs_sheet[:-len(".pc2")] + "_fire.pc2"
    with cache.PC2Writer(abs_fire, 2 * count, start_frame=frame_start) as writer:
        for sample in rows:
            writer.append(sample)
    name = fire_object_name(obj)
    old = bpy.data.objects.get(name)
    mesh = old.data if old is not None and old.type == "MESH" else None
    if mesh is None or len(mesh.vertices) != 2 * count:
        mesh = bpy.data.meshes.new(name)
        mesh.vertices.add(2 * count)
    path = sheet_pc2_path[:-len(".pc2")] + "_fire.pc2"
    fire, gn, ident = _particle_object(obj, name, mesh, path, frame_start, 0, fire_material())
    gn[ident["Count"]] = count
    light, gn, ident = _particle_object(obj, light_object_name(obj), mesh, path, frame_start, 1,
                                        light_material())
    gn[ident["Count"]] = count
    apply_embers(obj, sheet_pc2_path, frames, frame_start)
    apply_lamps(obj, frames, frame_start)
    light.visible_camera = False
    light.visible_glossy = False
    light.visible_transmission = False
    light.visible_volume_scatter = False
    light.hide_select = True
    sync_flame_settings(obj)


# --- EEVEE's flame light -----------------------------------------------------------------------
LAMPS = 4              # point lights per sheet, one per quarter of the fire around its centre
LAMP_POWER = 0.00065   # W per unit of flame weight (T/T0)^4 at Intensity 1 (see docs/blender.md)
LAMP_LIFT = 0.5        # of Flame Height: the lamps sit in the flames, above their particles
LAMP_RADIUS = 0.02     # m: soft shadows, as from a flame's width


def lamp_object_name(obj, k: int) -> str:
    return f"ThinBurn Fire Lamp {k + 1} {obj.name}"


def lamp_frames(frames, lift: float):
    """Per frame, LAMPS (x, y, z, weight): the hot particles (Min Temperature and up) split into
    LAMPS sectors of the XY plane around their weight centre, each sector's weight centre
    ``lift`` above it and its weight sum(T/T0)^4. A lamp with no particle keeps its last place
    at weight 0. Returns (frames, LAMPS, 4)."""
    out = np.zeros((len(frames), LAMPS, 4))
    for f, (pos, temp) in enumerate(frames):
        pos = np.asarray(pos, dtype=np.float64).reshape(-1, 3)
        temp = np.asarray(temp, dtype=np.float64).reshape(-1)
        if f:
            out[f, :, :3] = out[f - 1, :, :3]
        hot = temp >= MIN_TEMPERATURE
        if not hot.any():
            continue
        w, p = (temp[hot] / FLAME_K) ** 4, pos[hot]
        centre = w @ p / w.sum()
        angle = np.arctan2(p[:, 1] - centre[1], p[:, 0] - centre[0])
        sector = np.floor((angle + np.pi) / (2 * np.pi) * LAMPS).astype(int) % LAMPS
        for k in range(LAMPS):
            mine = sector == k
            if mine.any():
                out[f, k, :3] = w[mine] @ p[mine] / w[mine].sum() + (0.0, 0.0, lift)
                out[f, k, 3] = w[mine].sum()
    return out


def _eevee_only_light(name):
    """A point light Cycles leaves dark (its light nodes emit 0) and EEVEE, which ignores light
    nodes, lights with: Cycles has the camera-invisible flame spheres instead."""
    data = bpy.data.lights.get(name)
    if data is None or data.type != "POINT":
        data = bpy.data.lights.new(name, "POINT")
    data.shadow_soft_size = LAMP_RADIUS
    data.use_temperature = True
    data.use_nodes = True
    emit = next(n for n in data.node_tree.nodes if n.bl_idname == "ShaderNodeEmission")
    emit.inputs["Strength"].default_value = 0.0
    return data


def apply_lamps(obj, frames, frame_start: float) -> None:
    """"ThinBurn Fire Lamp 1..LAMPS <sheet>": keyframed point lights that follow the fire
    (EEVEE's flame light; see _eevee_only_light)."""
    settings = getattr(obj, "thinburn", None)
    height = float(getattr(settings, "flame_height", FLAME_HEIGHT))
    track = lamp_frames(frames, LAMP_LIFT * height)
    for k in range(LAMPS):
        name = lamp_object_name(obj, k)
        lamp = bpy.data.objects.get(name)
        if lamp is not None and lamp.type != "LIGHT":
            bpy.data.objects.remove(lamp)
            lamp = None
        if lamp is None:
            lamp = bpy.data.objects.new(name, _eevee_only_light(name))
            for coll in obj.users_collection:
                coll.objects.link(lamp)
        lamp.hide_select = True
        lamp.animation_data_clear()
        lamp.data.animation_data_clear()
        for f, (x, y, z, weight) in enumerate(track[:, k]):
            lamp.location = (x, y, z)
            lamp.keyframe_insert("location", frame=frame_start + f)
            lamp.data.energy = LAMP_POWER * weight
            lamp.data.keyframe_insert("energy", frame=frame_start + f)
    sync_lamps(obj)


def sync_lamps(obj) -> None:
    """The lamps' colour and brightness follow Flame Temperature and Intensity (live)."""
    settings = getattr(obj, "thinburn", None)
    for k in range(LAMPS):
        lamp = bpy.data.objects.get(lamp_object_name(obj, k))
        if lamp is None or lamp.type != "LIGHT":
            continue
        lamp.data.temperature = float(getattr(settings, "flame_temperature", FLAME_COLOR_K))
        intensity = float(getattr(settings, "flame_intensity", 1.0))
        lamp.data.exposure = float(np.log2(max(intensity, 1e-6)))


# --- ash flakes -----------------------------------------------------------------------------------
FLAKE_MATERIAL = "ThinBurn Ash"
ATTR_BREAK = "tb_break_frame"  # the frame a flake breaks off (its material glows from then on)
FLAKE_SIZE = 0.012     # m: side of a flake (a piece of a few faces of a fine mesh)
FLAKE_FALL = 0.35      # m/s: terminal speed of a light flake of char
FLAKE_DRAG = 4.0       # 1/s: how fast it reaches the air's speed plus its fall
FLAKE_FLUTTER = 0.12   # m/s: amplitude of its side-to-side swing
FLAKE_SPIN = (2.0, 6.0)  # rad/s: tumbling
FLAKE_LIFT = (0.6, 1.0)  # m/s: the fire's updraft under a flake as it breaks off (> FLAKE_FALL) ...
FLAKE_LIFT_TIME = 0.5  # s: ... which fades as the flake leaves the flames
FLAKE_SCATTER = (0.05, 0.25)  # m/s: ... and carries it sideways, out of the burnt hole
FLAKE_GLOW_TIME = 0.4  # s: its ember glow fades to 1/e in this time
FLAKE_GLOW = 1.5       # emission strength of a flake as it breaks off
FLAKE_RAGGED = (0.6, 1.3, 0.25)  # a flake's size factor (low, high) and its corners' jitter
FLAKE_GLOW_K = 1150.0  # K: the colour of that glow (dull orange)


def flake_object_name(obj) -> str:
    return f"ThinBurn Ash {obj.name}"


def _rotate(vectors, axes, angles):
    """Rodrigues: (k, m, 3) vectors turned about unit axes (k, 3) by angles (k,)."""
    c, s = np.cos(angles)[:, None, None], np.sin(angles)[:, None, None]
    a = axes[:, None, :]
    return (vectors * c + np.cross(a, vectors) * s
            + a * np.sum(a * vectors, axis=2, keepdims=True) * (1 - c))


def _pick_flakes(positions, faces, burnout, share, rng):
    """The faces that shed a flake: each face that burns out within the bake, with probability
    share * (face area / flake area), at most 1 (small faces: one flake for several of them).
    Returns, per flake in face order, (the frame index it breaks off at, its centre, its
    face's unit normal and first edge's direction) there; numpy over the faces of each size."""
    n_frames = positions.shape[0]
    draws = rng.random(len(faces))  # one per face, in face order
    found = []
    by_size = {}
    for i, face in enumerate(faces):
        by_size.setdefault(len(face), []).append(i)
    for size, which in by_size.items():
        which = np.array(which)
        idx = np.array([faces[i] for i in which], dtype=np.int64).reshape(-1, size)
        when = burnout[idx].max(axis=1)
        soon = when < n_frames - 1
        which, idx, f0 = which[soon], idx[soon], np.ceil(when[soon]).astype(int)
        pts = positions[f0[:, None], idx]  # (m, size, 3) at the frame each burns out
        edge = np.linalg.norm(pts - np.roll(pts, 1, axis=1), axis=2).mean(axis=1)
        keep = draws[which] < share * np.minimum(1.0, (edge / FLAKE_SIZE) ** 2)
        found.append((which[keep], f0[keep], pts[keep]))
    order = np.concatenate([w for w, _, _ in found]) if found else np.zeros(0, dtype=int)
    if len(order) == 0:
        return np.zeros(0, dtype=int), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3))
    f0 = np.concatenate([f for _, f, _ in found])
    centre = np.concatenate([p.mean(axis=1) for _, _, p in found])
    normal = np.concatenate([np.cross(p[:, 1] - p[:, 0], p[:, -1] - p[:, 0]) for _, _, p in found])
    first = np.concatenate([p[:, 1] - p[:, 0] for _, _, p in found])
    sort = np.argsort(order, kind="stable")
    f0, centre, normal, first = f0[sort], centre[sort], normal[sort], first[sort]
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    normal = np.where(length > 1e-12, normal / np.maximum(length, 1e-12), (0.0, 0.0, 1.0))
    first = first - normal * np.sum(first * normal, axis=1, keepdims=True)
    first /= np.maximum(np.linalg.norm(first, axis=1, keepdims=True), 1e-12)
    return f0, centre, normal, first


def flake_frames(positions, faces, burnout, dt: float, share: float, seed: int = 0,
                 floor=None, wind=(0.0, 0.0, 0.0)):
    """Flakes of brittle char that break off where faces burn out.

    ``positions`` (frames, n, 3) world positions of the baked sheet, ``faces`` a list of vertex
    index lists, ``burnout`` (n,) frames since the first frame (cache.NEVER_FRAME: never).
    Faces that burn out within the bake shed flakes (_pick_flakes): a torn quad about
    FLAKE_SIZE across, at the face, that the fire's updraft first lifts (FLAKE_LIFT, fading
    over FLAKE_LIFT_TIME) and carries sideways (FLAKE_SCATTER), then falls at FLAKE_FALL,
    swings from side to side, tumbles, drifts with the wind and comes to rest flat on
    ``floor`` (a world height; None: it keeps falling). Before it breaks off the flake is
    folded into a point (invisible). Returns
    ((frames, 4 * flakes, 3) corners, the number of flakes, (flakes,) the frame index each
    breaks off at). Deterministic per seed; all flakes move together (numpy), frame by frame."""
    positions = np.asarray(positions, dtype=np.float64)
    n_frames = positions.shape[0]
    rng = np.random.default_rng([int(seed), 0xA5A5])
    wind = np.asarray(wind, dtype=np.float64)
    f0, centre, normal, u = _pick_flakes(positions, faces, burnout, share, rng)
    k = len(f0)
    out = np.zeros((n_frames, 4 * k, 3), dtype=np.float32)
    if k == 0:
        return out, 0, f0
    v = np.cross(normal, u)
    corners = 0.5 * FLAKE_SIZE * np.stack([u + v, -u + v, -u - v, u - v], axis=1)  # about the centre
    low, high, jitter = FLAKE_RAGGED  # torn, not cut: uneven sizes and corners
    corners *= (rng.uniform(low, high, size=k)[:, None, None]
                * rng.uniform(1 - jitter, 1 + jitter, size=(k, 4))[:, :, None])
    axes = rng.standard_normal((k, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    spin = rng.uniform(*FLAKE_SPIN, size=k) * rng.choice([-1.0, 1.0], size=k)
    phase = rng.uniform(0, 2 * np.pi, size=k)
    swing_dir = np.stack([np.cos(phase), np.sin(phase), np.zeros(k)], axis=1)
    swing_rate = rng.uniform(2.0, 4.0, size=k)
    lift = rng.uniform(*FLAKE_LIFT, size=k)
    heading = rng.uniform(0, 2 * np.pi, size=k)
    scatter = rng.uniform(*FLAKE_SCATTER, size=k)[:, None] * np.stack(
        [np.cos(heading), np.sin(heading), np.zeros(k)], axis=1)
    flat = corners - normal[:, None, :] * np.sum(corners * normal[:, None, :], axis=2, keepdims=True)
    flat[:, :, 2] = 0.0  # how a flake lies once it has landed
    pos, vel, angle = centre.copy(), np.zeros((k, 3)), np.zeros(k)
    landed = np.zeros(k, dtype=bool)
    rest = np.zeros((k, 4, 3))
    for f in range(n_frames):
        free = (f >= f0) & ~landed
        t = (f - f0) * dt
        draft = np.exp(-np.maximum(t, 0.0) / FLAKE_LIFT_TIME)[:, None]  # the fire's, fading
        target = wind + draft * scatter
        target[:, 2] += lift * draft[:, 0] - FLAKE_FALL
        target += (FLAKE_FLUTTER * swing_rate / 3.0 * np.sin(swing_rate * t))[:, None] * swing_dir
        vel[free] += FLAKE_DRAG * (target[free] - vel[free]) * dt
        moving = free & (f > f0)
        pos[moving] += vel[moving] * dt
        angle[moving] += spin[moving] * dt
        shape = _rotate(corners, axes, angle)
        if floor is not None:
            # only on the way down: a flake off a sheet lying on the floor rises first
            down = moving & (vel[:, 2] < 0) & (pos[:, 2] + shape[:, :, 2].min(axis=1) <= floor)
            landed |= down
            rest[down] = flat[down] + np.stack([pos[down, 0], pos[down, 1],
                                                np.full(int(down.sum()), floor + 0.0005)], axis=1)[:, None, :]
        now = np.where(landed[:, None, None], rest, pos[:, None, :] + shape)
        now[f < f0] = centre[f < f0, None, :]  # folded away until it breaks off
        out[f] = now.reshape(-1, 3)
    return out, k, f0


def flake_material(fps: float):
    """"ThinBurn Ash": black, rough char with a little grey sheen that glows a dull orange as
    it breaks off and cools to black within about FLAKE_GLOW_TIME (it reads the flake's
    tb_break_frame and the current frame, through a driver)."""
    mat, tree = _empty_material(FLAKE_MATERIAL, clear=False)
    if tree is None:
        mat = bpy.data.materials[FLAKE_MATERIAL]
        _set_glow_rate(mat, fps)
        return mat
    bsdf = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    bsdf.inputs["Base Color"].default_value = (0.03, 0.028, 0.026, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.85
    bsdf.inputs["Sheen Weight"].default_value = 0.4  # ash's grey fuzz at grazing angles
    frame = node(tree, "ShaderNodeValue", -1000, -300, label="Frame")
    frame.name = "Frame"
    curve = frame.outputs[0].driver_add("default_value")
    curve.driver.type = "SCRIPTED"
    curve.driver.expression = "frame"
    broke = node(tree, "ShaderNodeAttribute", -1000, -450, attribute_type="GEOMETRY",
                 attribute_name=ATTR_BREAK)
    age = node(tree, "ShaderNodeMath", -800, -350, operation="SUBTRACT")  # frames since
    tree.links.new(frame.outputs[0], age.inputs[0])
    tree.links.new(broke.outputs["Fac"], age.inputs[1])
    rate = node(tree, "ShaderNodeMath", -600, -350, operation="MULTIPLY")
    rate.name = "Glow Rate"
    tree.links.new(age.outputs[0], rate.inputs[0])
    fade = node(tree, "ShaderNodeMath", -400, -350, operation="EXPONENT")
    tree.links.new(rate.outputs[0], fade.inputs[0])
    glow = node(tree, "ShaderNodeMath", -200, -350, operation="MULTIPLY")
    tree.links.new(fade.outputs[0], glow.inputs[0])
    glow.inputs[1].default_value = FLAKE_GLOW
    body = node(tree, "ShaderNodeBlackbody", -200, -150)
    body.inputs["Temperature"].default_value = FLAKE_GLOW_K
    tree.links.new(body.outputs[0], bsdf.inputs["Emission Color"])
    tree.links.new(glow.outputs[0], bsdf.inputs["Emission Strength"])
    _set_glow_rate(mat, fps)
    return mat


def _set_glow_rate(mat, fps: float) -> None:
    """exp(-age_frames / (FLAKE_GLOW_TIME * fps)): the scene's frame rate sets the fade."""
    rate = mat.node_tree.nodes.get("Glow Rate") if mat.node_tree is not None else None
    if rate is not None:
        rate.inputs[1].default_value = -1.0 / (FLAKE_GLOW_TIME * fps)


def apply_flakes(obj, sheet_pc2_path: str, frame_start: float, burnout_frames, floor) -> None:
    """Ash flakes for a finished bake: "ThinBurn Ash <sheet>" playing ``<name>_ash.pc2``."""
    settings = getattr(obj, "thinburn", None)
    share = float(getattr(settings, "flakes", 0.0))
    name = flake_object_name(obj)
    old = bpy.data.objects.get(name)
    if old is not None:
        bpy.data.objects.remove(old)
    if share <= 0.0:
        return
    abs_sheet = bpy.path.abspath(sheet_pc2_path)
    _, local = cache.read_pc2(abs_sheet)
    m = np.array(obj.matrix_world, dtype=np.float64)
    world = local @ m[:3, :3].T + m[:3, 3]
    faces = [list(p.vertices) for p in obj.data.polygons]
    since = np.asarray(burnout_frames, dtype=np.float64) - frame_start
    scene = bpy.context.scene
    dt = scene.render.fps_base / scene.render.fps
    corners, count, broke = flake_frames(world, faces, since, dt, share,
                                         seed=int(getattr(settings, "seed", 0)), floor=floor)
    if count == 0:
        return
    abs_path = abs_sheet[:-len(".pc2")] + "_ash.pc2"
    with cache.PC2Writer(abs_path, 4 * count, start_frame=frame_start) as writer:
        for sample in corners:
            writer.append(sample)
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(corners[0].tolist(), [], [(4 * k, 4 * k + 1, 4 * k + 2, 4 * k + 3)
                                              for k in range(count)])
    cache.write_point_attribute(mesh, ATTR_BREAK, np.repeat(frame_start + broke, 4).astype(np.float32))
    mesh.materials.append(flake_material(1.0 / dt))
    flakes = bpy.data.objects.new(name, mesh)
    for coll in obj.users_collection:
        coll.objects.link(flakes)
    md = ensure_modifier(flakes, CACHE_MODIFIER, "MESH_CACHE", 0)
    md.cache_format = "PC2"
    md.filepath = sheet_pc2_path[:-len(".pc2")] + "_ash.pc2"
    md.frame_start = frame_start
    md.interpolation = "LINEAR"
    md.forward_axis, md.up_axis = "POS_Y", "POS_Z"
