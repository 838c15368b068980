"""The fire front on any triangulated surface (MODEL.md §9): arrival times from distances on
the surface itself, not in a UV chart or a projection.

``SurfaceCells(vertices, faces, cells=64)`` samples the surface uniformly (about cells² cells
over its total area, or at an explicit ``spacing``), independent of how the mesh is
triangulated, where it lies in space and of duplicated seam vertices (welded by position).
``SurfaceFront(cells)`` is the incremental solver (ignite, advance, arrival);
``surface_arrival_times`` is the one-shot form. See docs/surface_front.md.
"""
from __future__ import annotations

import numbers
from typing import Callable, Optional, Union

import numpy as np

from . import _core
from ._validate import index_array, integer, real, real_array

__all__ = ["SurfaceCells", "SurfaceFront", "surface_arrival_times"]


class SurfaceCells(_core.SurfaceCells):
    """Cells of a triangle mesh: positions on the surface, unit normals, areas, Gaussian
    curvature, a neighbour graph (``nbr_offset``/``nbr_index``, CSR) and the cells' own
    triangulation (``triangles``).

    vertices: (n, 3) floats; faces: (m, 3) vertex indices; any pose, open or closed, several
    pieces, holes. Faces sharing an edge three or more times (non-manifold), faces repeating
    a vertex and meshes of zero area are refused (ValueError naming ``faces``/``vertices``).
    cells: about cells² cells over the total area (like the sheet's N×N grid), unless
    spacing (m, > 0) is given. weld_tol: vertices closer than weld_tol × bounding-box
    diagonal are merged (UV seams).
    """

    def __init__(self, vertices, faces, cells: int = 64, spacing: Optional[float] = None,
                 weld_tol: float = 1e-6):
        v = real_array(vertices, "vertices", (-1, 3))
        if v.shape[0] < 3:
            raise ValueError(f"vertices must have at least 3 rows, got {v.shape[0]}")
        f = index_array(faces, "faces", (-1, 3), v.shape[0])
        if f.shape[0] < 1:
            raise ValueError("faces must have at least one row")
        n = integer(cells, "cells", low=1, high=20000)
        h = 0.0 if spacing is None else real(spacing, "spacing", low=0.0, low_open=True)
        tol = real(weld_tol, "weld_tol", low=0.0, high=0.1)
        super().__init__(v, f, cells=n, spacing=h, weld_tol=tol)
        self.num_vertices = v.shape[0]

    def __len__(self) -> int:
        return self.size

    def at_vertices(self, values) -> np.ndarray:
        """Per-cell values (cells,) interpolated to the input vertices (n,); +inf stays +inf."""
        vals = real_array(values, "values", (self.size,), finite=False)
        idx, w = self.vertex_cells, self.vertex_weights
        picked = vals[idx]
        used = w > 0.0
        out = np.where(used, picked * np.where(used, w, 0.0), 0.0).sum(axis=1)
        out[np.any(used & np.isinf(picked), axis=1)] = np.inf
        return out

    def nearest_cells(self, points) -> np.ndarray:
        """Index of the nearest cell (Euclidean) for each of (k, 3) points, O(log n) each."""
        return self.nearest(real_array(np.atleast_2d(points), "points", (-1, 3)))


SpeedLike = Union[float, np.ndarray, Callable]


def _per_cell(value, cells: SurfaceCells, name: str, *, vector: bool) -> np.ndarray:
    """A per-cell field from a number/vector, an array, or a callable(positions, normals)."""
    if callable(value):
        value = value(cells.positions, cells.normals)
    shape = (cells.size, 3) if vector else (cells.size,)
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be a number, an array or a callable, got bool")
    if not vector and isinstance(value, numbers.Real):
        value = np.full(cells.size, float(value))
    arr = np.asarray(value)
    if vector and arr.shape == (3,):
        arr = np.broadcast_to(arr, shape)
    return real_array(arr, name, shape)


def _speed(speed, cells: SurfaceCells) -> np.ndarray:
    v = _per_cell(speed, cells, "speed", vector=False)
    if np.any(v < 0.0):
        raise ValueError("speed must be >= 0 everywhere (0 marks a cell that never burns)")
    return v


def _drive(drive, cells: SurfaceCells) -> Optional[np.ndarray]:
    """Drive vectors laid onto the cells' tangent planes (the normal part is dropped)."""
    if drive is None:
        return None
    e = _per_cell(drive, cells, "drive", vector=True)
    n = cells.normals
    e = e - np.sum(e * n, axis=1)[:, None] * n
    if np.any(np.linalg.norm(e, axis=1) >= 1.0):
        raise ValueError("drive must have a tangential part |e| < 1 at every cell")
    return np.ascontiguousarray(e)


def _points(sources) -> np.ndarray:
    """(k, 3) float64 source points; a single (3,) point is accepted."""
    if sources is None or isinstance(sources, (str, bytes)):
        raise TypeError(f"sources must be (k, 3) points, got {type(sources).__name__}")
    try:
        a = np.asarray(sources, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"sources must be (k, 3) points: {exc}") from None
    return real_array(a[None] if a.ndim == 1 else a, "sources", (-1, 3))


class SurfaceFront:
    """Incremental fire front on surface cells: ``ignite`` points, then ``advance`` in time.

    speed: m/s per cell; a number, an array (cells,), or a callable(positions, normals)
    returning one; 0 marks a cell that never burns. drive: None, a 3-vector, an array
    (cells, 3) or a callable; laid onto each cell's tangent plane, |e| < 1 there. Spread is
    then fastest along e (head v(1+|e|), back v(1-|e|)), as FireFront's drive.
    """

    def __init__(self, cells: SurfaceCells, speed: SpeedLike = 1.0, drive=None,
                 init_radius: float = 2.0):
        if not isinstance(cells, _core.SurfaceCells):
            raise TypeError(f"cells must be a SurfaceCells, got {type(cells).__name__}")
        r = real(init_radius, "init_radius", low=0.0, high=10.0)
        self.cells = cells
        self._front = _core.SurfaceFront(cells, init_radius=r)
        self.set_speed(speed, drive)

    def set_speed(self, speed: SpeedLike, drive=None) -> None:
        """Speeds (and drive) used by later ignite/advance calls."""
        self._front.set_speed(_speed(speed, self.cells), _drive(drive, self.cells))

    def ignite(self, point=None, *, cell: Optional[int] = None, t0: float = 0.0) -> None:
        """Ignite the surface point nearest to a 3-D point, or a cell, at t0 (>= time)."""
        t = real(t0, "t0")
        if (point is None) == (cell is None):
            raise TypeError("ignite takes exactly one of point or cell")
        if t < self._front.time:
            raise ValueError(f"t0 = {t} is earlier than the time already advanced to ({self._front.time})")
        if cell is not None:
            self._front.ignite_cell(integer(cell, "cell", low=0, high=self.cells.size - 1), t)
        else:
            self._front.ignite_point(real_array(point, "point", (3,)), t)

    def advance(self, t_end: float) -> np.ndarray:
        """Accept every cell with arrival time <= t_end; returns them in acceptance order."""
        if isinstance(t_end, (bool, np.bool_)) or not isinstance(t_end, numbers.Real):
            raise TypeError(f"t_end must be a real number, got {type(t_end).__name__}")
        if np.isnan(t_end):
            raise ValueError("t_end must not be NaN")
        return self._front.advance(float(t_end))

    @property
    def arrival(self) -> np.ndarray:
        """Accepted arrival times (s) per cell, +inf where not burnt yet."""
        return self._front.arrival()

    @property
    def num_trial(self) -> int:
        """Cells in the narrow band (tentative time, not yet accepted)."""
        return self._front.num_trial()

    @property
    def time(self) -> float:
        """Largest t_end advanced to so far (-inf before the first advance)."""
        return self._front.time

    def accepted(self, cell: int) -> bool:
        return self._front.accepted(integer(cell, "cell", low=0, high=self.cells.size - 1))


def surface_arrival_times(vertices, faces, sources, *, speed: SpeedLike = 1.0, t0=0.0,
                          cells: int = 64, spacing: Optional[float] = None, drive=None):
    """Arrival times of the fire front on a surface from point sources (one shot).

    vertices (n, 3), faces (m, 3): the mesh (see SurfaceCells). sources: (k, 3) points, each
    snapped to the surface at its nearest cell. t0: ignition time(s), a number or (k,).
    speed, drive: as SurfaceFront. cells / spacing: the resolution (as SurfaceCells).
    Returns (times, cells): times (cells,) float64 in s (+inf where never reached) and the
    SurfaceCells (positions, normals, ...; ``cells.at_vertices(times)`` gives per-vertex times).
    """
    sc = SurfaceCells(vertices, faces, cells=cells, spacing=spacing)
    pts = _points(sources)
    if isinstance(t0, numbers.Real) and not isinstance(t0, (bool, np.bool_)):
        times = np.full(pts.shape[0], real(t0, "t0"))
    else:
        times = real_array(t0, "t0", (pts.shape[0],))
    v = _speed(speed, sc)
    e = _drive(drive, sc)
    return _core.surface_arrival_times(sc, v, e, pts, times), sc
