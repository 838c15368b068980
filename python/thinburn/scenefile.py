"""A small scene format for bakes away from Blender (wedges, farms): JSON or npz.

A scene is a mesh, how it is held and lit, a material and the bake's settings. The Blender
add-on writes one from a sheet (``thinburn_addon.scene_export.write_scene``); the demo scenes
are built by ``demo_scene``. ``load_scene`` / ``save_scene`` pick the format by extension:

``.json``::

    {"format": "thinburn-scene", "version": 2,
     "name": "Sheet",
     "vertices": [[x, y, z], ...], "faces": [[a, b, c], ...],          # metres, triangles
     "material": "paper"  or  {"preset": "paper", "V0": 3.5, ...},    # Material fields
     "igniters": [{"point": [x, y, z], "time": 0.0, "radius": 0.01}],  # seconds, metres
     "settings": {"cells": 64, "fps": 24, "frames": 240, "seed": 0, "front": "fmm",
                  "lattice": null, "floor": 0.0, "pinned": [0, 42], "integrator": "implicit",
                  "shell": true, "wind": [0, 0, 0],      # or one [x, y, z] per frame
                  "heat_ignites": false, "finish_within": null,   # version 2 from here on
                  "ignite_frame": null},
     "params": {"crumple_gain": 1.0, "gravity": [0, 0, -9.81]},  # Simulation(**params)
     "maps": {"speed_map": [...], "fuel_map": [...], "ignite_map": [...]},  # one per vertex
     "surfaces": [{"points": [[x, y, z], ...], "time": 0.0, "radius": 0.01}],
     "flames": [[[x, y, z, width], ...], ...],            # per frame, or null
     "dynamics": [{"buoyancy": 1.0, "gravity": [0, 0, -9.81], ...}, ...],  # per frame, or null
     "colliders": [{"name": "Ball", "vertices": [...], "faces": [...], "thickness": 0.001,
                    "friction": 0.5 or [per frame], "rotation": [[3 x 3] per frame],
                    "translation": [[x, y, z] per frame]}],
     "fields": [{"frame": 1, "wind_scale": 1.0, "fields": [{"kind": "WIND", ...}]}, ...],
     "to_world": [[4 x 4] per frame] or null}

``.npz``: the arrays ``vertices`` and ``faces``, and ``scene``, the rest as a JSON string.

Frame k of a bake is simulated time k / fps: its igniters with time in [k/fps, (k+1)/fps) are
lit (in the file's order), then its ``surfaces`` (``Simulation.ignite_near``), then the
``ignite_map`` at frame ``ignite_frame``; the state is recorded; then the frame's flames
(``set_fire_sources``), colliders' poses, wind and changed ``dynamics`` are set and one step of
1/fps is taken (the last frame takes none), as the add-on's bake does. The wind is ``wind``,
or with ``fields`` (per frame: Blender's Wind and Turbulence fields, thinburn.force_fields.
FieldSpec, at that scene frame, times the sheet's Wind Scale) the fields' wind at the
lattice's control vertices (``force_fields.blow``), and ``wind`` only says what it was at the
sheet's centre. A file with none of the version-2 fields is written as version 1.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import numpy as np

from . import _validate as V
from .materials import MATERIAL_FIELDS, MATERIALS, Material, resolve_material

FORMAT = "thinburn-scene"
VERSION = 2
SETTINGS_V1 = ("cells", "fps", "frames", "seed", "front", "lattice", "floor", "pinned",
               "integrator", "shell", "wind")
SETTINGS_V2 = ("heat_ignites", "finish_within", "ignite_frame")
SETTINGS = SETTINGS_V1 + SETTINGS_V2
MAPS = ("speed_map", "fuel_map", "ignite_map")
# Per-frame motion parameters (Simulation.set_dynamics): the add-on's keyframeable ones.
DYNAMICS = ("buoyancy", "wind_drag", "friction", "crumple_gain", "gravity")
# What a version-1 file cannot hold: written only when set, and then as version 2.
V2_FIELDS = ("maps", "surfaces", "flames", "dynamics", "colliders", "fields", "to_world")


@dataclass
class SceneSpec:
    """Everything a bake needs, in plain numbers."""

    vertices: np.ndarray
    faces: np.ndarray
    material: object = "paper"           # a preset name or a dict {"preset": name, field: value}
    igniters: list = field(default_factory=list)  # dicts: point, time, radius
    name: str = "Sheet"
    cells: int = 64
    fps: float = 24.0
    frames: int = 240
    seed: int = 0
    front: str = "fmm"
    lattice: int | None = None
    floor: float | None = None
    pinned: list | None = None
    integrator: str = "implicit"
    shell: bool = True
    wind: object = (0.0, 0.0, 0.0)       # (3,) or one (3,) per frame
    params: dict = field(default_factory=dict)
    heat_ignites: bool = False           # Simulation(heat_ignites=)
    finish_within: float | None = None   # Simulation(finish_within=), seconds
    ignite_frame: int | None = None      # the frame index at which maps["ignite_map"] lights
    maps: dict = field(default_factory=dict)      # MAPS: (n,) values per vertex
    surfaces: list = field(default_factory=list)  # dicts: points (k, 3), time, radius
    flames: list | None = None           # per frame: (k, 4) rows [x, y, z, width]
    dynamics: list | None = None         # per frame: {DYNAMICS key: value}
    colliders: list = field(default_factory=list)  # dicts, see the module docstring
    fields: list | None = None           # per frame: {"frame", "wind_scale", "fields": [FieldSpec dicts]}
    to_world: list | None = None         # per frame (4, 4): the bake frame to the world
    view_pad: float = 0.35               # the pictures' room around the sheet (not saved)

    # --- derived -----------------------------------------------------------------------------
    def resolved_material(self, changes: dict | None = None) -> Material:
        """The Material: the preset with the file's and then ``changes``' field values."""
        mat = self.material
        if isinstance(mat, dict):
            d = dict(mat)
            base = resolve_material(d.pop("preset", "paper"))
            _no_unknown(d, MATERIAL_FIELDS, "material", "fields")
            base = base.with_(**d)
        else:
            base = resolve_material(mat)
        return base.with_(**changes) if changes else base

    def material_name(self) -> str:
        if isinstance(self.material, dict):
            return str(self.material.get("preset", "paper"))
        return self.material.name if isinstance(self.material, Material) else str(self.material)

    def wind_at(self, k: int) -> tuple:
        w = np.asarray(self.wind, dtype=np.float64)
        if w.ndim == 2:
            return tuple(w[min(k, len(w) - 1)])
        return tuple(w)

    def in_world(self, k: int, points) -> np.ndarray:
        """(n, 3) points of frame k from the bake frame to the world (``to_world``; the same
        points when the sheet does not move)."""
        p = np.asarray(points, dtype=np.float64)
        if not self.to_world:
            return p
        F = np.asarray(self.to_world[min(k, len(self.to_world) - 1)], dtype=np.float64)
        return p @ F[:3, :3].T + F[:3, 3]

    def version(self) -> int:
        """1 when the scene uses nothing a version-1 reader lacks, else 2."""
        new = any(getattr(self, k) for k in V2_FIELDS)
        new = new or self.heat_ignites or self.finish_within is not None
        return 2 if new or self.ignite_frame is not None else 1

    def to_dict(self) -> dict:
        mat = self.material
        if isinstance(mat, Material):
            mat = {"preset": mat.name, **{k: v for k, v in mat.as_dict().items() if k != "name"}}
        version = self.version()
        keys = SETTINGS if version > 1 else SETTINGS_V1
        d = {
            "format": FORMAT, "version": version, "name": self.name,
            "vertices": np.asarray(self.vertices, float).tolist(),
            "faces": np.asarray(self.faces, int).tolist(),
            "material": mat,
            "igniters": [{"point": [float(x) for x in g["point"]], "time": float(g.get("time", 0.0)),
                          "radius": float(g.get("radius", 0.0))} for g in self.igniters],
            "settings": {k: _plain(getattr(self, k)) for k in keys},
            "params": {k: _plain(v) for k, v in self.params.items()},
        }
        if version > 1:
            d.update({k: _plain(getattr(self, k)) for k in V2_FIELDS})
        return d


def _plain(v):
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, dict):
        return {k: _plain(x) for k, x in v.items()}
    if isinstance(v, (tuple, list)):
        return [_plain(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    return v


def from_dict(d: dict, source: str = "scene") -> SceneSpec:
    """A SceneSpec from the JSON structure; errors name the field."""
    if not isinstance(d, dict) or d.get("format") != FORMAT:
        raise ValueError(f"{source}: not a thinburn scene (need \"format\": \"{FORMAT}\")")
    version = d.get("version", 0)
    if isinstance(version, bool) or not isinstance(version, int) or version > VERSION:
        raise ValueError(f"{source}: scene version {version!r} is newer than this thinburn "
                         f"reads ({VERSION}): install a newer thinburn")
    verts = V.real_array(d.get("vertices"), "vertices", (-1, 3))
    faces = V.index_array(d.get("faces"), "faces", (-1, 3), len(verts))
    settings = dict(d.get("settings") or {})
    _no_unknown(settings, SETTINGS, source, "settings")
    igniters = [_igniter(g, f"igniters[{i}]") for i, g in enumerate(d.get("igniters") or [])]
    spec = SceneSpec(verts, faces, material=d.get("material", "paper"), igniters=igniters,
                     name=str(d.get("name", "Sheet")), params=dict(d.get("params") or {}))
    for key, value in settings.items():
        setattr(spec, key, value)
    spec.cells = V.integer(spec.cells, "cells", low=2, high=4096)
    spec.frames = V.integer(spec.frames, "frames", low=1)
    spec.seed = V.integer(spec.seed, "seed", low=0)
    spec.fps = V.real(spec.fps, "fps", low=0.0, low_open=True)
    _read_v2(spec, d)
    spec.resolved_material()  # fails early on a bad material
    return spec


def _igniter(g, name: str) -> dict:
    if not isinstance(g, dict) or "point" not in g:
        raise ValueError(f"{name}: need an object with a 'point'")
    return {"point": V.vector3(g["point"], f"{name}.point").tolist(),
            "time": V.real(g.get("time", 0.0), f"{name}.time", low=0.0),
            "radius": V.real(g.get("radius", 0.0), f"{name}.radius", low=0.0)}


def _flag(value, name: str) -> bool:
    if not isinstance(value, bool):
        raise TypeError(f"{name} must be true or false, got {value!r}")
    return value


def _read_v2(spec: SceneSpec, d: dict) -> None:
    """The version-2 fields, each checked; a message names the field."""
    spec.heat_ignites = _flag(spec.heat_ignites, "heat_ignites")
    if spec.heat_ignites and not spec.shell:
        raise ValueError("heat_ignites: the heat comes from the fire particles, which need shell true")
    if spec.finish_within is not None:
        spec.finish_within = V.real(spec.finish_within, "finish_within", low=0.0, low_open=True)
    spec.maps = _maps(d.get("maps") or {}, len(spec.vertices))
    if spec.ignite_frame is not None:
        spec.ignite_frame = V.integer(spec.ignite_frame, "ignite_frame", low=0, high=spec.frames - 1)
        if "ignite_map" not in spec.maps:
            raise ValueError("ignite_frame: set, but maps has no ignite_map to light")
    elif "ignite_map" in spec.maps:
        raise ValueError("maps.ignite_map: needs the setting ignite_frame (the frame it lights at)")
    spec.surfaces = [_surface(g, f"surfaces[{i}]") for i, g in enumerate(d.get("surfaces") or [])]
    spec.flames = _per_frame(d.get("flames"), "flames", spec.frames, _flame_rows)
    spec.dynamics = _per_frame(d.get("dynamics"), "dynamics", spec.frames, _dynamics)
    spec.colliders = [_collider(c, f"colliders[{i}]", spec.frames)
                      for i, c in enumerate(d.get("colliders") or [])]
    spec.fields = _per_frame(d.get("fields"), "fields", spec.frames, _frame_fields)
    spec.to_world = _per_frame(d.get("to_world"), "to_world", spec.frames,
                               lambda m, name: V.real_array(m, name, (4, 4)).tolist())
    if (spec.flames or spec.colliders) and not spec.shell:
        raise ValueError("flames and colliders act on the sheet's motion: they need shell true")


def _frame_fields(entry, name: str) -> dict:
    """One frame's force fields: the scene frame (their noise is drawn per frame), the Wind
    Scale, and each field's FieldSpec values."""
    if not isinstance(entry, dict) or "fields" not in entry:
        raise ValueError(f"{name}: need an object with 'frame', 'wind_scale' and 'fields'")
    out = {"frame": V.integer(entry.get("frame", 0), f"{name}.frame"),
           "wind_scale": V.real(entry.get("wind_scale", 1.0), f"{name}.wind_scale"), "fields": []}
    for i, f in enumerate(entry["fields"]):
        out["fields"].append(_field_spec(f, f"{name}.fields[{i}]"))
    return out


def _field_spec(f, name: str) -> dict:
    """A FieldSpec's values, checked: the names it has, the kinds and shapes it knows."""
    from dataclasses import fields as dataclass_fields

    from .force_fields import FieldSpec

    if not isinstance(f, dict):
        raise TypeError(f"{name} must be an object of FieldSpec values, got {type(f).__name__}")
    known = [x.name for x in dataclass_fields(FieldSpec)]
    _no_unknown(f, known, name, "field settings")
    V.choice(f.get("kind"), f"{name}.kind", ("WIND", "TURBULENCE"))
    V.choice(f.get("shape"), f"{name}.shape", ("POINT", "LINE", "PLANE"))
    V.choice(f.get("z_direction"), f"{name}.z_direction", ("BOTH", "POSITIVE", "NEGATIVE"))
    V.choice(f.get("falloff"), f"{name}.falloff", ("SPHERE", "TUBE", "CONE"))
    for key in ("origin", "axis"):
        V.vector3(f.get(key), f"{name}.{key}")
    try:
        FieldSpec(**f)
    except TypeError as exc:  # a missing value
        raise ValueError(f"{name}: {exc}") from None
    return dict(f)


def _no_unknown(given, known, name: str, what: str) -> None:
    """A ValueError naming the keys of ``given`` that are not in ``known``, and the known ones."""
    unknown = sorted(set(given) - set(known))
    if unknown:
        raise ValueError(f"{name}: unknown {what} {unknown}; {what} are {list(known)}")


def _maps(maps, n: int) -> dict:
    if not isinstance(maps, dict):
        raise TypeError(f"maps must be an object of per-vertex arrays, got {type(maps).__name__}")
    _no_unknown(maps, MAPS, "maps", "maps")
    out = {}
    for key, values in maps.items():
        a = V.real_array(values, f"maps.{key}", (n,))
        if (a < 0).any():
            raise ValueError(f"maps.{key} must be >= 0 at every vertex, got {a.min():g}")
        out[key] = a.tolist()
    return out


def _surface(g, name: str) -> dict:
    if not isinstance(g, dict) or "points" not in g:
        raise ValueError(f"{name}: need an object with 'points'")
    return {"points": V.real_array(g["points"], f"{name}.points", (-1, 3)).tolist(),
            "time": V.real(g.get("time", 0.0), f"{name}.time", low=0.0),
            "radius": V.real(g.get("radius", 0.0), f"{name}.radius", low=0.0)}


def _per_frame(values, name: str, frames: int, item):
    """None, or one checked ``item`` per frame (exactly ``frames`` of them)."""
    if values is None:
        return None
    if not isinstance(values, list) or len(values) != frames:
        got = len(values) if isinstance(values, list) else type(values).__name__
        raise ValueError(f"{name}: need one entry per frame ({frames}), got {got}")
    return [item(v, f"{name}[{k}]") for k, v in enumerate(values)]


def _flame_rows(rows, name: str) -> list:
    a = V.real_array(rows if len(rows) else np.zeros((0, 4)), name, (-1, 4))
    if (a[:, 3] < 0).any():
        raise ValueError(f"{name}: flame widths (the 4th column) must be >= 0")
    return a.tolist()


def _dynamics(values, name: str) -> dict:
    if not isinstance(values, dict):
        raise TypeError(f"{name} must be an object of motion parameters, got {type(values).__name__}")
    _no_unknown(values, DYNAMICS, name, "motion parameters")
    return {k: (V.vector3(v, f"{name}.{k}").tolist() if k == "gravity" else V.real(v, f"{name}.{k}"))
            for k, v in values.items()}


def _collider(c, name: str, frames: int) -> dict:
    if not isinstance(c, dict):
        raise TypeError(f"{name} must be an object, got {type(c).__name__}")
    verts = V.real_array(c.get("vertices"), f"{name}.vertices", (-1, 3))
    faces = V.index_array(c.get("faces"), f"{name}.faces", (-1, 3), len(verts))
    friction = c.get("friction", 0.5)
    if isinstance(friction, list):
        friction = _per_frame(friction, f"{name}.friction", frames,
                              lambda f, n: V.real(f, n, low=0.0))
    else:
        friction = V.real(friction, f"{name}.friction", low=0.0)
    return {"name": str(c.get("name", name)), "vertices": verts.tolist(), "faces": faces.tolist(),
            "thickness": V.real(c.get("thickness", 0.0), f"{name}.thickness", low=0.0),
            "friction": friction,
            "rotation": _per_frame(_required(c, "rotation", name), f"{name}.rotation", frames,
                                   lambda m, n: V.real_array(m, n, (3, 3)).tolist()),
            "translation": _per_frame(_required(c, "translation", name), f"{name}.translation",
                                      frames, lambda t, n: V.vector3(t, n).tolist())}


def _required(d: dict, key: str, name: str):
    if d.get(key) is None:
        raise ValueError(f"{name}.{key}: missing (need one per frame)")
    return d[key]


def load_scene(path) -> SceneSpec:
    """Read a scene from .json or .npz."""
    path = os.fspath(path)
    if path.endswith(".npz"):
        with np.load(path) as data:
            for key in ("vertices", "faces", "scene"):
                if key not in data.files:
                    raise ValueError(f"{path}: no '{key}' array (not a thinburn scene)")
            d = json.loads(str(data["scene"]))
            d["vertices"], d["faces"] = data["vertices"], data["faces"]
    elif path.endswith(".json"):
        with open(path) as f:
            d = json.load(f)
    else:
        raise ValueError(f"scene file '{path}': the name must end in .json or .npz")
    return from_dict(d, path)


def save_scene(spec: SceneSpec, path) -> str:
    """Write a scene as .json or .npz (by extension). Returns the path."""
    path = os.fspath(path)
    d = spec.to_dict()
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    if path.endswith(".npz"):
        verts, faces = np.asarray(spec.vertices, float), np.asarray(spec.faces, np.int32)
        del d["vertices"], d["faces"]
        np.savez_compressed(path, vertices=verts, faces=faces, scene=np.array(json.dumps(d)))
    elif path.endswith(".json"):
        with open(path, "w") as f:
            json.dump(d, f)
    else:
        raise ValueError(f"scene file '{path}': the name must end in .json or .npz")
    return path


def demo_scene(material: str = "paper", cells: int = 64, fps: float = 24.0, frames: int = 240,
               vertices: int | None = None, seed: int = 0) -> SceneSpec:
    """The demo's scene for a preset (``thinburn.demo.default_scene``) as a SceneSpec."""
    from .demo import default_scene

    if material not in MATERIALS:
        raise ValueError(f"scene: unknown demo scene {material!r}; choose one of {sorted(MATERIALS)}")
    s = default_scene(material, vertices=vertices)
    return SceneSpec(s.vertices, s.faces, material=material, name=f"demo_{material}",
                     igniters=[{"point": list(map(float, s.ignite_at)), "time": 0.0,
                                "radius": float(s.ignite_radius)}],
                     cells=cells, fps=fps, frames=frames, seed=seed, floor=s.floor,
                     pinned=None if s.pinned is None else np.asarray(s.pinned).tolist(),
                     wind=tuple(s.wind), params=dict(s.params), view_pad=s.view_pad)
