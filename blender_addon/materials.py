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

from . import cache, mantaflow
from .fire import (LAMPS, apply_flakes, ember_object_name, fire_object_name, flake_object_name,
                   lamp_object_name, light_object_name)
from .nodes import (ensure_modifier, interface_socket, link, map_range, new_group, node, set_input,
                    socket, use_nodes)

CACHE_MODIFIER = "ThinBurn Cache"
BURN_MODIFIER = "ThinBurn Burn"
BURN_GROUP = "ThinBurn Burn"
CHAR_GROUP = "ThinBurn Char"
ATTR_IGNITE = "thinburn_ignite_time"
ATTR_BURNOUT = "thinburn_burnout_time"
ATTR_CHAR = "thinburn_char"
ATTR_BURNING = "thinburn_burning"  # 1 on the burning band this frame (Mantaflow's emitter)
PAPER = (0.85, 0.80, 0.70, 1.0)
CHAR = (0.02, 0.015, 0.01, 1.0)
EMBER = (1.0, 0.35, 0.05, 1.0)
EMBER_KELVIN = 1300.0
CHAR_POINT = 0.4  # share of a cell's burn after which it looks fully charred


# The burn's inputs, shared by the char group and the wrap group: (socket type, default, min,
# max, description).
BURN_INPUTS = {
    "Frame": ("NodeSocketFloat", 1.0, None, None, "The scene frame (a driver: frame)"),
    "Char Color": ("NodeSocketColor", CHAR, None, None, "Colour of fully charred material"),
    "Ember Strength": ("NodeSocketFloat", 6.0, 0.0, 1000.0, "Emission strength of the glowing edge"),
    "Ember Width": ("NodeSocketFloat", 0.3, 0.0, 1.0, "Share of the burn, before burn-through, that glows"),
    "Char Point": ("NodeSocketFloat", CHAR_POINT, 0.01, 1.0,
                   "Share of the burn after which the material is fully charred"),
    "Burn Through": ("NodeSocketFloat", 1.0, 0.0, 1.0, "1: burnt-out areas become holes; 0: they stay as char (ash)"),
}


def burn_input(tree, name):
    kind, default, lo, hi, desc = BURN_INPUTS[name]
    interface_socket(tree, name, "INPUT", kind, default, lo, hi, desc=desc)


# --- the shader group ----------------------------------------------------------------------------
def char_group():
    """Shader node group "ThinBurn Char" (created once, then reused)."""
    tree, fresh = new_group(CHAR_GROUP, "ShaderNodeTree")
    if not fresh:
        return tree
    interface_socket(tree, "Shader", "OUTPUT", "NodeSocketShader")
    interface_socket(tree, "Char", "OUTPUT", "NodeSocketFloat", desc="0 unburnt .. 1 fully charred")
    interface_socket(tree, "Ember", "OUTPUT", "NodeSocketFloat", desc="Glow weight of the ember edge")
    interface_socket(tree, "Alpha", "OUTPUT", "NodeSocketFloat", desc="0 where burnt through")
    burn_input(tree, "Frame")
    interface_socket(tree, "Paper Color", "INPUT", "NodeSocketColor", PAPER, desc="Colour of the unburnt sheet")
    for name in ("Char Color", "Ember Strength", "Ember Width", "Char Point"):
        burn_input(tree, name)
    interface_socket(tree, "Roughness", "INPUT", "NodeSocketFloat", 0.9, 0.0, 1.0)
    burn_input(tree, "Burn Through")

    gi = node(tree, "NodeGroupInput", -900, 0)
    go = node(tree, "NodeGroupOutput", 700, 0)
    ig = node(tree, "ShaderNodeAttribute", -900, 300, attribute_type="GEOMETRY", attribute_name=ATTR_IGNITE)
    bo = node(tree, "ShaderNodeAttribute", -900, 150, attribute_type="GEOMETRY", attribute_name=ATTR_BURNOUT)
    char = map_range(tree, -600, 300, (gi, "Frame"), (ig, "Fac"), (bo, "Fac"))
    width_lo = node(tree, "ShaderNodeMath", -600, 0, operation="SUBTRACT")
    width_lo.inputs[0].default_value = 1.0
    tree.links.new(gi.outputs["Ember Width"], width_lo.inputs[1])
    glow = map_range(tree, -400, 100, (char, "Result"), (width_lo, "Value"), 1.0, interp="SMOOTHSTEP")
    alive = node(tree, "ShaderNodeMath", -600, -200, operation="LESS_THAN")
    tree.links.new(gi.outputs["Frame"], alive.inputs[0])
    tree.links.new(bo.outputs["Fac"], alive.inputs[1])
    ember = node(tree, "ShaderNodeMath", -200, 0, operation="MULTIPLY")
    tree.links.new(glow.outputs["Result"], ember.inputs[0])
    tree.links.new(alive.outputs[0], ember.inputs[1])
    dark = map_range(tree, -400, 400, (char, "Result"), 0.0, (gi, "Char Point"), interp="SMOOTHSTEP")
    mix = node(tree, "ShaderNodeMix", -200, 300, data_type="RGBA")
    link(tree, dark, "Result", mix, "Factor_Float")
    link(tree, gi, "Paper Color", mix, "A_Color")
    link(tree, gi, "Char Color", mix, "B_Color")
    bsdf = node(tree, "ShaderNodeBsdfPrincipled", 50, 350)
    link(tree, mix, "Result_Color", bsdf, "Base Color")
    link(tree, gi, "Roughness", bsdf, "Roughness")
    kelvin = node(tree, "ShaderNodeBlackbody", -200, -250)
    set_input(kelvin, "Temperature", EMBER_KELVIN)
    strength = node(tree, "ShaderNodeMath", 50, -100, operation="MULTIPLY")
    tree.links.new(ember.outputs[0], strength.inputs[0])
    tree.links.new(gi.outputs["Ember Strength"], strength.inputs[1])
    emit = node(tree, "ShaderNodeEmission", 250, -100)
    link(tree, kelvin, "Color", emit, "Color")
    tree.links.new(strength.outputs[0], emit.inputs["Strength"])
    add = node(tree, "ShaderNodeAddShader", 400, 150)
    tree.links.new(bsdf.outputs[0], add.inputs[0])
    tree.links.new(emit.outputs[0], add.inputs[1])
    clear = node(tree, "ShaderNodeBsdfTransparent", 400, -150)
    keep = node(tree, "ShaderNodeMath", 400, -300, operation="SUBTRACT")  # 1 - Burn Through
    keep.inputs[0].default_value = 1.0
    tree.links.new(gi.outputs["Burn Through"], keep.inputs[1])
    solid = node(tree, "ShaderNodeMath", 550, -300, operation="MAXIMUM")
    tree.links.new(alive.outputs[0], solid.inputs[0])
    tree.links.new(keep.outputs[0], solid.inputs[1])
    out = node(tree, "ShaderNodeMixShader", 550, 0)
    tree.links.new(solid.outputs[0], out.inputs[0])
    tree.links.new(clear.outputs[0], out.inputs[1])
    tree.links.new(add.outputs[0], out.inputs[2])
    tree.links.new(out.outputs[0], go.inputs["Shader"])
    tree.links.new(char.outputs["Result"], go.inputs["Char"])
    tree.links.new(ember.outputs[0], go.inputs["Ember"])
    tree.links.new(alive.outputs[0], go.inputs["Alpha"])
    return tree


# --- burning any material -------------------------------------------------------------------------
WRAP_GROUP = "ThinBurn Burn Wrap"
WRAP_NODE = "ThinBurn Burn"  # the name of the inserted group node in a wrapped material


def wrap_group():
    """Shader node group "ThinBurn Burn Wrap": burns whatever shader comes in.

    Shader -> mix toward a char BSDF as the burn chars it -> plus the ember glow at the burning
    band -> mix with Transparent where burnt through. Where the mesh has no ThinBurn time
    attributes (they read 0) it passes the shader through untouched, so a material shared with
    other objects stays as it was on them."""
    tree, fresh = new_group(WRAP_GROUP, "ShaderNodeTree")
    if not fresh:
        return tree
    interface_socket(tree, "Shader", "INPUT", "NodeSocketShader", desc="The material's own shader")
    for name in ("Frame", "Char Color", "Ember Strength", "Ember Width", "Char Point", "Burn Through"):
        burn_input(tree, name)
    interface_socket(tree, "Shader", "OUTPUT", "NodeSocketShader")
    L = tree.links.new
    gi = node(tree, "NodeGroupInput", -1000, 0)
    go = node(tree, "NodeGroupOutput", 1000, 0)
    burn = node(tree, "ShaderNodeGroup", -700, 300, node_tree=char_group())
    for key in ("Frame", "Char Color", "Ember Strength", "Ember Width", "Char Point"):
        L(gi.outputs[key], burn.inputs[key])
    ig = node(tree, "ShaderNodeAttribute", -700, -250, attribute_type="GEOMETRY", attribute_name=ATTR_IGNITE)
    bo = node(tree, "ShaderNodeAttribute", -700, -400, attribute_type="GEOMETRY", attribute_name=ATTR_BURNOUT)
    baked = node(tree, "ShaderNodeMath", -450, -300, operation="GREATER_THAN")  # 0 without a bake
    L(bo.outputs["Fac"], baked.inputs[0])
    L(ig.outputs["Fac"], baked.inputs[1])
    dark = map_range(tree, -450, 300, (burn, "Char"), 0.0, (gi, "Char Point"), interp="SMOOTHSTEP")
    dark_here = node(tree, "ShaderNodeMath", -250, 300, operation="MULTIPLY")
    L(dark.outputs["Result"], dark_here.inputs[0])
    L(baked.outputs[0], dark_here.inputs[1])
    char_bsdf = node(tree, "ShaderNodeBsdfPrincipled", -250, 600)
    L(gi.outputs["Char Color"], char_bsdf.inputs["Base Color"])
    set_input(char_bsdf, "Roughness", 0.9)
    charred = node(tree, "ShaderNodeMixShader", 0, 300)
    L(dark_here.outputs[0], charred.inputs[0])
    L(gi.outputs["Shader"], charred.inputs[1])
    L(char_bsdf.outputs[0], charred.inputs[2])
    kelvin = node(tree, "ShaderNodeBlackbody", -250, -50)
    set_input(kelvin, "Temperature", EMBER_KELVIN)
    glow = node(tree, "ShaderNodeMath", -250, -200, operation="MULTIPLY")
    L(burn.outputs["Ember"], glow.inputs[0])
    L(gi.outputs["Ember Strength"], glow.inputs[1])
    glow_here = node(tree, "ShaderNodeMath", 0, -200, operation="MULTIPLY")
    L(glow.outputs[0], glow_here.inputs[0])
    L(baked.outputs[0], glow_here.inputs[1])
    emit = node(tree, "ShaderNodeEmission", 200, -100)
    L(kelvin.outputs[0], emit.inputs["Color"])
    L(glow_here.outputs[0], emit.inputs["Strength"])
    add = node(tree, "ShaderNodeAddShader", 400, 200)
    L(charred.outputs[0], add.inputs[0])
    L(emit.outputs[0], add.inputs[1])
    # hole = baked * (1 - alpha) * Burn Through
    gone = node(tree, "ShaderNodeMath", 200, -350, operation="SUBTRACT")
    gone.inputs[0].default_value = 1.0
    L(burn.outputs["Alpha"], gone.inputs[1])
    gone_here = node(tree, "ShaderNodeMath", 400, -350, operation="MULTIPLY")
    L(gone.outputs[0], gone_here.inputs[0])
    L(baked.outputs[0], gone_here.inputs[1])
    hole = node(tree, "ShaderNodeMath", 600, -350, operation="MULTIPLY")
    L(gone_here.outputs[0], hole.inputs[0])
    L(gi.outputs["Burn Through"], hole.inputs[1])
    clear = node(tree, "ShaderNodeBsdfTransparent", 600, -100)
    out = node(tree, "ShaderNodeMixShader", 800, 0)
    L(hole.outputs[0], out.inputs[0])
    L(add.outputs[0], out.inputs[1])
    L(clear.outputs[0], out.inputs[2])
    L(out.outputs[0], go.inputs["Shader"])
    return tree


def _surface_outputs(tree):
    return [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]


def _drive_frame(socket_):
    fcurve = socket_.driver_add("default_value")
    fcurve.driver.type = "SCRIPTED"
    fcurve.driver.expression = "frame"


def is_burn_wrapped(mat) -> bool:
    return mat is not None and mat.node_tree is not None and WRAP_NODE in mat.node_tree.nodes


def add_burn_to_material(mat) -> str:
    """Insert the burn (char, ember glow, burn-through) between a material's surface shader
    and its output(s). Returns "added", "already" or why it could not."""
    if mat is None:
        return "an empty material slot"
    if mat.name.startswith("ThinBurn "):
        return "already"  # the bake's own material burns already
    use_nodes(mat)
    tree = mat.node_tree
    if WRAP_NODE in tree.nodes:
        return "already"
    outputs = [o for o in _surface_outputs(tree) if o.inputs["Surface"].is_linked]
    if not outputs:
        return f"material '{mat.name}' has no shader connected to its Material Output's Surface"
    source = outputs[0].inputs["Surface"].links[0].from_socket
    x, y = outputs[0].location
    wrap = node(tree, "ShaderNodeGroup", x, y - 250, node_tree=wrap_group())
    wrap.name = wrap.label = WRAP_NODE
    tree.links.new(source, wrap.inputs["Shader"])
    for out in outputs:
        if out.inputs["Surface"].links[0].from_socket == source:
            tree.links.new(wrap.outputs["Shader"], out.inputs["Surface"])
    _drive_frame(wrap.inputs["Frame"])
    if hasattr(mat, "surface_render_method"):
        mat.surface_render_method = "DITHERED"  # EEVEE: holes where burnt through
    return "added"


def remove_burn_from_material(mat) -> bool:
    """Undo add_burn_to_material: reconnect the original shader and drop the node."""
    if not is_burn_wrapped(mat):
        return False
    tree = mat.node_tree
    wrap = tree.nodes[WRAP_NODE]
    links = wrap.inputs["Shader"].links
    source = links[0].from_socket if links else None
    targets = [link.to_socket for link in wrap.outputs["Shader"].links]
    if mat.node_tree.animation_data is not None:
        for fc in list(mat.node_tree.animation_data.drivers):
            if fc.data_path.startswith(f'nodes["{WRAP_NODE}"]'):
                mat.node_tree.animation_data.drivers.remove(fc)
    tree.nodes.remove(wrap)
    if source is not None:
        for target in targets:
            tree.links.new(source, target)
    return True


def burn_materials(obj) -> list:
    """add_burn_to_material for each of the object's slots; returns (slot index, result)."""
    return [(i, add_burn_to_material(slot.material)) for i, slot in enumerate(obj.material_slots)]


def sync_burnt(obj) -> None:
    """Apply the sheet's *Burnt* setting (holes or ash) to its bake: the "ThinBurn Burn"
    modifier's Remove Burnt and the Burn Through input of its burn nodes."""
    settings = getattr(obj, "thinburn", None)
    through = getattr(settings, "burnt", "HOLES") != "ASH"
    md = obj.modifiers.get(BURN_MODIFIER)
    if md is not None and md.node_group is not None:
        for item in md.node_group.interface.items_tree:
            if getattr(item, "in_out", "") == "INPUT" and item.name == "Remove Burnt":
                md[item.identifier] = through
    for slot in obj.material_slots:
        mat = slot.material
        if mat is None or mat.node_tree is None:
            continue
        for n in mat.node_tree.nodes:
            if n.bl_idname == "ShaderNodeGroup" and n.node_tree is not None \
                    and n.node_tree.name in (CHAR_GROUP, WRAP_GROUP) and "Burn Through" in n.inputs:
                n.inputs["Burn Through"].default_value = 1.0 if through else 0.0
    obj.update_tag()


# --- the geometry-nodes group after the cache ---------------------------------------------------
def burn_group():
    """Geometry node group "ThinBurn Burn": viewport char colour and removal of burnt faces."""
    tree, fresh = new_group(BURN_GROUP, "GeometryNodeTree")
    if not fresh:
        return tree
    interface_socket(tree, "Geometry", "INPUT", "NodeSocketGeometry")
    interface_socket(tree, "Remove Burnt", "INPUT", "NodeSocketBool", True,
        desc="Delete faces whose vertices have all burnt out (burn-through in the viewport)")
    interface_socket(tree, "Geometry", "OUTPUT", "NodeSocketGeometry")

    gi = node(tree, "NodeGroupInput", -1000, 0)
    go = node(tree, "NodeGroupOutput", 900, 0)
    now = node(tree, "GeometryNodeInputSceneTime", -1000, 300)
    ig = node(tree, "GeometryNodeInputNamedAttribute", -1000, 150, data_type="FLOAT")
    set_input(ig, "Name", ATTR_IGNITE)
    bo = node(tree, "GeometryNodeInputNamedAttribute", -1000, -150, data_type="FLOAT")
    set_input(bo, "Name", ATTR_BURNOUT)
    char = map_range(tree, -750, 300, (now, "Frame"), (ig, "Attribute"), (bo, "Attribute"))
    glow = map_range(tree, -550, 100, (char, "Result"), 0.6, 1.0, interp="SMOOTHSTEP")
    alive = node(tree, "FunctionNodeCompare", -750, -100, data_type="FLOAT", operation="LESS_THAN")
    link(tree, now, "Frame", alive, "A")
    link(tree, bo, "Attribute", alive, "B")
    ember = node(tree, "ShaderNodeMath", -350, 100, operation="MULTIPLY")
    tree.links.new(glow.outputs["Result"], ember.inputs[0])
    tree.links.new(alive.outputs[0], ember.inputs[1])
    dark = map_range(tree, -550, 400, (char, "Result"), 0.0, CHAR_POINT, interp="SMOOTHSTEP")
    charred = node(tree, "ShaderNodeMix", -350, 350, data_type="RGBA")
    link(tree, dark, "Result", charred, "Factor_Float")
    set_input(charred, "A_Color", PAPER)
    set_input(charred, "B_Color", CHAR)
    colour = node(tree, "ShaderNodeMix", -150, 300, data_type="RGBA")
    tree.links.new(ember.outputs[0], socket(colour.inputs, "Factor_Float"))
    link(tree, charred, "Result_Color", colour, "A_Color")
    set_input(colour, "B_Color", EMBER)
    # the burning band (lit, not burnt out) for a Mantaflow flow source: written into the
    # vertex group of that name when the sheet has one (mantaflow.py), else an attribute
    lit = node(tree, "FunctionNodeCompare", -750, -300, data_type="FLOAT", operation="GREATER_EQUAL")
    link(tree, now, "Frame", lit, "A")
    link(tree, ig, "Attribute", lit, "B")
    band = node(tree, "FunctionNodeBooleanMath", -550, -300, operation="AND")
    tree.links.new(lit.outputs[0], band.inputs[0])
    tree.links.new(alive.outputs[0], band.inputs[1])
    burning = node(tree, "GeometryNodeStoreNamedAttribute", -100, -300, data_type="FLOAT", domain="POINT")
    set_input(burning, "Name", ATTR_BURNING)
    link(tree, gi, "Geometry", burning, "Geometry")
    tree.links.new(band.outputs[0], socket(burning.inputs, "Value"))
    store = node(tree, "GeometryNodeStoreNamedAttribute", 100, 0, data_type="FLOAT_COLOR", domain="POINT")
    set_input(store, "Name", ATTR_CHAR)
    link(tree, burning, "Geometry", store, "Geometry")
    link(tree, colour, "Result_Color", store, "Value")
    # A face goes only when all its vertices burnt out: capture the test on points, then read
    # it on faces (a boolean is true on a face when true on all its points).
    burnt = node(tree, "FunctionNodeBooleanMath", -150, -150, operation="NOT")
    tree.links.new(alive.outputs[0], burnt.inputs[0])
    capture = node(tree, "GeometryNodeCaptureAttribute", 300, 0, domain="POINT")
    capture.capture_items.new("BOOLEAN", "Burnt")
    tree.links.new(store.outputs[0], capture.inputs[0])
    tree.links.new(burnt.outputs[0], capture.inputs[1])
    gate = node(tree, "FunctionNodeBooleanMath", 500, -150, operation="AND")
    tree.links.new(capture.outputs[1], gate.inputs[0])
    tree.links.new(gi.outputs["Remove Burnt"], gate.inputs[1])
    delete = node(tree, "GeometryNodeDeleteGeometry", 700, 0, domain="FACE", mode="ONLY_FACE")
    tree.links.new(capture.outputs[0], delete.inputs["Geometry"])
    tree.links.new(gate.outputs[0], delete.inputs["Selection"])
    tree.links.new(delete.outputs[0], go.inputs["Geometry"])
    return tree


# --- applying and freeing a bake ------------------------------------------------------------------
def char_material(obj):
    """A material "ThinBurn <sheet>" whose surface is the "ThinBurn Char" group."""
    mat = bpy.data.materials.new(f"ThinBurn {obj.name}")
    use_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    group = node(tree, "ShaderNodeGroup", 0, 0, node_tree=char_group())
    group.name = CHAR_GROUP
    out = node(tree, "ShaderNodeOutputMaterial", 300, 0)
    tree.links.new(group.outputs["Shader"], out.inputs["Surface"])
    fcurve = group.inputs["Frame"].driver_add("default_value")
    fcurve.driver.type = "SCRIPTED"
    fcurve.driver.expression = "frame"
    if hasattr(mat, "surface_render_method"):
        mat.surface_render_method = "DITHERED"
    return mat


def apply_bake(obj, pc2_path: str, frame_start: float, ignite, burnout, floor=None) -> None:
    """Hook a finished bake onto the sheet: attributes, modifiers, and a material if it has none;
    ash flakes land on ``floor`` (the bake's world height, None: they keep falling)."""
    mesh = obj.data
    cache.write_point_attribute(mesh, ATTR_IGNITE, ignite)
    cache.write_point_attribute(mesh, ATTR_BURNOUT, burnout)
    base = np.tile(np.asarray(PAPER, dtype=np.float32), (len(mesh.vertices), 1))
    cache.write_point_attribute(mesh, ATTR_CHAR, base, "FLOAT_COLOR")
    mesh.color_attributes.active_color = mesh.color_attributes[ATTR_CHAR]
    mesh.color_attributes.render_color_index = mesh.color_attributes.active_color_index

    md = ensure_modifier(obj, CACHE_MODIFIER, "MESH_CACHE", 0)
    md.cache_format = "PC2"
    md.filepath = pc2_path
    md.frame_start = frame_start  # PC2 sample 0 is this frame
    md.frame_scale = 1.0
    md.play_mode = "SCENE"
    md.time_mode = "FRAME"
    md.interpolation = "LINEAR"
    md.deform_mode = "OVERWRITE"
    md.forward_axis, md.up_axis = "POS_Y", "POS_Z"
    burn = ensure_modifier(obj, BURN_MODIFIER, "NODES", 1)
    burn.node_group = burn_group()

    if not any(slot.material for slot in obj.material_slots):
        mat = char_material(obj)
        if obj.material_slots:
            obj.material_slots[0].material = mat
        else:
            obj.data.materials.append(mat)
    else:
        burn_materials(obj)  # the sheet's own materials char, glow and burn through too
    sync_burnt(obj)
    apply_flakes(obj, pc2_path, frame_start, burnout, floor)
    obj.update_tag()
    mesh.update()


# --- what a bake wrote, and whose it is -----------------------------------------------------------
def _made_objects(obj) -> list:
    """The objects a bake of the sheet made, found by the names it gives them now."""
    names = (fire_object_name(obj), light_object_name(obj), ember_object_name(obj),
             flake_object_name(obj), *(lamp_object_name(obj, k) for k in range(LAMPS)))
    return [o for o in map(bpy.data.objects.get, names) if o is not None]


def _same_file(a: str, b: str) -> bool:
    return os.path.normcase(os.path.realpath(a)) == os.path.normcase(os.path.realpath(b))


def owns_cache(settings) -> bool:
    """Whether the open .blend made the sheet's recorded cache files: the file the bake ran in
    (or, if that file is gone, its renamed self). A copy made by Save As does not own them."""
    made_in, here = settings.baked_blend, bpy.data.filepath
    if made_in == here or (made_in and here and _same_file(made_in, here)):
        return True
    return bool(made_in) and not os.path.exists(made_in)


def remove_files(paths, gone) -> None:
    for path in sorted(paths):
        for p in (path, path + ".partial"):
            if os.path.exists(p):
                os.remove(p)
                gone.append("file " + os.path.basename(p))


def _remove_object(ob) -> None:
    mesh = ob.data
    bpy.data.objects.remove(ob)
    if mesh is not None and mesh.users == 0 and isinstance(mesh, bpy.types.Mesh):
        bpy.data.meshes.remove(mesh)
    elif mesh is not None and mesh.users == 0 and isinstance(mesh, bpy.types.Light):
        bpy.data.lights.remove(mesh)


def record_bake(obj) -> list:
    """Store on the sheet what its bake wrote (files as the modifiers have them, the objects it
    made, the .blend it ran in). Objects an earlier bake made and this one did not (after a
    rename, say) go now; the files an earlier bake of this .blend wrote stay on the list, and
    on disk until Free (the saved file may still play them). Returns the objects that went."""
    settings = obj.thinburn
    made = _made_objects(obj)
    written = [md.filepath for o in [obj, *made]
               if (md := o.modifiers.get(CACHE_MODIFIER)) is not None and md.filepath]
    gone = []
    for item in settings.baked_objects:
        if item.object is not None and item.object not in made:
            gone.append("object " + item.object.name)
            _remove_object(item.object)
    if owns_cache(settings):
        written += [item.path for item in settings.baked_files]
    files, known = [], set()
    for f in written:  # the flames and their light share a file
        if bpy.path.abspath(f) not in known:
            known.add(bpy.path.abspath(f))
            files.append(f)
    settings.baked_files.clear()
    for f in files:
        settings.baked_files.add().path = f
    settings.baked_objects.clear()
    for o in made:
        settings.baked_objects.add().object = o
    settings.baked_blend = bpy.data.filepath
    return gone


def free_bake(obj) -> list:
    """Remove what apply_bake added, the objects the bake made and (when this .blend made them)
    its cache files; returns what went, for the report."""
    gone = []
    settings = obj.thinburn
    md = obj.modifiers.get(CACHE_MODIFIER)
    paths = set()
    recorded = len(settings.baked_files) > 0
    if recorded and owns_cache(settings):
        paths |= {bpy.path.abspath(item.path) for item in settings.baked_files}
    elif recorded:
        gone.append(f"kept the cache files: they belong to "
                    f"'{os.path.basename(settings.baked_blend) or 'an unsaved file'}', which this "
                    "file was saved from")
    elif settings.baked_file:  # a bake from before the record: what its modifiers point at
        paths.add(bpy.path.abspath(settings.baked_file))
    if md is not None:
        if md.filepath and not recorded:
            paths.add(bpy.path.abspath(md.filepath))
        obj.modifiers.remove(md)
        gone.append("modifier " + CACHE_MODIFIER)
    md = obj.modifiers.get(BURN_MODIFIER)
    if md is not None:
        obj.modifiers.remove(md)
        gone.append("modifier " + BURN_MODIFIER)
    if cache.remove_attributes(obj.data, (ATTR_IGNITE, ATTR_BURNOUT, ATTR_CHAR)):
        gone.append("attributes")
    for slot in obj.material_slots:
        if remove_burn_from_material(slot.material) and "burn from materials" not in gone:
            gone.append("burn from materials")
    for i, slot in enumerate(obj.material_slots):
        mat = slot.material
        if mat is not None and mat.name == f"ThinBurn {obj.name}":
            obj.data.materials.pop(index=i)
            if mat.users == 0:
                bpy.data.materials.remove(mat)
            gone.append("material")
            break
    made = {o.name: o for o in _made_objects(obj)}
    made.update({i.object.name: i.object for i in settings.baked_objects if i.object is not None})
    for fire in made.values():
        fmd = fire.modifiers.get(CACHE_MODIFIER)
        if fmd is not None and fmd.filepath and not recorded:
            paths.add(bpy.path.abspath(fmd.filepath))
        _remove_object(fire)
        if "fire particles" not in gone:
            gone.append("fire particles")
    gone += mantaflow.free(obj, delete_files=not recorded or owns_cache(settings))
    remove_files(paths, gone)
    settings.baked_file = ""
    settings.baked_shape = ""
    settings.baked_strain = 0.0
    settings.baked_files.clear()
    settings.baked_objects.clear()
    settings.baked_blend = ""
    obj.update_tag()
    return gone
