"""A small scene format for bakes away from Blender (wedges, farms): JSON or npz.

A scene is a mesh, how it is held and lit, a material and the bake's settings. The Blender
add-on writes one from a sheet (``thinburn_addon.scene_export.write_scene``); the demo scenes
are built by ``demo_scene``. ``load_scene`` / ``save_scene`` pick the format by extension:

``.json``::

    {"format": "thinburn-scene", "version": 1,
     "name": "Sheet",
     "vertices": [[x, y, z], ...], "faces": [[a, b, c], ...],          # metres, triangles
     "material": "paper"  or  {"preset": "paper", "V0": 3.5, ...},    # Material fields
     "igniters": [{"point": [x, y, z], "time": 0.0, "radius": 0.01}],  # seconds, metres
     "settings": {"cells": 64, "fps": 24, "frames": 240, "seed": 0, "front": "fmm",
                  "lattice": null, "floor": 0.0, "pinned": [0, 42], "integrator": "implicit",
                  "shell": true, "wind": [0, 0, 0]},     # or one [x, y, z] per frame
     "params": {"crumple_gain": 1.0, "gravity": [0, 0, -9.81]}}  # Simulation(**params)

``.npz``: the arrays ``vertices`` and ``faces``, and ``scene``, the rest as a JSON string.

Frame k of a bake is simulated time k / fps: its igniters with time in [k/fps, (k+1)/fps) are
lit, the state is recorded, then one step of 1/fps is taken (the last frame takes none), as
the add-on's bake does.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import numpy as np

from . import _validate as V
from .materials import MATERIAL_FIELDS, MATERIALS, Material, resolve_material

FORMAT = "thinburn-scene"
VERSION = 1
SETTINGS = ("cells", "fps", "frames", "seed", "front", "lattice", "floor", "pinned", "integrator",
            "shell", "wind")


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
    view_pad: float = 0.35               # the pictures' room around the sheet (not saved)

    # --- derived -----------------------------------------------------------------------------
    def resolved_material(self, changes: dict | None = None) -> Material:
        """The Material: the preset with the file's and then ``changes``' field values."""
        mat = self.material
        if isinstance(mat, dict):
            d = dict(mat)
            base = resolve_material(d.pop("preset", "paper"))
            unknown = sorted(set(d) - set(MATERIAL_FIELDS))
            if unknown:
                raise ValueError(f"material: unknown fields {unknown}; fields are {list(MATERIAL_FIELDS)}")
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

    def to_dict(self) -> dict:
        mat = self.material
        if isinstance(mat, Material):
            mat = {"preset": mat.name, **{k: v for k, v in mat.as_dict().items() if k != "name"}}
        return {
            "format": FORMAT, "version": VERSION, "name": self.name,
            "vertices": np.asarray(self.vertices, float).tolist(),
            "faces": np.asarray(self.faces, int).tolist(),
            "material": mat,
            "igniters": [{"point": [float(x) for x in g["point"]], "time": float(g.get("time", 0.0)),
                          "radius": float(g.get("radius", 0.0))} for g in self.igniters],
            "settings": {k: _plain(getattr(self, k)) for k in SETTINGS},
            "params": {k: _plain(v) for k, v in self.params.items()},
        }


def _plain(v):
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, (tuple, list)):
        return [_plain(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    return v


def from_dict(d: dict, source: str = "scene") -> SceneSpec:
    """A SceneSpec from the JSON structure; errors name the field."""
    if not isinstance(d, dict) or d.get("format") != FORMAT:
        raise ValueError(f"{source}: not a thinburn scene (need \"format\": \"{FORMAT}\")")
    if int(d.get("version", 0)) > VERSION:
        raise ValueError(f"{source}: scene version {d.get('version')} is newer than this thinburn "
                         f"reads ({VERSION})")
    verts = V.real_array(d.get("vertices"), "vertices", (-1, 3))
    faces = V.index_array(d.get("faces"), "faces", (-1, 3), len(verts))
    settings = dict(d.get("settings") or {})
    unknown = sorted(set(settings) - set(SETTINGS))
    if unknown:
        raise ValueError(f"{source}: unknown settings {unknown}; settings are {list(SETTINGS)}")
    igniters = []
    for i, g in enumerate(d.get("igniters") or []):
        if not isinstance(g, dict) or "point" not in g:
            raise ValueError(f"igniters[{i}]: need an object with a 'point'")
        igniters.append({"point": V.vector3(g["point"], f"igniters[{i}].point").tolist(),
                         "time": V.real(g.get("time", 0.0), f"igniters[{i}].time", low=0.0),
                         "radius": V.real(g.get("radius", 0.0), f"igniters[{i}].radius", low=0.0)})
    spec = SceneSpec(verts, faces, material=d.get("material", "paper"), igniters=igniters,
                     name=str(d.get("name", "Sheet")), params=dict(d.get("params") or {}))
    for key, value in settings.items():
        setattr(spec, key, value)
    spec.cells = V.integer(spec.cells, "cells", low=2, high=4096)
    spec.frames = V.integer(spec.frames, "frames", low=1)
    spec.seed = V.integer(spec.seed, "seed", low=0)
    spec.fps = V.real(spec.fps, "fps", low=0.0, low_open=True)
    spec.resolved_material()  # fails early on a bad material
    return spec


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
