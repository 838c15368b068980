"""Fire particles of a bake (when the core has ``Simulation.particles``).

They become an object "ThinBurn Fire <sheet>" whose Mesh Cache plays ``<name>_fire.pc2`` and
whose geometry nodes ("ThinBurn Fire") turn the cached points into a point cloud with a
``temperature`` attribute and the emission material "ThinBurn Fire". Renders without the
add-on.
"""
from __future__ import annotations

import numpy as np

import bpy

from . import cache
from .nodes import ensure_modifier, interface_socket, new_group, node, set_input, socket, use_nodes

CACHE_MODIFIER = "ThinBurn Cache"
FIRE_GROUP = "ThinBurn Fire"


def fire_object_name(obj) -> str:
    return f"ThinBurn Fire {obj.name}"


def fire_group():
    """Geometry node group "ThinBurn Fire": the first Count points of the cached mesh become a
    point cloud; point Count + i carries (temperature, alive, 0) of particle i."""
    tree, fresh = new_group(FIRE_GROUP, "GeometryNodeTree")
    if not fresh:
        return tree
    interface_socket(tree, "Geometry", "INPUT", "NodeSocketGeometry")
    interface_socket(tree, "Count", "INPUT", "NodeSocketInt", 1, 0, desc="Particle slots in the cache")
    interface_socket(tree, "Radius", "INPUT", "NodeSocketFloat", 0.004, 0.0, desc="Radius of a fire particle, m")
    interface_socket(tree, "Min Temperature", "INPUT", "NodeSocketFloat", 150.0, 0.0,
                     desc="Particles cooler than this (K above ambient) are left out: they no "
                          "longer glow, and fewer see-through particles render faster")
    interface_socket(tree, "Material", "INPUT", "NodeSocketMaterial")
    interface_socket(tree, "Geometry", "OUTPUT", "NodeSocketGeometry")
    gi = node(tree, "NodeGroupInput", -900, 0)
    go = node(tree, "NodeGroupOutput", 900, 0)
    index = node(tree, "GeometryNodeInputIndex", -900, -300)
    pos = node(tree, "GeometryNodeInputPosition", -900, -450)
    other = node(tree, "ShaderNodeMath", -650, -300, operation="ADD")
    tree.links.new(index.outputs[0], other.inputs[0])
    tree.links.new(gi.outputs["Count"], other.inputs[1])
    sample = node(tree, "GeometryNodeSampleIndex", -450, -200, data_type="FLOAT_VECTOR", domain="POINT")
    tree.links.new(gi.outputs["Geometry"], sample.inputs["Geometry"])
    tree.links.new(pos.outputs[0], socket(sample.inputs, "Value"))
    tree.links.new(other.outputs[0], sample.inputs["Index"])
    split = node(tree, "ShaderNodeSeparateXYZ", -250, -200)
    tree.links.new(socket(sample.outputs, "Value"), split.inputs[0])
    first = node(tree, "FunctionNodeCompare", -450, 100, data_type="INT", operation="LESS_THAN")
    tree.links.new(index.outputs[0], socket(first.inputs, "A_INT"))
    tree.links.new(gi.outputs["Count"], socket(first.inputs, "B_INT"))
    live = node(tree, "FunctionNodeCompare", -50, -200, data_type="FLOAT", operation="GREATER_THAN")
    tree.links.new(split.outputs["Y"], live.inputs[0])
    set_input(live, "B", 0.5)
    hot = node(tree, "FunctionNodeCompare", -50, -400, data_type="FLOAT", operation="GREATER_EQUAL")
    tree.links.new(split.outputs["X"], hot.inputs[0])
    tree.links.new(gi.outputs["Min Temperature"], hot.inputs[1])
    glowing = node(tree, "FunctionNodeBooleanMath", 150, -300, operation="AND")
    tree.links.new(live.outputs[0], glowing.inputs[0])
    tree.links.new(hot.outputs[0], glowing.inputs[1])
    keep = node(tree, "FunctionNodeBooleanMath", 150, 0, operation="AND")
    tree.links.new(first.outputs[0], keep.inputs[0])
    tree.links.new(glowing.outputs[0], keep.inputs[1])
    store = node(tree, "GeometryNodeStoreNamedAttribute", 150, 250, data_type="FLOAT", domain="POINT")
    set_input(store, "Name", "temperature")
    tree.links.new(gi.outputs["Geometry"], store.inputs["Geometry"])
    tree.links.new(split.outputs["X"], socket(store.inputs, "Value"))
    points = node(tree, "GeometryNodeMeshToPoints", 400, 100)
    tree.links.new(store.outputs[0], points.inputs["Mesh"])
    tree.links.new(keep.outputs[0], points.inputs["Selection"])
    tree.links.new(gi.outputs["Radius"], points.inputs["Radius"])
    setmat = node(tree, "GeometryNodeSetMaterial", 650, 100)
    tree.links.new(points.outputs[0], setmat.inputs["Geometry"])
    tree.links.new(gi.outputs["Material"], setmat.inputs["Material"])
    tree.links.new(setmat.outputs[0], go.inputs["Geometry"])
    return tree


AMBIENT_K = 293.15      # the core's particle temperatures are kelvin above ambient
FLAME_K = 900.0         # a particle's temperature at birth (the core's temperature0)
FLAME_STRENGTH = 20.0   # emission strength of a particle at FLAME_K


def fire_material():
    """Glowing, see-through flame particles: a blackbody emission of the particle's absolute
    temperature, brightness ~ (T / FLAME_K)^4 (Stefan-Boltzmann), added to a transparent
    BSDF so that cooled particles fade out instead of turning into black beads."""
    mat = bpy.data.materials.get(FIRE_GROUP)
    if mat is not None:
        return mat
    mat = bpy.data.materials.new(FIRE_GROUP)
    use_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    temp = node(tree, "ShaderNodeAttribute", -800, 0, attribute_type="GEOMETRY", attribute_name="temperature")
    absolute = node(tree, "ShaderNodeMath", -550, 150, operation="ADD")
    tree.links.new(temp.outputs["Fac"], absolute.inputs[0])
    absolute.inputs[1].default_value = AMBIENT_K
    body = node(tree, "ShaderNodeBlackbody", -350, 150)
    tree.links.new(absolute.outputs[0], body.inputs["Temperature"])
    ratio = node(tree, "ShaderNodeMath", -550, -100, operation="DIVIDE")
    tree.links.new(temp.outputs["Fac"], ratio.inputs[0])
    ratio.inputs[1].default_value = FLAME_K
    power = node(tree, "ShaderNodeMath", -350, -100, operation="POWER")
    tree.links.new(ratio.outputs[0], power.inputs[0])
    power.inputs[1].default_value = 4.0
    scale = node(tree, "ShaderNodeMath", -150, -100, operation="MULTIPLY")
    tree.links.new(power.outputs[0], scale.inputs[0])
    scale.inputs[1].default_value = FLAME_STRENGTH
    emit = node(tree, "ShaderNodeEmission", 50, 50)
    tree.links.new(body.outputs[0], emit.inputs["Color"])
    tree.links.new(scale.outputs[0], emit.inputs["Strength"])
    clear = node(tree, "ShaderNodeBsdfTransparent", 50, -150)
    add = node(tree, "ShaderNodeAddShader", 250, 0)
    tree.links.new(clear.outputs[0], add.inputs[0])
    tree.links.new(emit.outputs[0], add.inputs[1])
    out = node(tree, "ShaderNodeOutputMaterial", 450, 0)
    tree.links.new(add.outputs[0], out.inputs["Surface"])
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
        fire.visible_shadow = False  # flames light the scene; they cast no shadow
        for coll in obj.users_collection:
            coll.objects.link(fire)
    md = ensure_modifier(fire, CACHE_MODIFIER, "MESH_CACHE", 0)
    md.cache_format = "PC2"
    md.filepath = sheet_pc2_path[:-len(".pc2")] + "_fire.pc2"
    md.frame_start = frame_start
    md.interpolation = "NONE"  # slots are reused by different particles from frame to frame
    gn = ensure_modifier(fire, FIRE_GROUP, "NODES", 1)
    gn.node_group = fire_group()
    ident = {s.name: s.identifier for s in gn.node_group.interface.items_tree
             if getattr(s, "in_out", "") == "INPUT"}
    gn[ident["Count"]] = count
    gn[ident["Material"]] = fire_material()
    fire.update_tag()
