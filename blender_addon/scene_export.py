"""A sheet's bake inputs as a thinburn scene file (thinburn.scenefile), for wedges and farms.

``write_scene(obj, path)`` or ``bpy.ops.thinburn.export_scene(filepath=...)`` on the active
sheet samples the scene at every frame of the bake's range, as the bake does (job.BakeJob),
and writes what the core is given: the world-space mesh at the first frame (lifted onto its
Floor object as the bake lifts it), the material, the settings (Heat Ignites, Burn Duration),
the painted maps, and per frame each lit igniter's ignitions (an Empty's position and its path
to the next frame, a mesh igniter's surface points, the Flames), the collision objects' poses
and friction, the force fields (blown as the bake blows them), the keyframed motion parameters
and gravity. A sheet whose transform is animated is written in the bake frame
(thinburn.bake_frame), with each frame's map to the world. What a scene file cannot hold is
said, one ``ExportWarning`` per setting (the operator reports them): the other sheets of a Heat
Ignites group, a collision object that changes shape. ``python -m thinburn wedge --scene FILE
--param ...`` then bakes it outside Blender.
"""
from __future__ import annotations

import dataclasses
import warnings

import bpy
import numpy as np
from bpy.props import StringProperty

from thinburn import bake_frame as moving

from . import inputs, job, properties
from .file_export import ExportOperator, registrar
from .inputs import BakeError


class ExportWarning(UserWarning):
    """A bake input the scene file cannot hold: the text names the setting."""


def _maps(obj, settings) -> tuple:
    """({map name: (n,) values}, ignite frame index or None) as the bake reads them."""
    maps = {}
    for key in ("speed_map", "fuel_map", "ignite_map"):
        values = inputs.vertex_map(obj, settings, key)
        if values is not None:
            maps[key] = values
    return maps, (job.ignite_frame_index(settings) if "ignite_map" in maps else None)


def _base_spec(obj, context, frames: list, fps: float, shell: bool):
    """The SceneSpec of what the bake reads once, at its first frame (the scene is there)."""
    from thinburn.scenefile import SceneSpec

    settings = obj.thinburn
    world, tris, matrix = inputs.sheet_geometry(obj)
    floor = inputs.floor_height(context.scene, settings)
    job.check_floor(obj, world, floor, settings)
    pinned = (np.flatnonzero(inputs.pin_mask(obj, settings.pin_group)).tolist()
              if settings.pin_group else None)
    params = {key: float(getattr(settings, key)) for key in properties.MODEL_PARAMS}
    if shell:
        params.update(inputs.dynamics(context.scene, settings))
    maps, ignite_frame = _maps(obj, settings)
    mat = properties.build_material(settings).as_dict()
    mat.pop("name", None)
    spec = SceneSpec(world, tris, material={"preset": settings.material, **mat}, name=obj.name,
                     cells=int(settings.cells), fps=float(fps), frames=len(frames),
                     seed=int(settings.seed), front=settings.front,
                     lattice=(int(settings.lattice) or None) if shell else None, floor=floor,
                     pinned=pinned, integrator=settings.integrator, shell=shell, params=params,
                     heat_ignites=bool(settings.heat_ignites and shell),
                     finish_within=float(settings.burn_duration) if settings.burn_duration > 0 else None,
                     ignite_frame=ignite_frame, maps={k: v.tolist() for k, v in maps.items()})
    return spec, matrix


def _core_spacing(spec, estimate: float) -> float:
    """Half the core's cell spacing, as the bake samples igniter paths and mesh igniters once
    the core has said it (job.BakeJob waits for it): the same Simulation, built here."""
    from thinburn.wedge import simulation_for

    sim = simulation_for(spec, {})[0]
    spacing = float(getattr(sim, "cell_spacing", 0.0))
    return 0.5 * spacing if spacing > 0 else estimate


def _colliders(context, obj, shell: bool) -> list:
    """The collision objects the bake uses (job.BakeJob: the Floor Object's and open meshes'
    Collision left out), warning for those it leaves out."""
    if not shell:
        return []
    settings = obj.thinburn
    floor = settings.floor_object if settings.floor_mode == "OBJECT" else None
    depsgraph = context.evaluated_depsgraph_get()
    kept = []
    for name in inputs.collision_objects(context.view_layer, obj.name):
        if floor is not None and name == floor.name:
            continue  # the sheet rests on the Floor: the bake uses that alone
        if inputs.closed_mesh(inputs.collider_sample(bpy.data.objects[name], depsgraph)["faces"]):
            kept.append(name)
        else:
            warnings.warn(f"Collision '{name}' is not a closed mesh: the bake ignores it, and so "
                          "does the scene file", ExportWarning, stacklevel=3)
    return kept


class FrameRecorder:
    """Samples every frame of a sheet's bake (inputs.sample_frame, as job.BakeJob does) and
    turns it into the scene file's per-frame inputs, in the bake frame."""

    def __init__(self, context, obj, frames: list, spacing: float, colliders: list, m0):
        self.context, self.obj, self.frames = context, obj, frames
        self.spacing, self.collider_names = spacing, colliders
        self.inverse = np.linalg.inv(m0)
        settings = obj.thinburn
        self.igniters = inputs.igniter_objects(obj, settings)
        self.flames = inputs.flame_igniters(self.igniters)
        self.winds = inputs.wind_objects(context.view_layer)
        self.samples, self.maps, self.collider_samples = [], [], []

    def sample(self, floor) -> None:
        scene = self.context.scene
        for frame in self.frames:
            s = inputs.sample_frame(scene, frame, self.obj.name, self.igniters, self.winds, self.spacing)
            F = moving.frame_map(s.matrix, self.inverse)
            if floor is not None and not moving.keeps_floor(F):
                what = inputs.transform_animation(self.obj) or "its transform changes"
                raise BakeError(inputs.floor_motion_error(self.obj.name, what, frame))
            depsgraph = self.context.evaluated_depsgraph_get()
            self.collider_samples.append([inputs.collider_sample(bpy.data.objects[n], depsgraph)
                                          for n in self.collider_names])
            self.samples.append(s)
            self.maps.append(F)

    def ignitions(self, dt: float) -> list:
        """Every frame's Empty ignitions, as the bake makes them (job.empty_ignitions), in its
        order."""
        out, n = [], len(self.samples)
        for k, (here, F) in enumerate(zip(self.samples, self.maps)):
            there, F_next = (self.samples[k + 1], self.maps[k + 1]) if k + 1 < n else (None, None)
            out += [{"point": [float(x) for x in point], "time": float(t), "radius": float(radius)}
                    for point, t, radius in job.empty_ignitions(here, there, F, F_next, k, dt, self.spacing)]
        return out

    def surfaces(self, dt: float) -> list:
        return [{"points": pts, "radius": float(radius), "time": float(t)}
                for k, (s, F) in enumerate(zip(self.samples, self.maps))
                for pts, radius, t in job.surface_ignitions(s, F, k, dt, self.spacing)]

    def flame_rows(self):
        """Per frame the lit Flames as rows [x, y, z, width], or None without Flames."""
        if not self.flames:
            return None
        return [np.column_stack(job.flame_sources(s, F)).reshape(-1, 4)
                for s, F in zip(self.samples, self.maps)]

    def dynamics(self, params: dict):
        """Per frame the motion parameters with gravity in the bake frame, or None when every
        frame has those the Simulation is built with (``params``)."""
        rows = [job.bake_frame_dynamics(s, F) for s, F in zip(self.samples, self.maps)]
        base = {k: v for k, v in params.items() if k in rows[0]}
        return [{k: (list(v) if k == "gravity" else v) for k, v in r.items()} for r in rows] \
            if any(r != base for r in rows) else None

    def wind(self, centre: np.ndarray) -> list:
        """Per frame the wind at the sheet's centre at Start, turned into the bake frame (what
        the fields blow there; a reader of the file blows the fields themselves)."""
        return [moving.direction_to_bake(F, s.wind_at(moving.to_world(F, centre[None]))[0]).tolist()
                for s, F in zip(self.samples, self.maps)]

    def field_specs(self):
        """Per frame the force fields (world), the scene frame and Wind Scale, or None when the
        view layer has none (the bake then blows no wind)."""
        if not self.winds:
            return None
        return [{"frame": int(s.frame), "wind_scale": float(s.wind_scale),
                 "fields": [dataclasses.asdict(f) for f in s.fields]} for s in self.samples]

    def collider_specs(self) -> list:
        out = []
        for i, name in enumerate(self.collider_names):
            track = [frame[i] for frame in self.collider_samples]
            first = track[0]
            if any(not (np.array_equal(c["vertices"], first["vertices"]) and
                        np.array_equal(c["faces"], first["faces"])) for c in track):
                warnings.warn(f"Collision '{name}' changes shape during the bake: the scene file "
                              "holds its shape at Start (its pose and Friction per frame)",
                              ExportWarning, stacklevel=3)
            poses = [job.collider_in_bake_frame(c, F) for c, F in zip(track, self.maps)]
            out.append({"name": name, "vertices": first["vertices"], "faces": first["faces"],
                        "thickness": first["thickness"], "friction": [c["friction"] for c in track],
                        "rotation": [c["rotation"] for c in poses],
                        "translation": [c["translation"] for c in poses]})
        return out


def _warn_group(scene, obj) -> None:
    group = inputs.heat_group(scene, obj)
    if len(group) > 1:
        others = ", ".join(repr(n) for n in group[1:])
        warnings.warn(f"'{obj.name}' bakes together with {others} (Heat Ignites: close enough to "
                      f"heat each other): the scene file holds '{obj.name}' alone", ExportWarning,
                      stacklevel=3)


def scene_spec(obj, context=None):
    """A thinburn.scenefile.SceneSpec of the sheet's bake inputs; ExportWarning for each input
    it cannot hold."""
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
    shell = bool(settings.crumple and job.core_supports("shell"))
    restore = scene.frame_current
    try:
        scene.frame_set(frames[0])
        _warn_group(scene, obj)
        job.check_crumple_needs(settings, shell, inputs.flame_igniters(inputs.igniter_objects(obj, settings)))
        spec, m0 = _base_spec(obj, context, frames, fps, shell)
        spacing = _core_spacing(spec, 0.5 * inputs.cell_spacing(spec.vertices, spec.faces, settings.cells))
        recorder = FrameRecorder(context, obj, frames, spacing, _colliders(context, obj, shell), m0)
        recorder.sample(spec.floor)
    finally:
        scene.frame_set(restore)
    spec.igniters = recorder.ignitions(dt)
    spec.surfaces = recorder.surfaces(dt)
    spec.flames = recorder.flame_rows()
    spec.dynamics = recorder.dynamics(spec.params) if shell else None
    spec.wind = recorder.wind(spec.vertices.mean(axis=0))
    spec.fields = recorder.field_specs()
    spec.colliders = recorder.collider_specs()
    moves = any(not np.array_equal(F, np.eye(4)) for F in recorder.maps)
    spec.to_world = [F.tolist() for F in recorder.maps] if moves else None
    return spec


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
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ExportWarning)
            write_scene(context.active_object, path, context)
        for w in caught:
            self.report({"WARNING"}, f"ThinBurn: {w.message}")


register, unregister = registrar(THINBURN_OT_export_scene)
