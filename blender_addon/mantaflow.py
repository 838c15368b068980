"""Mantaflow fire from a ThinBurn bake in one click ("Add Mantaflow Fire").

The baked sheet becomes a Fluid *Flow* (Fire) that emits only where its ``thinburn_burning``
vertex group is 1 (the "ThinBurn Burn" modifier writes the burning band into it every frame),
and a Fluid *Domain* box is made around everything the sheet sweeps over the bake, with room
above for the flames. Its cache folder sits beside the ThinBurn cache; *Free* removes the
flow, the domain and that folder.

bpy-as-a-module (bpy from PyPI) imports Blender's ``manta`` module when ``bpy`` loads, before
Mantaflow's registry has linked its classes to their base classes, so every grid lacks the
methods it inherits (``'LevelsetGrid' object has no attribute 'setConst'``) and the first
solver aborts the process when it is freed. ``prepare_solver`` works around it: one
throwaway domain makes Mantaflow set up its registry, then the module's init function (the
library's exported ``PyInit_manta_main``) is run again, which rebuilds the classes in place
with their inherited methods. Blender itself imports ``manta`` only after that set-up, so
there nothing is done.
"""
from __future__ import annotations

import ctypes
import glob
import os
import shutil
import sys
import tempfile

import numpy as np

import bpy

from . import cache
from .fire import fire_object_name

FLOW_MODIFIER = "ThinBurn Flow"
DOMAIN_MODIFIER = "Fluid"
GROUP = "thinburn_burning"  # the burning band; materials.ATTR_BURNING writes it
DOMAIN_MATERIAL = "ThinBurn Smoke"
MARGIN = 0.25          # of the sheet's largest horizontal size, on each side of its sweep
ROOM_ABOVE = 1.0       # of the sheet's largest horizontal size, above its sweep, for the flames
MIN_ROOM = 0.05        # m, at least this much room on every side
SURFACE_EMISSION = 1.5  # voxels: a planar sheet emits this far from its surface
SMOKE_DENSITY = 2.0     # the smoke's density scale
SMOKE_FLAME_K = 1600.0  # K: the flames' blackbody colour (orange)
SMOKE_FLAME_STRENGTH = 20.0  # volume emission per unit of Mantaflow's flame


def domain_object_name(obj) -> str:
    return f"ThinBurn Domain {obj.name}"


def cache_folder(obj) -> str:
    """Beside the sheet's PC2: ``<cache>/<name>_mantaflow``."""
    return obj.thinburn.baked_file[:-len(".pc2")] + "_mantaflow"


# --- bpy-as-a-module's Mantaflow ----------------------------------------------------------------
def _broken_manta():
    """The ``manta`` module when its classes lack their inherited methods, else None. In
    Blender itself ``manta`` is not imported until a solver exists: it is never imported here."""
    manta = sys.modules.get("manta")
    grid = getattr(manta, "LevelsetGrid", None)
    if grid is None or hasattr(grid, "setConst"):
        return None
    return manta


class MantaflowError(RuntimeError):
    """Mantaflow cannot bake in this Blender; the text says what to do instead."""


def _bpy_library():
    """The library that holds ``PyInit_manta_main``: bpy's own (``bpy/__init__.so`` or
    ``.pyd``), else the running executable when it exports it."""
    local = os.path.dirname(os.path.normpath(bpy.utils.resource_path("LOCAL")))
    paths = [p for p in sorted(glob.glob(os.path.join(local, "__init__*"))) if not p.endswith(".py")]
    for path in paths + [None]:
        try:
            lib = ctypes.PyDLL(path)
        except OSError:
            continue
        if hasattr(lib, "PyInit_manta_main"):
            return lib
    raise MantaflowError(
        "Mantaflow's Python module is incomplete in this Blender ('LevelsetGrid' has no "
        "'setConst') and ThinBurn cannot mend it here: bake the smoke domain in Blender "
        "itself (open the .blend and use the domain's Physics > Cache > Bake Data)")


def prepare_solver(scene) -> bool:
    """Make Mantaflow usable in bpy-as-a-module (see the module docstring). True when it had
    to be mended; False when nothing was wrong (Blender itself, or already mended)."""
    manta = _broken_manta()
    if manta is None:
        return False
    lib = _bpy_library()
    mesh = bpy.data.meshes.new("ThinBurn Mantaflow Setup")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)], [],
                     [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)])
    probe = bpy.data.objects.new(mesh.name, mesh)
    scene.collection.objects.link(probe)
    md = probe.modifiers.new(DOMAIN_MODIFIER, "FLUID")
    md.fluid_type = "DOMAIN"
    md.domain_settings.resolution_max = 6
    md.domain_settings.cache_directory = os.path.join(tempfile.gettempdir(), "thinburn_manta_setup")
    try:
        bpy.context.evaluated_depsgraph_get().update()  # the solver's creation sets up the registry
    finally:
        bpy.data.objects.remove(probe)
        bpy.data.meshes.remove(mesh)
    lib.PyInit_manta_main.restype = ctypes.py_object
    lib.PyInit_manta_main()  # rebuilds the classes in place, now with their base classes' methods
    if not hasattr(manta.LevelsetGrid, "setConst"):
        raise MantaflowError("Mantaflow's Python module is still incomplete after ThinBurn's "
                             "mend: bake the smoke domain in Blender itself (the domain's "
                             "Physics > Cache > Bake Data)")
    return True


# --- the flow and the domain ----------------------------------------------------------------------
def sweep_bounds(obj):
    """World (low, high) corners of everything the baked sheet covers over its bake."""
    _, local = cache.read_pc2(bpy.path.abspath(obj.thinburn.baked_file))
    m = np.array(obj.matrix_world, dtype=np.float64)
    world = local.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3]
    return world.min(axis=0), world.max(axis=0)


def domain_box(low, high):
    """The domain's corners: the sweep, MARGIN of its size around it, ROOM_ABOVE above."""
    size = float(max(high[0] - low[0], high[1] - low[1], MIN_ROOM))
    side = max(MARGIN * size, MIN_ROOM)
    up = max(ROOM_ABOVE * size, MIN_ROOM)
    lo = np.array([low[0] - side, low[1] - side, low[2] - side])
    hi = np.array([high[0] + side, high[1] + side, high[2] + up])
    return lo, hi


def _burning_group(obj):
    """The vertex group the burn modifier fills; every vertex in it (at 0) so that the
    geometry nodes have weights to set."""
    group = obj.vertex_groups.get(GROUP) or obj.vertex_groups.new(name=GROUP)
    group.add(range(len(obj.data.vertices)), 0.0, "REPLACE")
    return group


def add_flow(obj):
    """The sheet's Fluid flow (Fire), emitting from its burning band; last in the stack, so
    after "ThinBurn Burn"."""
    _burning_group(obj)
    md = obj.modifiers.get(FLOW_MODIFIER) or obj.modifiers.new(FLOW_MODIFIER, "FLUID")
    md.fluid_type = "FLOW"
    flow = md.flow_settings
    flow.flow_type = "FIRE"
    flow.flow_behavior = "INFLOW"
    flow.flow_source = "MESH"
    flow.use_plane_init = True  # a sheet is open: emit from its surface, not its inside
    flow.surface_distance = SURFACE_EMISSION
    flow.density_vertex_group = GROUP
    return md


def _box_mesh(name, lo, hi):
    xs, ys, zs = (lo[0], hi[0]), (lo[1], hi[1]), (lo[2], hi[2])
    verts = [(x, y, z) for x in xs for y in ys for z in zs]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    return mesh


def smoke_material():
    """"ThinBurn Smoke": Principled Volume, dark smoke from Mantaflow's ``density`` and flames
    that glow a blackbody colour from its ``flame`` grid (SMOKE_FLAME_K, strength
    SMOKE_FLAME_STRENGTH per unit flame)."""
    mat = bpy.data.materials.get(DOMAIN_MATERIAL)
    if mat is not None:
        return mat
    mat = bpy.data.materials.new(DOMAIN_MATERIAL)
    mat.use_nodes = True
    tree = mat.node_tree
    tree.nodes.clear()
    vol = tree.nodes.new("ShaderNodeVolumePrincipled")
    vol.inputs["Color"].default_value = (0.05, 0.05, 0.05, 1.0)
    vol.inputs["Density"].default_value = SMOKE_DENSITY
    flame = tree.nodes.new("ShaderNodeAttribute")
    flame.attribute_name = "flame"
    flame.location = (-600, -300)
    strength = tree.nodes.new("ShaderNodeMath")
    strength.operation = "MULTIPLY"
    strength.inputs[1].default_value = SMOKE_FLAME_STRENGTH
    strength.location = (-350, -300)
    tree.links.new(flame.outputs["Fac"], strength.inputs[0])
    tree.links.new(strength.outputs[0], vol.inputs["Emission Strength"])
    body = tree.nodes.new("ShaderNodeBlackbody")
    body.inputs["Temperature"].default_value = SMOKE_FLAME_K
    body.location = (-350, -100)
    tree.links.new(body.outputs[0], vol.inputs["Emission Color"])
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    out.location = (300, 0)
    tree.links.new(vol.outputs[0], out.inputs["Volume"])
    return mat


def add_domain(obj, scene, resolution: int):
    """The domain box around the sheet's sweep (an earlier one of this sheet is replaced)."""
    remove_domain(obj)
    lo, hi = domain_box(*sweep_bounds(obj))
    name = domain_object_name(obj)
    domain = bpy.data.objects.new(name, _box_mesh(name, lo, hi))
    for coll in obj.users_collection:
        coll.objects.link(domain)
    domain.data.materials.append(smoke_material())
    domain.display_type = "WIRE"
    md = domain.modifiers.new(DOMAIN_MODIFIER, "FLUID")
    md.fluid_type = "DOMAIN"
    ds = md.domain_settings
    ds.domain_type = "GAS"
    ds.resolution_max = resolution
    ds.cache_type = "MODULAR"  # bake once, then scrub; Free deletes the folder
    ds.cache_data_format = "OPENVDB"
    ds.cache_directory = cache_folder(obj)
    settings = obj.thinburn
    ds.cache_frame_start = settings.frame_start
    ds.cache_frame_end = settings.frame_end
    settings.mantaflow_domain = domain
    return domain


def hide_thinburn_flames(obj, hide: bool) -> None:
    """The add-on's own flame volume, out of the way of Mantaflow's (its light and embers stay)."""
    fire = bpy.data.objects.get(fire_object_name(obj))
    if fire is not None:
        fire.hide_render = hide
        fire.hide_viewport = hide


def bake(domain, scene) -> None:
    """Bake the domain's data (``bpy.ops.fluid.bake_data``) over its cache frames."""
    prepare_solver(scene)
    with bpy.context.temp_override(scene=scene, object=domain, active_object=domain):
        result = bpy.ops.fluid.bake_data()
    if "FINISHED" not in result:
        raise MantaflowError(f"Mantaflow's bake of '{domain.name}' did not finish ({result}): "
                             "see the console for the solver's message")


def remove_domain(obj, delete_files: bool = True) -> list:
    """Remove the sheet's Mantaflow domain and (``delete_files``) its cache folder."""
    gone = []
    settings = obj.thinburn
    domain = settings.mantaflow_domain or bpy.data.objects.get(domain_object_name(obj))
    if domain is not None:
        md = domain.modifiers.get(DOMAIN_MODIFIER)
        folder = bpy.path.abspath(md.domain_settings.cache_directory) if md is not None else ""
        mesh = domain.data
        bpy.data.objects.remove(domain)
        if mesh is not None and mesh.users == 0:
            bpy.data.meshes.remove(mesh)
        gone.append("Mantaflow domain")
        if delete_files and folder and os.path.isdir(folder):
            shutil.rmtree(folder)
            gone.append("folder " + os.path.basename(folder.rstrip(os.sep)))
    settings.mantaflow_domain = None
    return gone


def free(obj, delete_files: bool) -> list:
    """Everything add_mantaflow_fire made on and for the sheet; its cache folder only with
    ``delete_files`` (Free's rule: only the .blend that baked deletes the cache)."""
    gone = remove_domain(obj, delete_files)
    md = obj.modifiers.get(FLOW_MODIFIER)
    if md is not None:
        obj.modifiers.remove(md)
        gone.append("modifier " + FLOW_MODIFIER)
    group = obj.vertex_groups.get(GROUP)
    if group is not None:
        obj.vertex_groups.remove(group)
    hide_thinburn_flames(obj, False)
    return gone
