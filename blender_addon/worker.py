"""The bake's worker thread: it drives the thinburn core and nothing else.

No bpy here. The main thread reads the scene, turns each frame into a ``FrameTask`` (its
ignitions, force fields and frame map, plain numbers) and queues it; the worker runs the core's ``ignite``,
``step`` and array copies with the GIL released inside the core, and queues the results.
"""
from __future__ import annotations

import math
import queue
import threading
from dataclasses import dataclass, field

import numpy as np

from thinburn import force_fields as fields
from thinburn._mesh_measures import lattice_turns

from .stretch import ALONG_FROM, chord_strains


def lick_of(ids) -> np.ndarray:
    """Per fire particle, a number in [0, 1) fixed by its birth serial number for its life (the
    golden-ratio sequence, evenly spread): its flame tongue's height (fire.py, "ThinBurn Fire").
    A particle's row changes as others die, so a random value per row redrew every height
    each frame."""
    return np.mod(np.asarray(ids, dtype=np.float64) * 0.6180339887498949, 1.0).astype(np.float32)

MAX_PATH_SAMPLES = 64  # per igniter and frame: bounds the work of a fast-moving igniter


@dataclass
class FrameTask:
    """One frame for the worker: light these points, record the state, then step."""

    index: int                      # 0 for the bake's first frame
    ignitions: list = field(default_factory=list)  # (point (3,) in the bake frame, time s, radius m)
    fields: list = field(default_factory=list)  # fields.FieldSpec (world) blowing during the step
    wind_scale: float = 1.0         # m/s per unit of field strength
    frame: int = 0                  # the scene frame (the fields' noise is drawn per frame)
    to_world: np.ndarray = field(default_factory=lambda: np.eye(4))  # bake frame -> world now
    dynamics: dict = field(default_factory=dict)  # motion parameters that changed
    step: bool = True               # False on the last frame
    surfaces: list = field(default_factory=list)  # mesh igniters: (points (k, 3), radius m, time s)
    painted: object = None          # (n,) Ignite map values to light at this frame's start
    flames: object = None           # (points (k, 3), widths (k,)) of the lit Flames, or None
    colliders: object = None        # collision objects in the bake frame (job._collider_task), or None


def path_ignitions(start, end, t0: float, dt: float, spacing: float) -> list:
    """Ignitions along an igniter's straight path over one frame: (point, time, radius).

    ``start`` and ``end`` are (position, strength, radius) at this frame and the next (``end``
    None on the last frame). The igniter lights its position at t0; if it is still lit at the
    next frame, it also lights points along the way, at most ``spacing`` apart (or
    MAX_PATH_SAMPLES of them), at times interpolated in [t0, t0 + dt).
    """
    pos, strength, radius = start
    if strength <= 0.0:
        return []
    p0 = np.asarray(pos, dtype=np.float64)
    out = [(p0, t0, float(radius))]
    if end is None or end[1] <= 0.0:
        return out
    p1 = np.asarray(end[0], dtype=np.float64)
    r1 = float(end[2])
    dist = float(np.linalg.norm(p1 - p0))
    k = min(MAX_PATH_SAMPLES, math.ceil(dist / spacing)) if spacing > 0 else 1
    for j in range(1, k):
        s = j / k
        out.append((p0 + s * (p1 - p0), t0 + s * dt, radius + s * (r1 - radius)))
    return out


def simulation_shape(sim) -> dict:
    """What the core made of the sheet: ``geometry`` ("plane": the paper's N×N grid over a flat
    sheet; "surface": cells on a curved shell's surface), ``cells`` (how many), ``spacing`` (m
    between neighbouring cells), ``couples`` (the lattice's; 0 without motion) and ``fit`` (how
    far the mesh lies off a curved shell's lattice, Simulation.lattice_fit). A core without
    shells (no ``geometry``) is "plane"."""
    geometry = getattr(sim, "geometry", "plane")
    n = int(sim.cells)
    cells = int(getattr(sim, "num_cells", n * n))
    spacing = float(getattr(sim, "cell_spacing", 0.0))
    try:
        couples = int(getattr(sim, "lattice_couples", 0))
        fit = float(getattr(sim, "lattice_fit", 0.0))
    except (ValueError, RuntimeError):  # shell=False: no lattice
        couples, fit = 0, 0.0
    return dict(geometry=geometry, cells=cells, spacing=spacing, couples=couples, fit=fit)


class CoreWorker(threading.Thread):
    """Builds the Simulation, then runs the queued FrameTasks in order.

    Messages on ``results`` (tuples): ("built", shape) once the Simulation exists (its
    geometry, cells and couples: ``simulation_shape``), then ("frame", index, positions, lit,
    particles or None, strains or None: ``edge_strains``), ("done", ignition_times,
    burnout_times), ("error", text), ("cancelled",).

    stretch_edges: the stretch meter's (first ends, second ends, rest lengths), for
    ``edge_strains``.
    """

    def __init__(self, make_simulation, dt: float, want_particles: bool, shell: bool = False,
                 stretch_edges=None):
        super().__init__(name="thinburn-bake", daemon=True)
        self._shell = shell
        self._make_simulation = make_simulation
        self._dt = float(dt)
        self._want_particles = want_particles
        self.tasks: queue.Queue = queue.Queue()
        self.results: queue.Queue = queue.Queue()
        self._cancel = threading.Event()
        self._colliders = None  # thinburn.colliders.Colliders built from the first task that has some
        self._collider_meshes = []  # per collider: the (vertices, faces) its field was built from
        self._stretch_edges = stretch_edges  # (first ends, second ends, rest lengths)

    def cancel(self) -> None:
        self._cancel.set()
        self.tasks.put(None)  # wake a worker that waits for a task

    def run(self) -> None:
        try:
            sim = self._make_simulation()
            self.results.put(("built", simulation_shape(sim)))
            while not self._cancel.is_set():
                task = self.tasks.get()
                if task is None or self._cancel.is_set():
                    break
                self.results.put(self._run_task(sim, task))
                if not task.step:
                    self.results.put(("done", np.array(sim.vertex_ignition_times(), copy=True),
                                      np.array(sim.vertex_burnout_times(), copy=True)))
                    return
            self.results.put(("cancelled",))
        except Exception as exc:  # reported on the main thread, never swallowed
            self.results.put(("error", f"{type(exc).__name__}: {exc}"))

    def _run_task(self, sim, task: FrameTask):
        lit = 0
        for point, time, radius in task.ignitions:
            try:
                lit += sim.ignite(point, time=time, radius=radius)
            except ValueError:
                pass  # the igniter is off the sheet: it lights nothing (counted as lit == 0)
        for points, radius, time in task.surfaces:
            lit += sim.ignite_near(points, radius=radius, time=time)
        if task.painted is not None:
            lit += sim.ignite_map(task.painted, time=task.index * self._dt)
        # A fresh array per frame (the main thread keeps it), written by the core directly.
        positions = sim.vertex_positions(out=np.empty((sim.n_vertices, 3)))
        strains = self.edge_strains(sim, positions)  # before the step: the same frame
        if strains is not None:
            strains += (self.lattice_turn(sim),)
        particles = None
        if self._want_particles:
            pts, temps = sim.particles()
            particles = (np.array(pts, dtype=np.float32, copy=True),
                         np.array(temps, dtype=np.float32, copy=True),
                         lick_of(sim.particle_ids()))
        if task.flames is not None:
            sim.set_fire_sources(*task.flames)
        if task.step:
            if task.colliders is not None:
                self._collide(sim, task.colliders)
            self._blow(sim, task, positions)
            if task.dynamics:
                sim.set_dynamics(**task.dynamics)
            sim.step(self._dt)
        return ("frame", task.index, positions, lit, particles, strains)

    @staticmethod
    def lattice_turn(sim) -> float:
        """The largest turn (degrees) of a flat sheet's lattice between neighbouring couples
        where the sheet has not burnt (control strength above a half); 0 on a curved shell.
        Past 40 degrees the mesh follows the couples: a crease on the lattice's lines."""
        if getattr(sim, "geometry", "plane") != "plane":
            return 0.0
        turn = lattice_turns(sim)
        whole = sim.control_strength().min(axis=-1) > 0.5
        return float(turn[whole].max()) if whole.any() else 0.0

    def edge_strains(self, sim, positions):
        """(strains, creased): per stretch-meter edge, l/L - 1 now, and how many of them were
        measured along the surface. An edge whose chord strains past ALONG_FROM is measured
        along the surface (Simulation.surface_lengths): where the lattice folds sharply
        between couples its surface creases along the couple line, and an edge across the
        crease is a chord, far shorter than the sheet under it (docs/lattice.md, "Creases
        between couples"): the sheet did not shrink there. None without stretch edges. Here,
        not on the main thread."""
        if self._stretch_edges is None:
            return None
        e0, e1, rest = self._stretch_edges
        strain = chord_strains(positions, e0, e1, rest)
        over = np.flatnonzero(np.abs(strain) > ALONG_FROM)
        if not over.size:
            return strain, 0
        # The add-on ships its own core, which has surface_lengths on every lattice.
        along = sim.surface_lengths(np.stack([e0[over], e1[over]], axis=1))
        strain[over] = along / rest[over] - 1.0
        return strain, len(over)

    def _collide(self, sim, colliders: list) -> None:
        """Blender's Collision objects as the core's mesh colliders. A field is built only when
        a mesh is new or changed shape (0.1-0.3 s each); a collider that only moved gets a new
        pose, and one that did not move is left alone (a pose change wakes the whole sheet)."""
        from thinburn.colliders import Colliders

        meshes = [(c["vertices"], c["faces"]) for c in colliders]
        same = (self._colliders is not None and len(meshes) == len(self._collider_meshes) and
                all(v.shape == v0.shape and np.array_equal(v, v0) and np.array_equal(f, f0)
                    for (v, f), (v0, f0) in zip(meshes, self._collider_meshes)))
        if not same:
            self._colliders = Colliders(meshes=[dict(vertices=c["vertices"], faces=c["faces"],
                                                     friction=c["friction"], thickness=c["thickness"])
                                                for c in colliders])
            self._collider_meshes = meshes
            self._poses = [None] * len(colliders)
            self._frictions = [c["friction"] for c in colliders]
            for i, c in enumerate(colliders):
                self._set_pose(i, c)
            sim.set_colliders(self._colliders)
            return
        for i, c in enumerate(colliders):
            self._set_pose(i, c)
            if c["friction"] != self._frictions[i]:
                self._colliders.set_friction(i, c["friction"])
                self._frictions[i] = c["friction"]

    def _set_pose(self, i: int, c: dict) -> None:
        pose = (np.asarray(c["rotation"], dtype=np.float64), np.asarray(c["translation"], dtype=np.float64))
        old = self._poses[i]
        if old is not None and np.array_equal(old[0], pose[0]) and np.array_equal(old[1], pose[1]):
            return
        # A pose within rounding of a rotation (a float32 matrix_world) is made exactly one.
        u, _, vt = np.linalg.svd(pose[0])
        self._colliders.set_transform(i, pose[1], u @ vt)
        self._poses[i] = pose

    def _blow(self, sim, task: FrameTask, positions: np.ndarray) -> None:
        """The force fields' wind for the step (thinburn.force_fields.blow)."""
        fields.blow(sim, task.fields, task.wind_scale, task.frame, task.to_world, positions, self._shell)
