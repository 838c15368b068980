"""What a bake adds to the sheet, all of it plain Blender data that renders without the add-on.

* Modifier "ThinBurn Cache" (Mesh Cache, PC2), first in the stack: the baked motion.
* Point attributes ``thinburn_ignite_time`` and ``thinburn_burnout_time``, in frames
  (cache.NEVER_FRAME where a vertex never ignites).
* Modifier "ThinBurn Burn" (geometry nodes, group "ThinBurn Burn"), right after the cache: it
  writes the colour attribute ``thinburn_char`` for the current frame (viewport) and removes
  faces whose vertices have all burnt out. The cache always sees the full mesh.
* Shader node group "ThinBurn Char": char colour, a glowing ember edge and burn-through
  (alpha) from the two time attributes and the frame (a driver, ``frame``, feeds it).
"""
from __future__ import annotations

import os

import numpy as np

import bpy

from . import cache

CACHE_MODIFIER = "ThinBurn Cache"
BURN_MODIFIER = "ThinBurn Burn"
BURN_GROUP = "ThinBurn Burn"
CHAR_GROUP = "ThinBurn Char"
FIRE_GROUP = "ThinBurn Fire"
ATTR_IGNITE = "thinburn_ignite_time"
ATTR_BURNOUT = "thinburn_burnout_time"
ATTR_CHAR = "thinburn_char"
PAPER = (0.85, 0.80, 0.70, 1.0)
CHAR = (0.02, 0.015, 0.01, 1.0)
EMBER = (1.0, 0.35, 0.05, 1.0)
EMBER_KELVIN = 1300.0
CHAR_POINT = 0.4  # share of a cell's burn after which it looks fully charred


# --- small node-building helpers ---------------------------------------------------------------
def _socket(sockets, key):
    """A socket by identifier, else by name (first available one)."""
    for s in sockets:
        if s.identifier == key:
            return s
    for s in sockets:
        if s.name == key and s.enabled:
            return s
    raise KeyError(key)


def _node(tree, kind, x, y, **attrs):
    node = tree.nodes.new(kind)
    node.location = (x, y)
    for k, v in attrs.items():
        setattr(node, k, v)
    return node


def _link(tree, out_node, out_key, in_node, in_key):
    tree.links.new(_socket(out_node.outputs, out_key), _socket(in_node.inputs, in_key))


def _set(node, key, value):
    _socket(node.inputs, key).default_value = value


def _new_group(name, kind):
    old = bpy.data.node_groups.get(name)
    if old is not None:
        return old, False
    return bpy.data.node_groups.new(name, kind), True


def _io(tree, name, in_out, socket_type, default=None, lo=None, hi=None, desc=""):
    s = tree.interface.new_socket(name, in_out=in_out, socket_type=socket_type, description=desc)
    if default is not None:
        s.default_value = default
    if lo is not None:
        s.min_value = lo
    if hi is not None:
        s.max_value = hi
    return s


def _map_range(tree, x, y, value, lo, hi, clamp=True, interp="LINEAR"):
    """MapRange(value from [lo, hi] to [0, 1]); each argument is (node, socket) or a number."""
    n = _node(tree, "ShaderNodeMapRange", x, y, clamp=clamp, interpolation_type=interp)
    for key, src in (("Value", value), ("From Min", lo), ("From Max", hi)):
        if isinstance(src, tuple):
            _link(tree, src[0], src[1], n, key)
        else:
            _set(n, key, src)
    return n


# --- the shader group ----------------------------------------------------------------------------
def char_group():
    """Shader node group "ThinBurn Char" (created once, then reused)."""
    tree, fresh = _new_group(CHAR_GROUP, "ShaderNodeTree")
    if not fresh:
        return tree
    _io(tree, "Shader", "OUTPUT", "NodeSocketShader")
    _io(tree, "Char", "OUTPUT", "NodeSocketFloat", desc="0 unburnt .. 1 fully charred")
    _io(tree, "Ember", "OUTPUT", "NodeSocketFloat", desc="Glow weight of the ember edge")
    _io(tree, "Alpha", "OUTPUT", "NodeSocketFloat", desc="0 where burnt through")
    _io(tree, "Frame", "INPUT", "NodeSocketFloat", 1.0, desc="The scene frame (a driver: frame)")
    _io(tree, "Paper Color", "INPUT", "NodeSocketColor", PAPER, desc="Colour of the unburnt sheet")
    _io(tree, "Char Color", "INPUT", "NodeSocketColor", CHAR, desc="Colour of fully charred material")
    _io(tree, "Ember Strength", "INPUT", "NodeSocketFloat", 6.0, 0.0, 1000.0,
        desc="Emission strength of the glowing edge")
    _io(tree, "Ember Width", "INPUT", "NodeSocketFloat", 0.3, 0.0, 1.0,
        desc="Share of the burn, before burn-through, that glows")
    _io(tree, "Char Point", "INPUT", "NodeSocketFloat", CHAR_POINT, 0.01, 1.0,
        desc="Share of the burn after which the material is fully charred")
    _io(tree, "Roughness", "INPUT", "NodeSocketFloat", 0.9, 0.0, 1.0)

    gi = _node(tree, "NodeGroupInput", -900, 0)
    go = _node(tree, "NodeGroupOutput", 700, 0)
    ig = _node(tree, "ShaderNodeAttribute", -900, 300, attribute_type="GEOMETRY", attribute_name=ATTR_IGNITE)
    bo = _node(tree, "ShaderNodeAttribute", -900, 150, attribute_type="GEOMETRY", attribute_name=ATTR_BURNOUT)
    char = _map_range(tree, -600, 300, (gi, "Frame"), (ig, "Fac"), (bo, "Fac"))
    width_lo = _node(tree, "ShaderNodeMath", -600, 0, operation="SUBTRACT")
    width_lo.inputs[0].default_value = 1.0
    tree.links.new(gi.outputs["Ember Width"], width_lo.inputs[1])
    glow = _map_range(tree, -400, 100, (char, "Result"), (width_lo, "Value"), 1.0, interp="SMOOTHSTEP")
    alive = _node(tree, "ShaderNodeMath", -600, -200, operation="LESS_THAN")
    tree.links.new(gi.outputs["Frame"], alive.inputs[0])
    tree.links.new(bo.outputs["Fac"], alive.inputs[1])
    ember = _node(tree, "ShaderNodeMath", -200, 0, operation="MULTIPLY")
    tree.links.new(glow.outputs["Result"], ember.inputs[0])
    tree.links.new(alive.outputs[0], ember.inputs[1])
    dark = _map_range(tree, -400, 400, (char, "Result"), 0.0, (gi, "Char Point"), interp="SMOOTHSTEP")
    mix = _node(tree, "ShaderNodeMix", -200, 300, data_type="RGBA")
    _link(tree, dark, "Result", mix, "Factor_Float")
    _link(tree, gi, "Paper Color", mix, "A_Color")
    _link(tree, gi, "Char Color", mix, "B_Color")
    bsdf = _node(tree, "ShaderNodeBsdfPrincipled", 50, 350)
    _link(tree, mix, "Result_Color", bsdf, "Base Color")
    _link(tree, gi, "Roughness", bsdf, "Roughness")
    kelvin = _node(tree, "ShaderNodeBlackbody", -200, -250)
    _set(kelvin, "Temperature", EMBER_KELVIN)
    strength = _node(tree, "ShaderNodeMath", 50, -100, operation="MULTIPLY")
    tree.links.new(ember.outputs[0], strength.inputs[0])
    tree.links.new(gi.outputs["Ember Strength"], strength.inputs[1])
    emit = _node(tree, "ShaderNodeEmission", 250, -100)
    _link(tree, kelvin, "Color", emit, "Color")
    tree.links.new(strength.outputs[0], emit.inputs["Strength"])
    add = _node(tree, "ShaderNodeAddShader", 400, 150)
    tree.links.new(bsdf.outputs[0], add.inputs[0])
    tree.links.new(emit.outputs[0], add.inputs[1])
    clear = _node(tree, "ShaderNodeBsdfTransparent", 400, -150)
    out = _node(tree, "ShaderNodeMixShader", 550, 0)
    tree.links.new(alive.outputs[0], out.inputs[0])
    tree.links.new(clear.outputs[0], out.inputs[1])
    tree.links.new(add.outputs[0], out.inputs[2])
    tree.links.new(out.outputs[0], go.inputs["Shader"])
    tree.links.new(char.outputs["Result"], go.inputs["Char"])
    tree.links.new(ember.outputs[0], go.inputs["Ember"])
    tree.links.new(alive.outputs[0], go.inputs["Alpha"])
    return tree


# --- the geometry-nodes group after the cache ---------------------------------------------------
def burn_group():
    """Geometry node group "ThinBurn Burn": viewport char colour and removal of burnt faces."""
    tree, fresh = _new_group(BURN_GROUP, "GeometryNodeTree")
    if not fresh:
        return tree
    _io(tree, "Geometry", "INPUT", "NodeSocketGeometry")
    _io(tree, "Remove Burnt", "INPUT", "NodeSocketBool", True,
        desc="Delete faces whose vertices have all burnt out (burn-through in the viewport)")
    _io(tree, "Geometry", "OUTPUT", "NodeSocketGeometry")

    gi = _node(tree, "NodeGroupInput", -1000, 0)
    go = _node(tree, "NodeGroupOutput", 900, 0)
    now = _node(tree, "GeometryNodeInputSceneTime", -1000, 300)
    ig = _node(tree, "GeometryNodeInputNamedAttribute", -1000, 150, data_type="FLOAT")
    _set(ig, "Name", ATTR_IGNITE)
    bo = _node(tree, "GeometryNodeInputNamedAttribute", -1000, -150, data_type="FLOAT")
    _set(bo, "Name", ATTR_BURNOUT)
    char = _map_range(tree, -750, 300, (now, "Frame"), (ig, "Attribute"), (bo, "Attribute"))
    glow = _map_range(tree, -550, 100, (char, "Result"), 0.6, 1.0, interp="SMOOTHSTEP")
    alive = _node(tree, "FunctionNodeCompare", -750, -100, data_type="FLOAT", operation="LESS_THAN")
    _link(tree, now, "Frame", alive, "A")
    _link(tree, bo, "Attribute", alive, "B")
    ember = _node(tree, "ShaderNodeMath", -350, 100, operation="MULTIPLY")
    tree.links.new(glow.outputs["Result"], ember.inputs[0])
    tree.links.new(alive.outputs[0], ember.inputs[1])
    dark = _map_range(tree, -550, 400, (char, "Result"), 0.0, CHAR_POINT, interp="SMOOTHSTEP")
    charred = _node(tree, "ShaderNodeMix", -350, 350, data_type="RGBA")
    _link(tree, dark, "Result", charred, "Factor_Float")
    _set(charred, "A_Color", PAPER)
    _set(charred, "B_Color", CHAR)
    colour = _node(tree, "ShaderNodeMix", -150, 300, data_type="RGBA")
    tree.links.new(ember.outputs[0], _socket(colour.inputs, "Factor_Float"))
    _link(tree, charred, "Result_Color", colour, "A_Color")
    _set(colour, "B_Color", EMBER)
    store = _node(tree, "GeometryNodeStoreNamedAttribute", 100, 0, data_type="FLOAT_COLOR", domain="POINT")
    _set(store, "Name", ATTR_CHAR)
    _link(tree, gi, "Geometry", store, "Geometry")
    _link(tree, colour, "Result_Color", store, "Value")
    # A face goes only when all its vertices burnt out: capture the test on points, then read
    # it on faces (a boolean is true on a face when true on all its points).
    burnt = _node(tree, "FunctionNodeBooleanMath", -150, -150, operation="NOT")
    tree.links.new(alive.outputs[0], burnt.inputs[0])
    capture = _node(tree, "GeometryNodeCaptureAttribute", 300, 0, domain="POINT")
    capture.capture_items.new("BOOLEAN", "Burnt")
    tree.links.new(store.outputs[0], capture.inputs[0])
    tree.links.new(burnt.outputs[0], capture.inputs[1])
    gate = _node(tree, "FunctionNodeBooleanMath", 500, -150, operation="AND")
    tree.links.new(capture.outputs[1], gate.inputs[0])
    tree.links.new(gi.outputs["Remove Burnt"], gate.inputs[1])
    delete = _node(tree, "GeometryNodeDeleteGeometry", 700, 0, domain="FACE", mode="ONLY_FACE")
    tree.links.new(capture.outputs[0], delete.inputs["Geometry"])
    tree.links.new(gate.outputs[0], delete.inputs["Selection"])
    tree.links.new(delete.outputs[0], go.inputs["Geometry"])
    return tree


def _use_nodes(mat):
    if mat.node_tree is None:  # Blender < 5.0 starts materials without nodes
        mat.use_nodes = True


# --- applying and freeing a bake ------------------------------------------------------------------
def char_material(obj):
    """A material "ThinBurn <sheet>" whose surface is the "ThinBurn Char" group."""
    mat = bpy.data.materials.new(f"ThinBurn {obj.name}")
    _use_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    group = _node(tree, "ShaderNodeGroup", 0, 0, node_tree=char_group())
    group.name = CHAR_GROUP
    out = _node(tree, "ShaderNodeOutputMaterial", 300, 0)
    tree.links.new(group.outputs["Shader"], out.inputs["Surface"])
    fcurve = group.inputs["Frame"].driver_add("default_value")
    fcurve.driver.type = "SCRIPTED"
    fcurve.driver.expression = "frame"
    if hasattr(mat, "surface_render_method"):
        mat.surface_render_method = "DITHERED"
    return mat


def _modifier(obj, name, kind, index):
    md = obj.modifiers.get(name)
    if md is not None and md.type != kind:
        obj.modifiers.remove(md)
        md = None
    if md is None:
        md = obj.modifiers.new(name, kind)
    current = list(obj.modifiers).index(md)
    if current != index:
        obj.modifiers.move(current, index)
    return md


def apply_bake(obj, pc2_path: str, frame_start: float, ignite, burnout) -> None:
    """Hook a finished bake onto the sheet: attributes, modifiers, and a material if it has none."""
    mesh = obj.data
    cache.write_point_attribute(mesh, ATTR_IGNITE, ignite)
    cache.write_point_attribute(mesh, ATTR_BURNOUT, burnout)
    base = np.tile(np.asarray(PAPER, dtype=np.float32), (len(mesh.vertices), 1))
    cache.write_point_attribute(mesh, ATTR_CHAR, base, "FLOAT_COLOR")
    mesh.color_attributes.active_color = mesh.color_attributes[ATTR_CHAR]
    mesh.color_attributes.render_color_index = mesh.color_attributes.active_color_index

    md = _modifier(obj, CACHE_MODIFIER, "MESH_CACHE", 0)
    md.cache_format = "PC2"
    md.filepath = pc2_path
    md.frame_start = frame_start  # PC2 sample 0 is this frame
    md.frame_scale = 1.0
    md.play_mode = "SCENE"
    md.time_mode = "FRAME"
    md.interpolation = "LINEAR"
    md.deform_mode = "OVERWRITE"
    md.forward_axis, md.up_axis = "POS_Y", "POS_Z"
    burn = _modifier(obj, BURN_MODIFIER, "NODES", 1)
    burn.node_group = burn_group()

    if not any(slot.material for slot in obj.material_slots):
        mat = char_material(obj)
        if obj.material_slots:
            obj.material_slots[0].material = mat
        else:
            obj.data.materials.append(mat)
    obj.update_tag()
    mesh.update()


def free_bake(obj) -> list:
    """Remove what apply_bake added (and the cache files); returns what went, for the report."""
    gone = []
    md = obj.modifiers.get(CACHE_MODIFIER)
    paths = set()
    if obj.thinburn.baked_file:
        paths.add(bpy.path.abspath(obj.thinburn.baked_file))
    if md is not None:
        if md.filepath:
            paths.add(bpy.path.abspath(md.filepath))
        obj.modifiers.remove(md)
        gone.append("modifier " + CACHE_MODIFIER)
    md = obj.modifiers.get(BURN_MODIFIER)
    if md is not None:
        obj.modifiers.remove(md)
        gone.append("modifier " + BURN_MODIFIER)
    if cache.remove_attributes(obj.data, (ATTR_IGNITE, ATTR_BURNOUT, ATTR_CHAR)):
        gone.append("attributes")
    for i, slot in enumerate(obj.material_slots):
        mat = slot.material
        if mat is not None and mat.name == f"ThinBurn {obj.name}":
            obj.data.materials.pop(index=i)
            if mat.users == 0:
                bpy.data.materials.remove(mat)
            gone.append("material")
            break
    fire = bpy.data.objects.get(fire_object_name(obj))
    if fire is not None:
        fmd = fire.modifiers.get(CACHE_MODIFIER)
        if fmd is not None and fmd.filepath:
            paths.add(bpy.path.abspath(fmd.filepath))
        mesh = fire.data
        bpy.data.objects.remove(fire)
        if mesh is not None and mesh.users == 0:
            bpy.data.meshes.remove(mesh)
        gone.append("fire particles")
    for path in sorted(paths):
        for p in (path, path + ".partial"):
            if os.path.exists(p):
                os.remove(p)
                gone.append("file " + os.path.basename(p))
    obj.thinburn.baked_file = ""
    obj.update_tag()
    return gone


# --- fire particles (needs thinburn.Simulation.particles) -----------------------------------------
def fire_object_name(obj) -> str:
    return f"ThinBurn Fire {obj.name}"


def fire_group():
    """Geometry node group "ThinBurn Fire": the first Count points of the cached mesh become a
    point cloud; point Count + i carries (temperature, alive, 0) of particle i."""
    tree, fresh = _new_group(FIRE_GROUP, "GeometryNodeTree")
    if not fresh:
        return tree
    _io(tree, "Geometry", "INPUT", "NodeSocketGeometry")
    _io(tree, "Count", "INPUT", "NodeSocketInt", 1, 0, desc="Particle slots in the cache")
    _io(tree, "Radius", "INPUT", "NodeSocketFloat", 0.004, 0.0, desc="Radius of a fire particle, m")
    _io(tree, "Material", "INPUT", "NodeSocketMaterial")
    _io(tree, "Geometry", "OUTPUT", "NodeSocketGeometry")
    gi = _node(tree, "NodeGroupInput", -900, 0)
    go = _node(tree, "NodeGroupOutput", 900, 0)
    index = _node(tree, "GeometryNodeInputIndex", -900, -300)
    pos = _node(tree, "GeometryNodeInputPosition", -900, -450)
    other = _node(tree, "ShaderNodeMath", -650, -300, operation="ADD")
    tree.links.new(index.outputs[0], other.inputs[0])
    tree.links.new(gi.outputs["Count"], other.inputs[1])
    sample = _node(tree, "GeometryNodeSampleIndex", -450, -200, data_type="FLOAT_VECTOR", domain="POINT")
    tree.links.new(gi.outputs["Geometry"], sample.inputs["Geometry"])
    tree.links.new(pos.outputs[0], _socket(sample.inputs, "Value"))
    tree.links.new(other.outputs[0], sample.inputs["Index"])
    split = _node(tree, "ShaderNodeSeparateXYZ", -250, -200)
    tree.links.new(_socket(sample.outputs, "Value"), split.inputs[0])
    first = _node(tree, "FunctionNodeCompare", -450, 100, data_type="INT", operation="LESS_THAN")
    tree.links.new(index.outputs[0], _socket(first.inputs, "A_INT"))
    tree.links.new(gi.outputs["Count"], _socket(first.inputs, "B_INT"))
    live = _node(tree, "FunctionNodeCompare", -50, -200, data_type="FLOAT", operation="GREATER_THAN")
    tree.links.new(split.outputs["Y"], live.inputs[0])
    _set(live, "B", 0.5)
    keep = _node(tree, "FunctionNodeBooleanMath", 150, 0, operation="AND")
    tree.links.new(first.outputs[0], keep.inputs[0])
    tree.links.new(live.outputs[0], keep.inputs[1])
    store = _node(tree, "GeometryNodeStoreNamedAttribute", 150, 250, data_type="FLOAT", domain="POINT")
    _set(store, "Name", "temperature")
    tree.links.new(gi.outputs["Geometry"], store.inputs["Geometry"])
    tree.links.new(split.outputs["X"], _socket(store.inputs, "Value"))
    points = _node(tree, "GeometryNodeMeshToPoints", 400, 100)
    tree.links.new(store.outputs[0], points.inputs["Mesh"])
    tree.links.new(keep.outputs[0], points.inputs["Selection"])
    tree.links.new(gi.outputs["Radius"], points.inputs["Radius"])
    setmat = _node(tree, "GeometryNodeSetMaterial", 650, 100)
    tree.links.new(points.outputs[0], setmat.inputs["Geometry"])
    tree.links.new(gi.outputs["Material"], setmat.inputs["Material"])
    tree.links.new(setmat.outputs[0], go.inputs["Geometry"])
    return tree


def fire_material():
    """Emission from the particles' temperature attribute (kelvin) through a blackbody."""
    mat = bpy.data.materials.get(FIRE_GROUP)
    if mat is not None:
        return mat
    mat = bpy.data.materials.new(FIRE_GROUP)
    _use_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    temp = _node(tree, "ShaderNodeAttribute", -600, 0, attribute_type="GEOMETRY", attribute_name="temperature")
    body = _node(tree, "ShaderNodeBlackbody", -350, 100)
    tree.links.new(temp.outputs["Fac"], body.inputs["Temperature"])
    # Brightness grows with temperature (Stefan-Boltzmann ~T^4), scaled so 1500 K gives 5.
    ratio = _node(tree, "ShaderNodeMath", -350, -100, operation="DIVIDE")
    tree.links.new(temp.outputs["Fac"], ratio.inputs[0])
    ratio.inputs[1].default_value = 1500.0
    power = _node(tree, "ShaderNodeMath", -150, -100, operation="POWER")
    tree.links.new(ratio.outputs[0], power.inputs[0])
    power.inputs[1].default_value = 4.0
    scale = _node(tree, "ShaderNodeMath", 50, -100, operation="MULTIPLY")
    tree.links.new(power.outputs[0], scale.inputs[0])
    scale.inputs[1].default_value = 5.0
    emit = _node(tree, "ShaderNodeEmission", 250, 0)
    tree.links.new(body.outputs[0], emit.inputs["Color"])
    tree.links.new(scale.outputs[0], emit.inputs["Strength"])
    out = _node(tree, "ShaderNodeOutputMaterial", 450, 0)
    tree.links.new(emit.outputs[0], out.inputs["Surface"])
    return mat


def particle_cache_rows(frames) -> tuple:
    """Pack per-frame particles [(positions (k, 3), temperatures (k,))] into equal-size PC2
    samples: K = max k; rows 0..K-1 positions, rows K..2K-1 (temperature, alive, 0)."""
    count = max([len(t) for _, t in frames] + [1])
    rows = []
    for pos, temp in frames:
        k = len(temp)
        sample = np.zeros((2 * count, 3), dtype=np.float32)
        sample[:k] = pos
        if k:
            sample[k:count] = pos[0]  # idle slots sit on a live particle, hidden by alive = 0
        sample[count:count + k, 0] = temp
        sample[count:count + k, 1] = 1.0
        rows.append(sample)
    return count, rows


def apply_particles(obj, sheet_pc2_path: str, frames, frame_start: float) -> None:
    """Write the fire particles to their own PC2 and an object "ThinBurn Fire <sheet>"."""
    count, rows = particle_cache_rows(frames)
    abs_sheet = bpy.path.abspath(sheet_pc2_path)
    abs_fire = abs_sheet[:-len(".pc2")] + "_fire.pc2"
    with cache.PC2Writer(abs_fire, 2 * count, start_frame=frame_start) as writer:
        for sample in rows:
            writer.append(sample)
    name = fire_object_name(obj)
    fire = bpy.data.objects.get(name)
    if fire is None or fire.type != "MESH" or len(fire.data.vertices) != 2 * count:
        if fire is not None:
            bpy.data.objects.remove(fire)
        mesh = bpy.data.meshes.new(name)
        mesh.vertices.add(2 * count)
        fire = bpy.data.objects.new(name, mesh)
        for coll in obj.users_collection:
            coll.objects.link(fire)
    md = _modifier(fire, CACHE_MODIFIER, "MESH_CACHE", 0)
    md.cache_format = "PC2"
    md.filepath = sheet_pc2_path[:-len(".pc2")] + "_fire.pc2"
    md.frame_start = frame_start
    md.interpolation = "NONE"  # slots are reused by different particles from frame to frame
    gn = _modifier(fire, FIRE_GROUP, "NODES", 1)
    gn.node_group = fire_group()
    ident = {s.name: s.identifier for s in gn.node_group.interface.items_tree
             if getattr(s, "in_out", "") == "INPUT"}
    gn[ident["Count"]] = count
    gn[ident["Material"]] = fire_material()
    fire.update_tag()
