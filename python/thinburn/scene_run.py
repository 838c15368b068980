"""A scene file's per-frame inputs applied to a Simulation, in the add-on's bake's order.

``SceneRun(spec, fps)`` holds what a scene lights, blows and moves frame by frame;
``before_record(sim, k)`` lights frame k's igniters, surfaces and painted map, and
``before_step(sim, k)`` sets its flames, colliders, wind (its force fields') and motion
parameters. The order and
the calls are those of the add-on's worker (blender_addon/worker.py), so a scene exported from
Blender bakes here as it does there.
"""
from __future__ import annotations

import numpy as np

from .colliders import Colliders
from .force_fields import FieldSpec, blow
from .scenefile import DYNAMICS


def _frame_of(times, fps: float, frames: int) -> np.ndarray:
    """The frame each time is due at: the first k with time < (k + 1) / fps (the last frame
    for later ones), computed as the bake compares them."""
    ends = (np.arange(frames) + 1) * (1.0 / fps)
    return np.minimum(np.searchsorted(ends, np.asarray(times, dtype=np.float64), side="right"),
                      frames - 1)


def _due(items: list, fps: float, frames: int) -> list:
    """Per frame, its items (dicts with a 'time') in the file's order."""
    out = [[] for _ in range(frames)]
    if items:
        for item, k in zip(items, _frame_of([g["time"] for g in items], fps, frames)):
            out[int(k)].append(item)
    return out


def _at(values, k: int):
    """Entry k of a per-frame list (the last one past its end)."""
    return values[min(k, len(values) - 1)]


class ColliderPoses:
    """A scene's collision objects on a Simulation: built once, then each frame's pose and
    friction set only where they changed (a pose change wakes the whole sheet)."""

    def __init__(self, colliders: list):
        self.specs = colliders
        self.colliders = None
        self.poses = [None] * len(colliders)
        self.frictions = [None] * len(colliders)

    @staticmethod
    def friction(c: dict, k: int) -> float:
        f = c["friction"]
        return float(_at(f, k) if isinstance(f, list) else f)

    def apply(self, sim, k: int) -> None:
        if not self.specs:
            return
        first = self.colliders is None
        if first:
            self.colliders = Colliders(meshes=[
                dict(vertices=c["vertices"], faces=c["faces"], friction=self.friction(c, k),
                     thickness=c["thickness"]) for c in self.specs])
            self.frictions = [self.friction(c, k) for c in self.specs]
        for i, c in enumerate(self.specs):
            self._pose(i, np.asarray(_at(c["rotation"], k), dtype=np.float64),
                       np.asarray(_at(c["translation"], k), dtype=np.float64))
            f = self.friction(c, k)
            if f != self.frictions[i]:
                self.colliders.set_friction(i, f)
                self.frictions[i] = f
        if first:
            sim.set_colliders(self.colliders)

    def _pose(self, i: int, rotation: np.ndarray, translation: np.ndarray) -> None:
        old = self.poses[i]
        if old is not None and np.array_equal(old[0], rotation) and np.array_equal(old[1], translation):
            return
        # A pose within rounding of a rotation (Blender's float32 matrices) made exactly one.
        u, _, vt = np.linalg.svd(rotation)
        self.colliders.set_transform(i, translation, u @ vt)
        self.poses[i] = (rotation, translation)


class SceneRun:
    """Drives a Simulation through a SceneSpec's per-frame inputs."""

    def __init__(self, spec, fps: float, frames: int):
        self.spec, self.fps, self.dt = spec, float(fps), 1.0 / float(fps)
        self.igniters = _due(spec.igniters, fps, frames)
        self.surfaces = _due(spec.surfaces, fps, frames)
        self.colliders = ColliderPoses(spec.colliders)
        # As the add-on's bake: changes are against the values the Simulation was built with.
        self.dynamics = self._plain({k: v for k, v in spec.params.items() if k in DYNAMICS})

    def before_record(self, sim, k: int) -> None:
        """Light what frame k lights: its igniters, its surfaces, the painted map."""
        for g in self.igniters[k]:
            try:
                sim.ignite(g["point"], time=max(g["time"], sim.time), radius=g["radius"])
            except ValueError as exc:
                if "point" not in str(exc):
                    raise
                # An igniter off the sheet lights nothing, as in the add-on.
        for g in self.surfaces[k]:
            sim.ignite_near(g["points"], radius=g["radius"], time=max(g["time"], sim.time))
        if self.spec.ignite_frame == k:
            sim.ignite_map(self.spec.maps["ignite_map"], time=max(k * self.dt, sim.time))

    def before_step(self, sim, k: int) -> None:
        """Frame k's flames, colliders, wind and changed motion parameters, before its step."""
        spec = self.spec
        if spec.flames is not None:
            rows = np.asarray(_at(spec.flames, k), dtype=np.float64).reshape(-1, 4)
            sim.set_fire_sources(rows[:, :3], rows[:, 3])
        self.colliders.apply(sim, k)
        if spec.fields:
            self._blow(sim, k)
        else:
            sim.wind = spec.wind_at(k)
        if spec.dynamics:
            self._set_dynamics(sim, _at(spec.dynamics, k))

    def _blow(self, sim, k: int) -> None:
        """The frame's force fields, as the add-on blows them (force_fields.blow)."""
        entry = _at(self.spec.fields, k)
        F = np.eye(4) if not self.spec.to_world else np.asarray(_at(self.spec.to_world, k), dtype=np.float64)
        blow(sim, self._specs(entry), entry["wind_scale"], entry["frame"], F,
             sim.vertex_positions(), bool(self.spec.shell))

    @staticmethod
    def _specs(entry: dict) -> list:
        return [FieldSpec(**{key: (tuple(v) if isinstance(v, list) else v) for key, v in f.items()})
                for f in entry["fields"]]

    @staticmethod
    def _plain(values: dict) -> dict:
        return {key: (tuple(v) if key == "gravity" else v) for key, v in values.items()}

    def _set_dynamics(self, sim, now: dict) -> None:
        now = self._plain(now)
        changed = {key: v for key, v in now.items() if self.dynamics.get(key) != v}
        if changed:
            sim.set_dynamics(**changed)
            self.dynamics.update(changed)
