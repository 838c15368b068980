"""A sheet's bake inputs as a thinburn scene file (thinburn.scenefile), for wedges and farms.

``write_scene(obj, path)`` or ``bpy.ops.thinburn.export_scene(filepath=...)`` on the active
sheet samples the scene at every frame of the bake's range, as the bake does, and writes the
world-space mesh at the first frame, the material, the settings, the wind per frame and the
igniters as timed ignitions (a lit igniter's position at each frame, and along its path
between frames, the same points the bake lights; repeated ones are kept once, earliest).
Keyframed motion parameters are written with their first frame's values.
``python -m thinburn wedge --scene FILE --param ...`` then bakes it outside Blender.
"""
from __future__ import annotations

import bpy
import numpy as np
from bpy.props import StringProperty

from . import inputs, properties
from .file_export import ExportOperator, registrar
from .inputs import BakeError
from .job import core_supports
from .worker import path_ignitions


def scene_spec(obj, context=None):
    """A thinburn.scenefile.SceneSpec of the sheet's bake inputs."""
    from thinburn.scenefile import SceneSpec

    context = context or bpy.context
    scene = context.scene
    if obj is None or obj.type != "MESH":
        raise BakeError("scene export needs a ThinBurn mesh")
    settings = obj.thinburn
    if settings.frame_end <= settings.frame_start:
        raise BakeError(f"the frame range {settings.frame_start}–{settings.frame_end} is empty")
    frames = list(range(settings.frame_start, settings.frame_end + 1))
    fps = scene.render.fps / scene.render.fps_base
    dt = 1.0 / fps
    igniters = inputs.igniter_objects(obj, settings)
    winds = inputs.wind_objects(context.view_layer)
    restore = scene.frame_current
    try:
        scene.frame_set(frames[0])
        world, tris, _ = inputs.sheet_geometry(obj)
        floor = inputs.floor_height(scene, settings)
        pinned = (np.flatnonzero(inputs.pin_mask(obj, settings.pin_group)).tolist()
                  if settings.pin_group else None)
        shell = bool(settings.crumple and core_supports("shell"))
        params = {key: float(getattr(settings, key)) for key in properties.MODEL_PARAMS}
        if shell:
            params.update(inputs.dynamics(scene, settings))
        spacing = 0.5 * inputs.cell_spacing(world, tris, settings.cells)
        samples = [inputs.sample_frame(scene, f, obj.name, igniters, winds) for f in frames]
        centre = world.mean(axis=0)  # a scene file has one wind per frame: the fields' here
    finally:
        scene.frame_set(restore)
    ignitions, seen = [], set()
    for k, here in enumerate(samples):
        there = samples[k + 1] if k + 1 < len(samples) else None
        for i, start in enumerate(here.igniters):
            end = None if there is None else there.igniters[i]
            for point, t, radius in path_ignitions(start, end, k * dt, dt,
                                                   max(spacing, 0.5 * start[2])):
                key = (tuple(np.round(point, 9)), round(float(radius), 9))
                if key not in seen:
                    seen.add(key)
                    ignitions.append({"point": [float(x) for x in point], "time": float(t),
                                      "radius": float(radius)})
    mat = properties.build_material(settings).as_dict()
    mat.pop("name", None)
    return SceneSpec(world, tris, material={"preset": settings.material, **mat},
                     igniters=ignitions, name=obj.name, cells=int(settings.cells), fps=float(fps),
                     frames=len(frames), seed=int(settings.seed), front=settings.front,
                     lattice=(int(settings.lattice) or None) if shell else None, floor=floor,
                     pinned=pinned, integrator=settings.integrator, shell=shell,
                     wind=[s.wind_at(centre)[0].tolist() for s in samples], params=params)


def write_scene(obj, path, context=None) -> str:
    """Write the sheet's scene file (.json or .npz); returns the path."""
    from thinburn.scenefile import save_scene

    return save_scene(scene_spec(obj, context), path)


class THINBURN_OT_export_scene(ExportOperator, bpy.types.Operator):
    """Write the active sheet's bake inputs to a thinburn scene file, for wedges and farms"""

    bl_idname = "thinburn.export_scene"
    bl_label = "Export ThinBurn Scene"
    bl_options = {"REGISTER"}

    filepath: StringProperty(name="File", subtype="FILE_PATH", default="//thinburn_scene.json",
                             description="The scene file to write (.json or .npz)")

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return obj is not None and obj.type == "MESH"

    menu_label = "ThinBurn Scene (.json, .npz)"
    errors = (BakeError, ValueError, OSError)

    def write(self, context, path):
        write_scene(context.active_object, path, context)


register, unregister = registrar(THINBURN_OT_export_scene)
