"""A bake in progress: main-thread bookkeeping around the worker thread.

The modal operator calls ``tick()`` on every timer event and ``cancel()`` on Esc; in
background mode the operator calls ``run()``, which ticks until done. Everything here runs on
the main thread; the worker (worker.py) never sees bpy.
"""
from __future__ import annotations

import inspect
import math
import os
import queue
import time as _time

import bpy
import numpy as np
import thinburn

from thinburn import bake_frame as moving

from . import cache, fire, inputs, materials, properties, stretch
from .inputs import BakeError
from .worker import CoreWorker, FrameTask, path_ignitions

LOOKAHEAD = 4  # frames sampled ahead of the worker
# A sheet whose transform tilts it further than this is told that buoyancy, climb and flames
# keep its up at Start (thinburn.bake_frame): below it the error in "up" is under 1 - cos 10° = 1.5 %.
TILT_WARNING_DEG = 10.0


def core_supports(name: str) -> bool:
    """Whether thinburn.Simulation accepts the keyword ``name``."""
    return name in inspect.signature(thinburn.Simulation.__init__).parameters


def core_has_particles() -> bool:
    return hasattr(thinburn.Simulation, "particles")


class ProgressLines:
    """A bake's progress as text: one line per ``interval`` seconds (frame, percentage,
    elapsed time, ETA), for headless and background bakes."""

    def __init__(self, name: str, stream, interval: float):
        self.name, self.stream, self.interval = name, stream, interval
        self.t0 = _time.perf_counter()
        self.last = -1e9

    def building(self) -> None:
        """Before the core builds the sheet: a curved shell's cells take seconds."""
        self.stream.write(f"ThinBurn: '{self.name}' building its fire cells and motion lattice\n")
        self.stream.flush()

    def built(self, job) -> None:
        self.stream.write(f"ThinBurn: '{self.name}' built in {_time.perf_counter() - self.t0:.1f} s: "
                          f"{describe_shape(job.shape)}\n")
        self.stream.flush()

    def __call__(self, job, force: bool = False) -> None:
        now = _time.perf_counter()
        if not force and now - self.last < self.interval:
            return
        self.last = now
        frac = job.progress
        elapsed = now - self.t0
        left = job.seconds_left(now)
        eta = "?" if left is None else f"{left:.1f} s"
        self.stream.write(f"ThinBurn: '{self.name}' frame {job.current_frame} "
                          f"({job.frames_done}/{len(job.frames)}, {100 * frac:5.1f} %) "
                          f"elapsed {elapsed:.1f} s, ETA {eta}\n")
        self.stream.flush()


def check_floor(obj, world, floor, settings):
    """The sheet must start on or above the floor: said in the panel's words, not the core's.
    A sheet lying on a Floor object's top face is lifted clear of it (inputs.FLOOR_CLEARANCE)."""
    if floor is None or len(world) == 0:
        return
    low = float(np.min(world[:, 2]))
    on_object = settings.floor_mode == "OBJECT" and settings.floor_object is not None
    if on_object and floor - inputs.FLOOR_CLEARANCE - 1e-6 <= low < floor:
        world[:, 2] += floor - low
        return
    if low < floor - 1e-6:
        where = f"the top of '{settings.floor_object.name}'" if on_object else "Floor Height"
        raise BakeError(f"'{obj.name}' starts below its floor: its lowest point is at "
                        f"{low * 1000:.1f} mm, the floor ({where}) at {floor * 1000:.1f} mm. Move the "
                        "sheet up, or lower the floor (Floor Height, or the Floor object)")


def kept_bakes(sheets, objs) -> list:
    """The files of the sheets' last bakes that the saved .blend plays and this bake did not
    write over (inputs.cache_path wrote beside them), by name."""
    kept = []
    for sheet, obj in zip(sheets, objs):
        old = obj.thinburn.baked_file
        path = bpy.path.abspath(old) if old else ""
        if path and os.path.normpath(path) != os.path.normpath(sheet.abs_path) and inputs.saved_file_plays(path):
            kept.append(os.path.basename(path))
    return kept


def describe_shape(shape: dict) -> str:
    """The report's words for what the core made of the sheet (worker.simulation_shape)."""
    if shape["geometry"] == "surface":
        text = (f"a curved shell: {shape['cells']} fire cells on its surface, "
                f"{shape['spacing'] * 1000:.1f} mm apart")
    else:
        n = int(round(shape["cells"] ** 0.5))
        text = f"a flat sheet: {n}×{n} fire cells"
    if shape["couples"]:
        text += f", {shape['couples']} lattice couples"
    return text


def explain_core_error(text: str, lattice: int) -> str:
    """A failure of the core, with the panel's words where the core names its own arguments:
    'lattice' is Motion Detail, 'cells' Fire Detail."""
    out = f"the simulation failed: {text}"
    if "lattice" in text:
        now = "0: the core's choice" if lattice == 0 else str(lattice)
        out += (f". The lattice is Motion Detail (Physics > ThinBurn, now {now}): set it "
                f"{'higher' if lattice else 'yourself'}, e.g. 9 or more, or change Fire Detail")
    elif "wind" in text:
        out += (". The wind is each Wind or Turbulence field's Strength (and Noise) × Wind Scale "
                "(Physics > ThinBurn): lower them")
    elif "cells" in text:
        out += ". The cells are Fire Detail (Physics > ThinBurn)"
    return out


def check_crumple_needs(settings, shell: bool, flames: list) -> None:
    """Flames and Heat Ignites work through the fire particles, which need Crumple on."""
    if flames and not shell:
        raise BakeError(f"the Flame igniter {', '.join(repr(n) for n in flames)} burns as "
                        "fire particles, which need Crumple on: tick Crumple, or set its Kind "
                        "to Lights What It Touches")
    if settings.heat_ignites and not shell:
        raise BakeError("Heat Ignites needs Crumple on (the heat comes from the fire's "
                        "particles): tick Crumple, or untick Heat Ignites")


def ignite_frame_index(settings) -> int:
    """The index in the bake's frames at which the Ignite map lights."""
    if not settings.frame_start <= settings.ignite_frame <= settings.frame_end:
        raise BakeError(f"Ignite Frame {settings.ignite_frame} is outside the bake's frames "
                        f"{settings.frame_start}–{settings.frame_end}: set it in Physics > "
                        "ThinBurn > Painted")
    return settings.ignite_frame - settings.frame_start


# --- one frame's inputs in the bake frame (the core's), from the scene's samples --------------
def in_bake_frame(igniter, F):
    """An igniter's (world position, strength, radius) with its position in the bake frame."""
    pos, strength, radius = igniter
    return moving.to_bake(F, pos[None, :])[0], strength, radius


def empty_ignitions(here, there, F, F_next, k: int, dt: float, spacing: float) -> list:
    """Frame k's ignitions of the Empties: each lit one's position and its path to the next
    frame (``there`` None on the last frame)."""
    out = []
    for i, start in enumerate(here.igniters):
        start = in_bake_frame(start, F)
        end = None if there is None else in_bake_frame(there.igniters[i], F_next)
        out += path_ignitions(start, end, k * dt, dt, max(spacing, 0.5 * start[2]))
    return out


def surface_ignitions(here, F, k: int, dt: float, spacing: float) -> list:
    """Frame k's mesh igniters: (points, radius, time). A mesh igniter lights the cells within
    its radius of its surface (at least the surface's sampling, half a cell, so that radius 0
    still touches the sheet)."""
    return [(moving.to_bake(F, pts), max(radius, spacing), k * dt) for pts, radius in (here.surfaces or [])]


def flame_sources(here, F) -> tuple:
    """(points (k, 3), widths (k,)) of frame k's lit Flames."""
    lit = here.flames or []
    return (moving.to_bake(F, np.array([p for p, _ in lit], dtype=np.float64).reshape(-1, 3)),
            np.array([w for _, w in lit], dtype=np.float64))


def bake_frame_dynamics(here, F) -> dict:
    """The frame's motion parameters, its gravity turned into the bake frame."""
    now = dict(here.dynamics)
    now["gravity"] = tuple(float(g) for g in moving.direction_to_bake(F, now["gravity"]))
    return now


def collider_in_bake_frame(c: dict, F) -> dict:
    """A collider sample with its pose taken from the world into the bake frame."""
    inv = np.linalg.inv(F)
    c = dict(c)
    c["rotation"] = inv[:3, :3] @ c["rotation"]
    c["translation"] = inv[:3, :3] @ c["translation"] + inv[:3, 3]
    return c


class SheetCache:
    """One sheet's share of a bake: its vertices [start, stop) of the simulation, its PC2
    writer, and the map from the bake frame back to its own object space."""

    def __init__(self, name, modifier_path, abs_path, start, stop, matrix, step, frame_start):
        self.name, self.modifier_path, self.abs_path = name, modifier_path, abs_path
        self.start, self.stop = start, stop
        self.inverse = np.linalg.inv(matrix)
        self.cache_step = int(step)
        self.writer = cache.PC2Writer(abs_path, stop - start, start_frame=frame_start,
                                      sample_rate=float(self.cache_step))
        self.thinned = cache.ThinnedSamples(self.writer, self.cache_step)

    def add(self, index: int, positions: np.ndarray) -> None:
        inv = self.inverse
        self.thinned.add(index, positions[self.start:self.stop] @ inv[:3, :3].T + inv[:3, 3])


class BakeJob:
    """Bake ``obj`` frame by frame; the previous bake is replaced only when all frames are in.
    With Heat Ignites, the sheets within heat's reach of it (inputs.heat_group) bake with it as
    one simulation, each into its own cache."""

    def __init__(self, context, obj, keep_saved: bool = True):
        self.obj_name = obj.name
        self.scene = context.scene
        settings = obj.thinburn
        if obj.type != "MESH":
            raise BakeError(f"'{obj.name}' is not a mesh")
        if not settings.enabled:  # the panel's header checkbox gates the bake (issue #14)
            raise BakeError(f"ThinBurn is off for '{obj.name}': tick the checkbox in the header of "
                            "Properties > Physics > ThinBurn to burn it")
        if settings.frame_end <= settings.frame_start:
            raise BakeError(f"the frame range {settings.frame_start}–{settings.frame_end} is empty: "
                            "End must be after Start")
        self.frames = list(range(settings.frame_start, settings.frame_end + 1))
        self.fps = self.scene.render.fps / self.scene.render.fps_base
        self.dt = 1.0 / self.fps
        self.winds = inputs.wind_objects(context.view_layer)
        self.colliders = inputs.collision_objects(context.view_layer, obj.name)
        self.collider_samples = {}
        self.frame_restore = self.scene.frame_current
        # The sheet's rest state (its transform, the floor, who is near) is read at the first frame.
        self.scene.frame_set(self.frames[0])
        self.sheets = []
        try:
            self.members = inputs.heat_group(self.scene, obj)
            self.grouped = len(self.members) > 1
            objs = [bpy.data.objects[n] for n in self.members]
            if self.grouped:
                self._check_group(objs)
                self.igniters = inputs.group_igniters(objs)
                world, tris, parts = inputs.group_geometry(objs)
                self.matrix = np.eye(4)  # a group bakes in the world
            else:
                self.igniters = inputs.igniter_objects(obj, settings)
                world, tris, self.matrix = inputs.sheet_geometry(obj)
                parts = [(obj.name, 0, len(world), self.matrix)]
            self.flames = inputs.flame_igniters(self.igniters)
            kwargs = self._simulation_kwargs(obj, settings, objs)
            self.floor = kwargs.get("floor")  # where the ash flakes land, too
            check_floor(obj, world, self.floor, settings)
            for (name, first, count, mw), member in zip(parts, objs):
                paths = inputs.cache_path(member, member.thinburn, keep_saved)
                self.sheets.append(SheetCache(name, *paths, first, first + count, mw,
                                              member.thinburn.cache_step, float(self.frames[0])))
        except OSError as exc:
            self._abort_writers()
            self._restore_frame()
            raise BakeError(f"cannot write the cache file in '{settings.cache_dir}': "
                            f"{exc.strerror or exc}") from None
        except BakeError:
            self._abort_writers()
            self._restore_frame()
            raise
        self.modifier_path = self.sheets[0].modifier_path
        self.abs_path = self.sheets[0].abs_path
        self.cache_step = self.sheets[0].cache_step
        self.n_vertices = len(world)
        self.inverse = np.linalg.inv(self.matrix)
        # Igniter paths are sampled half a cell apart: an estimate until the core says (the
        # frames are sampled once it has: _await_shape).
        self.spacing = 0.5 * inputs.cell_spacing(world, tris, settings.cells)
        self.lattice = int(settings.lattice)
        self.crumple_gain = float(settings.crumple_gain)  # Crumple Amount as the bake starts
        self.max_strain = self.max_strain_frame = None  # set when a moving bake finishes
        self.shape = None  # what the core made of the sheet (worker.simulation_shape)
        edges = inputs.group_edges(objs) if self.grouped else inputs.mesh_edges(obj)
        self.stretch = stretch.StretchMeter(world, edges) if self.shell else None
        self.want_particles = core_has_particles() and self.shell
        self.particle_frames = []
        self.particle_licks = []   # per frame, each particle's tongue height seed (worker.lick_of)
        self.particle_owners = []  # a group's: which sheet's fire each particle is (its index)
        self.samples = {}
        self.next_sample = 0      # index of the next frame to sample
        self.next_task = 0        # index of the next frame to hand to the worker
        self.frames_done = 0
        self.lit = 0
        self.finished = False
        self.started = _time.perf_counter()
        self.built_at = None  # when the core had built the sheet (its cells and lattice)
        self.elapsed = 0.0
        self.message = ""
        # What the bake ignores, in an artist's words (the report shows them).
        self.warnings = inputs.wind_warnings(context.view_layer)
        if self.grouped:
            self.warnings += inputs.group_setting_warnings(obj, objs[1:])
        self.warnings += inputs.collision_warnings(context.view_layer, obj.name, self.shell)
        self._drop_floor_collider(settings)
        self._drop_open_colliders()
        self._note_thick_colliders()
        if self.flames and not settings.heat_ignites:
            self.warnings.append(
                f"{', '.join(repr(n) for n in self.flames)} {'is a Flame' if len(self.flames) == 1 else 'are Flames'}: "
                f"its heat bends '{obj.name}' but sets it alight only with Heat Ignites on "
                "(Physics > ThinBurn)")
        if self.n_vertices < (settings.cells / 4) ** 2:
            # The char, the glow and the motion live on the vertices (the fire's cells do not
            # show between them), and the bake reads the mesh before its modifiers.
            self.warnings.append(
                f"'{obj.name}' has {self.n_vertices} vertices for {settings.cells}×"
                f"{settings.cells} fire cells, so the burn shows only at those points: subdivide "
                f"the mesh (Edit Mode > Subdivide; about {settings.cells // 2} cuts) for a "
                "visible fire front")
        # The sheet's animated transform is followed: the core runs in the bake frame
        # (thinburn.bake_frame), F_k maps it to the world at frame index k.
        self.frame_maps = {}
        self.tilt = 0.0  # degrees, the most the bake frame's up turned from the world's
        meter = self.stretch
        self.worker = CoreWorker(lambda: thinburn.Simulation(world, tris, **kwargs), self.dt,
                                 self.want_particles, shell=self.shell,
                                 stretch_edges=None if meter is None else (*meter.ends, meter.rest))
        self.worker.start()

    # --- setup -------------------------------------------------------------------------------
    def _check_group(self, objs) -> None:
        """A group bakes in the world, so its sheets must keep still (a lone sheet's animated
        transform is followed: thinburn.bake_frame)."""
        for member in objs:
            what = inputs.transform_animation(member)
            if what:
                others = ", ".join(repr(o.name) for o in objs if o is not member)
                raise BakeError(
                    f"'{member.name}' bakes together with {others} (Heat Ignites: they are close "
                    f"enough to heat each other), and sheets baked together cannot move ({what}): "
                    "remove the animation, untick Heat Ignites on one of them (Physics > "
                    "ThinBurn), or move them further apart")

    def _vertex_map(self, obj, objs, key):
        if self.grouped:
            return inputs.group_vertex_map(objs, key)
        return inputs.vertex_map(obj, obj.thinburn, key)

    def _simulation_kwargs(self, obj, settings, objs) -> dict:
        kwargs = dict(material=properties.build_material(settings), cells=settings.cells,
                      seed=settings.seed, front=settings.front,
                      threads=settings.threads or None)
        for key in properties.MODEL_PARAMS:
            kwargs[key] = getattr(settings, key)
        self.shell = settings.crumple and core_supports("shell")
        if core_supports("shell"):
            kwargs["shell"] = self.shell
        if self.shell:
            kwargs["integrator"] = settings.integrator
            kwargs["lattice"] = settings.lattice or None
            if "crease_angle" in properties.PARAM_FIELDS["simulation"]:  # older cores have no creases
                # Blender keeps the angle in float32: 180° reads as 180.000005
                kwargs["crease_angle"] = min(180.0, math.degrees(settings.crease_angle))
            self.dynamics = inputs.dynamics(self.scene, settings)
            kwargs.update(self.dynamics)
        if any(o.thinburn.pin_group for o in objs):
            if not core_supports("pinned"):
                raise BakeError("this thinburn core cannot pin vertices yet: clear the Pin Group")
            kwargs["pinned"] = (inputs.group_pin_mask(objs) if self.grouped
                                else inputs.pin_mask(obj, settings.pin_group))
        check_crumple_needs(settings, self.shell, self.flames)
        if settings.heat_ignites:
            kwargs["heat_ignites"] = True
        if settings.burn_duration > 0:
            kwargs["finish_within"] = float(settings.burn_duration)
        for key in ("speed_map", "fuel_map"):
            values = self._vertex_map(obj, objs, key)
            if values is not None:
                kwargs[key] = values
        self.ignite_values = self._vertex_map(obj, objs, "ignite_map")
        self.ignite_index = None
        if self.ignite_values is not None:
            self.ignite_index = ignite_frame_index(settings)
        floor = inputs.floor_height(self.scene, settings)
        if floor is not None:
            if not core_supports("floor"):
                raise BakeError("this thinburn core has no floor yet: set Floor to None")
            kwargs["floor"] = floor
        return kwargs

    # --- progress ----------------------------------------------------------------------------
    @property
    def progress(self) -> float:
        return self.frames_done / len(self.frames)

    def seconds_left(self, now=None):
        """Seconds left at the frames' pace so far; None before the first frame. The pace is
        counted from when the core had built the sheet: a curved shell's surface cells take
        7-27 s before its first frame, and counted in, an artist's 10 s lantern bake was first
        told "ETA 3384.7 s"."""
        if self.frames_done <= 0 or self.built_at is None:
            return None
        now = _time.perf_counter() if now is None else now
        return (now - self.built_at) / self.frames_done * (len(self.frames) - self.frames_done)

    def eta_text(self) -> str:
        """Time left at the pace so far ("12 s", "2 min 5 s"; "?" before the first frame)."""
        left = self.seconds_left()
        if left is None:
            return "?"
        return f"{left:.0f} s" if left < 60 else f"{int(left // 60)} min {left % 60:.0f} s"

    def status_text(self) -> str:
        """The status bar's line during a UI bake: sheet, frame, percentage, ETA."""
        with_ = "".join(f" with '{n}'" if i == 0 else f", '{n}'" for i, n in enumerate(self.members[1:]))
        return (f"ThinBurn: baking '{self.obj_name}'{with_} frame {self.current_frame} of "
                f"{self.frames[0]}–{self.frames[-1]} ({100 * self.progress:.0f} %, ETA "
                f"{self.eta_text()})  (Esc to cancel)")

    @property
    def current_frame(self) -> int:
        return self.frames[min(self.frames_done, len(self.frames) - 1)]

    # --- driving -----------------------------------------------------------------------------
    def tick(self, budget_s: float = 0.05) -> bool:
        """Sample ahead, hand frames to the worker, store what came back. True when finished."""
        if self._await_shape(block=False):
            self._sample_ahead(_time.perf_counter() + budget_s)
        self._drain(block=False)
        return self.finished

    def run(self, progress=None, built=None) -> None:
        """Bake to the end (background mode); ``progress(self)`` after each frame, and
        ``built(self)`` once the core has built the sheet, if given."""
        self._await_shape(block=True)
        if built is not None and self.shape is not None:
            built(self)
        while not self.finished:
            self._sample_ahead(_time.perf_counter() + 1.0)
            self._drain(block=True)
            if progress is not None:
                progress(self)

    def cancel(self) -> None:
        """Stop now; the previous bake (file, modifier, attributes) stays as it was."""
        self.worker.cancel()
        self.worker.join(timeout=30.0)
        self._abort_writers()
        self._restore_frame()
        self.finished = True

    def _sample_ahead(self, deadline: float) -> None:
        try:
            self._sample_frames(deadline)
        except BakeError as exc:
            self._fail(str(exc))

    def _sample_frames(self, deadline: float) -> None:
        n = len(self.frames)
        while self.next_task < n and self.next_task < self.frames_done + LOOKAHEAD:
            need = min(self.next_task + 1, n - 1)
            while self.next_sample <= need:
                frame = self.frames[self.next_sample]
                sample = inputs.sample_frame(self.scene, frame, self.obj_name, self.igniters,
                                             self.winds, self.spacing)
                self.samples[self.next_sample] = sample
                if self.shell and self.colliders:
                    self.collider_samples[self.next_sample] = self._sample_colliders()
                self._follow(self.next_sample, sample)
                self.next_sample += 1
            self.worker.tasks.put(self._task(self.next_task))
            self.samples.pop(self.next_task - 1, None)
            self.collider_samples.pop(self.next_task - 1, None)
            self.next_task += 1
            if _time.perf_counter() > deadline:
                break

    def _follow(self, k: int, sample) -> None:
        """Record frame k's map from the bake frame to the world; a floor must stay level in
        the bake frame (the core's floor is z = const there)."""
        F = np.eye(4) if self.grouped else moving.frame_map(sample.matrix, self.inverse)
        self.frame_maps[k] = F
        if self.floor is not None and not moving.keeps_floor(F):
            obj = bpy.data.objects[self.obj_name]
            what = inputs.transform_animation(obj) or "its transform changes"
            raise BakeError(inputs.floor_motion_error(self.obj_name, what, sample.frame))
        self.tilt = max(self.tilt, moving.tilt_degrees(F))

    def _task(self, k: int) -> FrameTask:
        last = k == len(self.frames) - 1
        here = self.samples[k]
        there = None if last else self.samples[k + 1]
        F = self.frame_maps[k]
        ignitions = empty_ignitions(here, there, F, None if last else self.frame_maps[k + 1], k,
                                    self.dt, self.spacing)
        changed = {}
        if self.shell:
            now = bake_frame_dynamics(here, F)
            changed = {key: v for key, v in now.items() if self.dynamics.get(key) != v}
            self.dynamics.update(changed)
        surfaces = surface_ignitions(here, F, k, self.dt, self.spacing)
        # Every frame, so a Flame that goes out stops emitting.
        flames = flame_sources(here, F) if self.flames else None
        painted = self.ignite_values if k == self.ignite_index else None
        return FrameTask(index=k, ignitions=ignitions, fields=here.fields,
                         wind_scale=here.wind_scale, frame=here.frame, to_world=F,
                         dynamics=changed, step=not last, surfaces=surfaces, painted=painted,
                         flames=flames, colliders=self._collider_task(k))

    # --- collision objects -------------------------------------------------------------------
    def _drop_floor_collider(self, settings) -> None:
        """The Floor Object holds the sheet on its top already; its Collision as well kept the
        lattice a margin plus its Outer thickness above that (Blender's default 2 cm: Quick Burn
        on a plane on a Collision cube floated 26 mm up), so the floor alone is used."""
        floor = settings.floor_object if settings.floor_mode == "OBJECT" else None
        if floor is None or floor.name not in self.colliders:
            return
        self.colliders = [n for n in self.colliders if n != floor.name]
        self.warnings.append(f"'{floor.name}' is the Floor Object and has Collision: the sheet "
                             "rests on the Floor; its Collision is not used")

    def _drop_open_colliders(self) -> None:
        """An open mesh has no inside to push the sheet out of: warn and leave it out."""
        if not (self.shell and self.colliders):
            self.colliders = []
            return
        depsgraph = bpy.context.evaluated_depsgraph_get()
        kept = []
        for name in self.colliders:
            tris = inputs.collider_sample(bpy.data.objects[name], depsgraph)["faces"]
            if inputs.closed_mesh(tris):
                kept.append(name)
            else:
                self.warnings.append(f"Collision '{name}' is not a closed mesh (it has holes or open "
                                     "edges), so ThinBurn sheets pass through it: close it, or add a "
                                     "Solidify modifier above its Collision")
        self.colliders = kept

    def _note_thick_colliders(self) -> None:
        """The sheet rests its Outer thickness (plus the lattice's) off a collider: with Blender's
        default 2 cm, paper on a Collision table hovered 26.5 mm above it, unexplained."""
        for name in self.colliders:
            outer = float(bpy.data.objects[name].collision.thickness_outer)
            if outer > inputs.OUTER_NOTICE:
                # Outer alone is not the whole gap: an artist who lowered it to 1 mm, as the
                # note once told, still saw A4 paper hover 7.5 mm up (1 mm + the 6.6 mm lattice).
                self.warnings.append(
                    f"Collision '{name}': its Outer thickness ({1e3 * outer:.0f} mm) keeps the sheet that far "
                    "off its surface, and the sheet's motion lattice about its thickness more (a "
                    "quarter of its couples' spacing, at most 1 cm: 6.6 mm on an A4 sheet): for a sheet "
                    "resting on a table top make the table the Floor Object (the sheet then rests 0.5 mm "
                    "above it); for one draping over it lower Outer (Physics > Collision > Softbody & "
                    "Cloth) to about 1 mm")

    def _sample_colliders(self) -> list:
        depsgraph = bpy.context.evaluated_depsgraph_get()
        objects = bpy.data.objects
        for name in self.colliders:
            if objects.get(name) is None:
                raise BakeError(f"'{name}' was deleted or renamed during the bake")
        return [inputs.collider_sample(objects[name], depsgraph) for name in self.colliders]

    def _collider_task(self, k: int):
        """The colliders at frame k in the bake frame (the core's): each pose taken from the
        world into it; the worker rebuilds a collider's field only when its mesh changed."""
        here = self.collider_samples.get(k)
        if not here:
            return None
        return [collider_in_bake_frame(c, self.frame_maps[k]) for c in here]

    def _await_shape(self, block: bool) -> bool:
        """Whether the core has said what it made of the sheet (its "built" message, taken
        here). Frames are sampled only after it: igniter paths and mesh igniters are sampled
        with the core's cell spacing from the first frame on, so that every bake of a scene
        (UI, headless, a scene file's) samples alike, however fast the machine."""
        while self.shape is None and not self.finished:
            try:
                msg = self.worker.results.get(block=block, timeout=60.0 if block else None)
            except queue.Empty:
                if block and not self.worker.is_alive():
                    self._fail("the bake thread stopped without a result")
                if not block:
                    return False
                continue
            if msg[0] == "built":
                self._built(msg[1])
            elif msg[0] == "error":
                self._fail(explain_core_error(msg[1], self.lattice))
        return self.shape is not None

    def _built(self, shape: dict) -> None:
        self.shape = shape
        self.built_at = _time.perf_counter()
        if shape["spacing"] > 0:
            self.spacing = 0.5 * shape["spacing"]

    def _drain(self, block: bool) -> None:
        while not self.finished:
            try:
                msg = self.worker.results.get(block=block, timeout=60.0 if block else None)
            except queue.Empty:
                if block and not self.worker.is_alive():
                    self._fail("the bake thread stopped without a result")
                return
            kind = msg[0]
            if kind == "built":
                self._built(msg[1])
            elif kind == "frame":
                _, index, positions, lit, particles, strains = msg
                if strains is not None:  # the worker measures when the bake has a meter
                    strain, creased, turn = strains
                    self.stretch.add_strains(strain, creased, self.frames[index])
                    self.stretch.add_turn(turn, self.frames[index])
                for sheet in self.sheets:
                    sheet.add(index, positions)
                self.lit += lit
                if particles is not None:  # to the world: the fire objects do not move
                    pts, temps, licks = particles
                    F = self.frame_maps[index]
                    self.particle_frames.append((moving.to_world(F, pts).astype(np.float32), temps))
                    self.particle_licks.append(licks)
                    if self.grouped:
                        self.particle_owners.append(self._nearest_sheet(positions, pts))
                self.frames_done = index + 1
                if block and self.next_task < len(self.frames):
                    return  # let run() sample more
            elif kind == "done":
                self._finish(msg[1], msg[2])
            elif kind == "error":
                self._fail(explain_core_error(msg[1], self.lattice))

    def _nearest_sheet(self, positions: np.ndarray, pts: np.ndarray) -> np.ndarray:
        """(k,) for each fire particle the index of the sheet whose bounding box (now) is
        nearest: its flames show with that sheet's fire and go when that sheet is freed."""
        pts = np.asarray(pts, dtype=np.float64).reshape(-1, 3)
        gaps = []
        for sheet in self.sheets:
            part = positions[sheet.start:sheet.stop]
            lo, hi = part.min(axis=0), part.max(axis=0)
            gaps.append(np.linalg.norm(np.maximum(0.0, np.maximum(lo - pts, pts - hi)), axis=1))
        return np.argmin(np.stack(gaps), axis=0)

    def _abort_writers(self) -> None:
        for sheet in self.sheets:
            sheet.writer.abort()

    def _fail(self, text: str) -> None:
        self.cancel()
        raise BakeError(text)

    def _restore_frame(self) -> None:
        if self.scene.frame_current != self.frame_restore:
            self.scene.frame_set(self.frame_restore)

    # --- results -----------------------------------------------------------------------------
    def _finish(self, ignite_s: np.ndarray, burnout_s: np.ndarray) -> None:
        self.worker.join(timeout=30.0)
        objs = []
        for name in self.members:
            obj = bpy.data.objects.get(name)
            if obj is None:
                self._fail(f"the sheet '{name}' was deleted during the bake")
            objs.append(obj)
        for sheet in self.sheets:
            sheet.thinned.finish(len(self.frames) - 1)
            sheet.writer.commit()
        start = float(self.frames[0])
        ignite = cache.seconds_to_frames(ignite_s, start, self.fps)
        burnout = cache.seconds_to_frames(burnout_s, start, self.fps)
        kept = kept_bakes(self.sheets, objs)
        for k, (sheet, obj) in enumerate(zip(self.sheets, objs)):
            self._apply(obj, sheet, start, ignite[sheet.start:sheet.stop],
                        burnout[sheet.start:sheet.stop], self._particles_of(k))
        self._restore_frame()
        self.finished = True
        self.elapsed = _time.perf_counter() - self.started
        ignited = int(np.count_nonzero(ignite < cache.NEVER_FRAME))
        self.message = self._summary(ignite, ignited)
        if self.shape is not None:
            self.message += "; " + describe_shape(self.shape)
        if ignited == 0:
            self.message += " (no lit igniter touched the sheet)"
        if kept:
            self.message += (f"; the saved '{os.path.basename(bpy.data.filepath)}' still plays "
                             f"{', '.join(kept)} until you save it (this bake: "
                             f"{', '.join(os.path.basename(s.abs_path) for s in self.sheets)})")
        if self.stretch is not None:
            signed, at = self.stretch.largest_signed(burnout)
            worst = abs(signed)
            self.max_strain, self.max_strain_frame = worst, at
            for obj in objs:
                obj.thinburn.baked_strain = worst
            text = stretch.stretch_warning(self.obj_name, signed, at, self.lattice,
                                           crumple=self.crumple_gain, fit=(self.shape or {}).get("fit"),
                                           couples=(self.shape or {}).get("couples"))
            if text:
                self.warnings.append(text)
            else:
                text = stretch.crease_note(self.obj_name, self.stretch.turn, self.stretch.turn_frame,
                                           self.lattice, (self.shape or {}).get("couples"))
                if text:
                    self.warnings.append(text)
        if self.tilt > TILT_WARNING_DEG:
            self.warnings.append(inputs.tilt_warning(self.obj_name, self.tilt))

    def _apply(self, obj, sheet: SheetCache, start: float, ignite, burnout, particles) -> None:
        """Hook one sheet's share of the bake onto it: its PC2, attributes and fire."""
        materials.apply_bake(obj, sheet.modifier_path, start, ignite, burnout, self.floor)
        # Keep Every k: sample j of the file is frame Start + j k. The Mesh Cache modifier reads
        # sample (Frame Scale × frame − Frame Start) and blends between samples (its source,
        # MOD_meshcache.cc), so Frame Scale = 1/k and Frame Start = Start/k.
        md = obj.modifiers[materials.CACHE_MODIFIER]
        md.frame_scale = 1.0 / sheet.cache_step
        md.frame_start = start / sheet.cache_step
        if self.want_particles:
            frames, licks = particles
            fire.apply_particles(obj, sheet.modifier_path, frames, start, licks)
        obj.thinburn.baked_file = sheet.modifier_path
        obj.thinburn.baked_shape = "" if self.shape is None else describe_shape(self.shape)
        obj.thinburn.baked_strain = 0.0
        materials.record_bake(obj)

    def _particles_of(self, k: int) -> tuple:
        """Sheet k's fire particles frame by frame (a lone sheet has them all), and their
        tongue heights' seeds."""
        if not self.grouped:
            return self.particle_frames, self.particle_licks
        owners = self.particle_owners
        return ([(pts[own == k], temps[own == k]) for (pts, temps), own in zip(self.particle_frames, owners)],
                [licks[own == k] for licks, own in zip(self.particle_licks, owners)])

    def _summary(self, ignite, ignited: int) -> str:
        frames = f"frames {self.frames[0]}–{self.frames[-1]} in {self.elapsed:.1f} s"
        if not self.grouped:
            return (f"ThinBurn: baked '{self.obj_name}' {frames}; {ignited} of {self.n_vertices} "
                    "vertices caught fire")
        others = ", ".join(repr(n) for n in self.members[1:])
        each = ", ".join(
            f"'{sheet.name}' {int(np.count_nonzero(ignite[sheet.start:sheet.stop] < cache.NEVER_FRAME))}"
            f" of {sheet.stop - sheet.start}" for sheet in self.sheets)
        return (f"ThinBurn: baked '{self.obj_name}' together with {others} (Heat Ignites: they are "
                f"close enough to heat each other) {frames}; vertices that caught fire: {each}")
