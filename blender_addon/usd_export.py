"""A baked sheet to USD: its PC2 cache, time attributes and fire particles (thinburn.usd).

``export_object(obj, path)`` or ``bpy.ops.thinburn.export_usd(filepath=...)`` on the active
sheet. Time codes are the scene's frames (timeCodesPerSecond = the scene's fps); the points
are the cache's object-space samples under the sheet's world matrix; ``char`` per frame is
the add-on's own burn fraction (the "ThinBurn Char" group's Char: (frame − ignite) /
(burnout − ignite), clamped to [0, 1]); ``ignitionTime`` / ``burnoutTime`` are the point
attributes, in frames (1e9 = never).
"""
from __future__ import annotations

import os

import bpy
import numpy as np
from bpy.props import StringProperty

from . import cache
from .fire import CACHE_MODIFIER as FIRE_CACHE_MODIFIER
from .fire import fire_object_name
from .file_export import ExportOperator, registrar
from .inputs import BakeError, transform_animation
from .materials import ATTR_BURNOUT, ATTR_IGNITE


def _attribute(mesh, name):
    attr = mesh.attributes.get(name)
    if attr is None:
        return None
    values = np.empty(len(attr.data), dtype=np.float32)
    attr.data.foreach_get("value", values)
    return values


def burn_fraction(frames, ignite, burnout) -> np.ndarray:
    """(F, n) char per frame from the time attributes, as the Char shader group computes it."""
    f = np.asarray(frames, dtype=np.float64)[:, None]
    ign = np.asarray(ignite, dtype=np.float64)[None, :]
    out = np.asarray(burnout, dtype=np.float64)[None, :]
    span = np.maximum(out - ign, 1e-9)
    c = np.clip((f - ign) / span, 0.0, 1.0)
    return np.where(ign >= cache.NEVER_FRAME, 0.0, c).astype(np.float32)


def fire_particles(pc2_path):
    """Per frame (positions (k, 3), temperatures (k,)) from a fire PC2 (fire.particle_cache_rows)."""
    _, rows = cache.read_pc2(pc2_path)
    count = rows.shape[1] // 2
    out = []
    for sample in rows:
        alive = sample[count:, 1] > 0.5
        out.append((np.ascontiguousarray(sample[:count][alive]),
                    np.ascontiguousarray(sample[count:, 0][alive])))
    return out


def export_object(obj, path, scene=None) -> str:
    """Write ``obj``'s bake to ``path`` (.usda / .usdc / .usd); BakeError if it has none."""
    from thinburn.usd import write_usd

    scene = scene or bpy.context.scene
    if obj is None or obj.type != "MESH":
        raise BakeError("USD export needs a baked ThinBurn mesh")
    if not obj.thinburn.baked_file:
        raise BakeError(f"'{obj.name}' has no ThinBurn bake to export: bake it first")
    pc2 = bpy.path.abspath(obj.thinburn.baked_file)
    if not os.path.exists(pc2):
        raise BakeError(f"the cache file '{pc2}' of '{obj.name}' is missing: bake again")
    head, positions = cache.read_pc2(pc2)
    mesh = obj.data
    if head["points"] != len(mesh.vertices):
        raise BakeError(f"the cache '{pc2}' has {head['points']} points but '{obj.name}' has "
                        f"{len(mesh.vertices)} vertices: bake again")
    frames = head["start_frame"] + head["sample_rate"] * np.arange(head["samples"])
    counts = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("loop_total", counts)
    indices = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", indices)
    ignite = _attribute(mesh, ATTR_IGNITE)
    burnout = _attribute(mesh, ATTR_BURNOUT)
    char = None if ignite is None or burnout is None else burn_fraction(frames, ignite, burnout)
    particles = None
    fire = bpy.data.objects.get(fire_object_name(obj))
    if fire is not None and fire.modifiers.get(FIRE_CACHE_MODIFIER) is not None:
        fire_pc2 = bpy.path.abspath(fire.modifiers[FIRE_CACHE_MODIFIER].filepath)
        if os.path.exists(fire_pc2):
            particles = fire_particles(fire_pc2)
            if len(particles) != len(frames):
                particles = None  # a stale fire cache: leave it out rather than misalign
    fps = scene.render.fps / scene.render.fps_base
    return write_usd(path, (counts, indices), frames, positions, fps, char=char, ignition=ignite,
                     burnout=burnout, particles=particles, name=obj.name,
                     transform=world_matrices(obj, scene, frames))


def world_matrices(obj, scene, frames):
    """The sheet's world matrix (4, 4), or one per cached frame (F, 4, 4) when its transform
    is animated: the cache is in object space, and Blender places it with the matrix of each
    frame (the bake follows a moving sheet, thinburn.bake_frame)."""
    if not transform_animation(obj):
        return np.array(obj.matrix_world, dtype=np.float64)
    restore = scene.frame_current
    out = []
    try:
        for f in frames:
            frame = int(np.floor(f))
            scene.frame_set(frame, subframe=float(f - frame))
            out.append(np.array(obj.matrix_world, dtype=np.float64))
    finally:
        scene.frame_set(restore)
    return np.array(out)


class THINBURN_OT_export_usd(ExportOperator, bpy.types.Operator):
    """Export the active sheet's ThinBurn bake (motion, char, times, fire) to a USD file"""

    bl_idname = "thinburn.export_usd"
    bl_label = "Export ThinBurn Bake to USD"
    bl_options = {"REGISTER"}

    filepath: StringProperty(name="File", subtype="FILE_PATH", default="//thinburn.usda",
                             description="The .usda, .usdc or .usd file to write")

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return obj is not None and obj.type == "MESH" and bool(obj.thinburn.baked_file)

    menu_label = "ThinBurn Bake (.usda, .usdc)"
    errors = (BakeError, ValueError, ImportError, OSError)

    def write(self, context, path):
        export_object(context.active_object, path, context.scene)


register, unregister = registrar(THINBURN_OT_export_usd)
