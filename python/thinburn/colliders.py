"""Collision objects for the sheet's motion: spheres, oriented boxes and closed triangle meshes.

Each answers "signed distance and outward normal at a point" (negative inside). A mesh is
turned, when added, into a signed distance field on a grid (``resolution`` cells along its
longest side): exact point-triangle distances near the surface, spread by fast sweeping, the
sign from the parity of crossings along the grid's x lines (exact for a closed mesh, which is
required, and cheap: one pass over the triangles, against a winding number's every node times
every triangle). Queries interpolate the grid trilinearly. See docs/dynamics.md §3.2.

Every collider has a pose (world = rotation @ local + translation) that may change between
steps (``set_transform``): a moving collider wakes a sleeping sheet, and the move is its
velocity over the next step (the contact acts on the sheet's speed relative to it, so a moving
box carries what rests on it).
"""
from __future__ import annotations

import numpy as np

from . import _core
from . import _validate as V

DEFAULT_FRICTION = 0.5   # Coulomb coefficient, as the floor's default
DEFAULT_RESOLUTION = 64  # SDF grid cells along a mesh's longest side


def _rotation(value, name: str) -> np.ndarray:
    return np.eye(3) if value is None else V.real_array(value, name, (3, 3))


def _renamed(exc: ValueError, kind: str, name: str) -> ValueError:
    # The core names the kind ("spheres: radius ..."); the caller's list entry is more precise.
    return ValueError(str(exc).replace(f"{kind}:", f"{name}:", 1))


class Colliders:
    """A set of collision objects.

    spheres: dicts with ``centre`` (3,), ``radius`` (m, > 0), optional ``friction`` (>= 0,
    default 0.5) and ``thickness`` (m, >= 0: the surface grown outward, as Blender's outer
    thickness). boxes: ``centre``, ``half_extents`` (3,) along the columns of ``rotation``
    (3 x 3, default identity), ``friction``, ``thickness``. meshes: ``vertices`` (n, 3),
    ``faces`` (m, 3), closed (every edge in exactly two faces), ``friction``, ``thickness``,
    ``resolution`` (grid cells along the longest side, 8..512, default 64).
    """

    def __init__(self, spheres=(), boxes=(), meshes=()):
        self._core = _core.Colliders()
        for kind, items, add in (("spheres", spheres, self.add_sphere), ("boxes", boxes, self.add_box),
                                 ("meshes", meshes, self.add_mesh)):
            for i, item in enumerate(items):
                if not isinstance(item, dict):
                    raise TypeError(f"{kind}[{i}] must be a dict of keyword arguments, got {type(item).__name__}")
                try:
                    add(**item, _name=f"{kind}[{i}]")
                except TypeError as exc:
                    raise TypeError(f"{kind}[{i}]: {exc}") from None

    def add_sphere(self, centre, radius, friction=DEFAULT_FRICTION, thickness=0.0, *, _name="sphere") -> int:
        """Add a sphere; returns its index."""
        c = V.vector3(centre, f"{_name}.centre")
        r = V.real(radius, f"{_name}.radius", low=0.0, low_open=True)
        try:
            return self._core.add_sphere(c, r, V.real(friction, f"{_name}.friction"),
                                         V.real(thickness, f"{_name}.thickness"))
        except ValueError as exc:
            raise _renamed(exc, "spheres", _name) from None

    def add_box(self, centre, half_extents, rotation=None, friction=DEFAULT_FRICTION, thickness=0.0, *,
                _name="box") -> int:
        """Add an oriented box; returns its index."""
        c = V.vector3(centre, f"{_name}.centre")
        h = V.vector3(half_extents, f"{_name}.half_extents")
        R = _rotation(rotation, f"{_name}.rotation")
        try:
            return self._core.add_box(c, h, R, V.real(friction, f"{_name}.friction"),
                                      V.real(thickness, f"{_name}.thickness"))
        except ValueError as exc:
            raise _renamed(exc, "boxes", _name) from None

    def add_mesh(self, vertices, faces, friction=DEFAULT_FRICTION, thickness=0.0, resolution=DEFAULT_RESOLUTION,
                 *, _name="mesh") -> int:
        """Add a closed triangle mesh (its vertices in its local frame, pose identity); returns
        its index. Building the field costs about a second at resolution 64."""
        v = V.real_array(vertices, f"{_name}.vertices", (-1, 3))
        f = V.index_array(faces, f"{_name}.faces", (-1, 3), len(v))
        res = V.integer(resolution, f"{_name}.resolution", low=8, high=512)
        try:
            return self._core.add_mesh(v, f, V.real(friction, f"{_name}.friction"),
                                       V.real(thickness, f"{_name}.thickness"), res)
        except ValueError as exc:
            raise _renamed(exc, "meshes", _name) from None

    def set_transform(self, index, translation, rotation=None) -> None:
        """Collider ``index``'s pose: world = rotation @ local + translation (a sphere's or a
        box's local centre is its origin, so translation is its centre)."""
        i = V.integer(index, "index", low=0, high=len(self) - 1)
        self._core.set_transform(i, V.vector3(translation, "translation"), _rotation(rotation, "rotation"))

    def set_friction(self, index, friction) -> None:
        i = V.integer(index, "index", low=0, high=len(self) - 1)
        self._core.set_friction(i, V.real(friction, "friction", low=0.0))

    def query(self, points):
        """(distance (n,), outward normal (n, 3), index (n,)) of the nearest collider at each
        point; distance < 0 inside, +inf (index -1) without colliders."""
        p = np.atleast_2d(V.real_array(np.atleast_2d(points), "points", (-1, 3)))
        d, n, i = self._core.query(p)
        return np.asarray(d), np.asarray(n), np.asarray(i)

    def grid_spacing(self, index) -> float:
        """A mesh collider's SDF grid spacing (m); 0 for a sphere or a box."""
        return self._core.grid_spacing(V.integer(index, "index", low=0, high=len(self) - 1))

    def kind(self, index) -> str:
        return self._core.kind(V.integer(index, "index", low=0, high=len(self) - 1))

    def __len__(self) -> int:
        return len(self._core)

    def __repr__(self) -> str:
        return f"Colliders({', '.join(self.kind(i) for i in range(len(self)))})"
