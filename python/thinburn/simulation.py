"""The Simulation: a burning sheet stepped in time (numpy arrays in and out)."""
from __future__ import annotations

import numpy as np

from . import _core
from . import _validate as V
from ._threads import set_threads
from .materials import Material, resolve_material

FRONT_METHODS = ("cellular", "cellular16", "fmm1", "fmm")

# Keyword overrides accepted by Simulation(**params), with their bounds.
_PARAM_BOUNDS = {
    "cv": dict(low=0.0),
    "v_floor": dict(low=0.0, high=1.0, low_open=True),
    "speed_noise": dict(low=0.0, high=0.9),
    "duration_noise": dict(low=0.0, high=0.9),
    "climb": dict(low=0.0, high=0.9),
    "wind_spread": dict(low=0.0),
    "max_drive": dict(low=0.0, high=0.95),
    "ash_fraction": dict(low=0.0, high=1.0),
}


class Simulation:
    """A thin shell burning: cells and fire front (paper §3), lattice and motion (§4).

    Parameters
    ----------
    vertices : (n, 3) float array, metres; world up is +z, gravity along -z.
    faces : (m, 3) int array of vertex indices (triangles).
    uv : optional (n, 2) float array; the rest parameterisation. Without it the mesh is
        projected on its best-fit plane.
    material : a preset name from ``thinburn.MATERIALS`` or a ``thinburn.Material``.
    cells : N, the sheet is divided into N×N cells (the paper uses 128).
    seed : seeds every random draw; the same inputs and seed give bit-identical results.
    threads : thread count of the core (None: all logical cores). Results never depend on it.
    front : fire-front method, one of ``FRONT_METHODS``: "fmm" (second-order fast marching,
        the default, converges), "fmm1", "cellular" (the paper's 8-neighbour rule) or
        "cellular16".
    **params : overrides of the model's scalars: ``cv``, ``v_floor``, ``speed_noise``,
        ``duration_noise``, ``climb`` (flames climb: drive toward world-up, 0 = the paper's
        symmetric law), ``wind_spread`` (front drive per m/s of wind), ``max_drive``,
        ``ash_fraction``.
    """

    def __init__(self, vertices, faces, uv=None, material="paper", cells=128, seed=0,
                 threads=None, front="fmm", **params):
        verts = V.real_array(vertices, "vertices", (-1, 3))
        if len(verts) < 3:
            raise ValueError(f"vertices: an empty mesh (need >= 3 vertices, got {len(verts)})")
        tris = V.index_array(faces, "faces", (-1, 3), len(verts))
        if len(tris) == 0:
            raise ValueError("faces: an empty mesh (no triangles)")
        uvs = np.zeros((0, 2)) if uv is None else V.real_array(uv, "uv", (len(verts), 2))
        self.material: Material = resolve_material(material)
        self._threads = set_threads(threads)
        p = self._params(self.material, V.integer(cells, "cells", low=2, high=4096),
                         V.integer(seed, "seed", low=0, high=2**63 - 1),
                         V.choice(front, "front", FRONT_METHODS), params)
        self._sim = _core.Simulation(verts, tris, uvs, p)
        self.params = p
        self.n_vertices = len(verts)

    @staticmethod
    def _params(mat: Material, cells: int, seed: int, front: str, overrides: dict):
        p = _core.SimulationParams()
        p.cells, p.seed, p.front = cells, seed, front
        p.v0 = V.real(mat.v0, "material.V0", low=0.0, low_open=True)
        p.cv = V.real(mat.Cv, "material.Cv", low=0.0)
        p.burn_duration = V.real(mat.burn_duration, "material.burn_duration", low=0.0, low_open=True)
        p.speed_noise = V.real(mat.speed_noise, "material.speed_noise", low=0.0, high=0.9)
        p.duration_noise = V.real(mat.duration_noise, "material.duration_noise", low=0.0, high=0.9)
        p.areal_density = V.real(mat.areal_density, "material.mass", low=0.0, low_open=True)
        p.ash_fraction = V.real(mat.ash_fraction, "material.ash_fraction", low=0.0, high=1.0)
        for key, value in overrides.items():
            if key not in _PARAM_BOUNDS:
                raise TypeError(f"Simulation() got an unexpected keyword argument {key!r}; "
                                f"model parameters are {sorted(_PARAM_BOUNDS)}")
            setattr(p, key, V.real(value, key, **_PARAM_BOUNDS[key]))
        return p

    # --- driving -----------------------------------------------------------------------
    def ignite(self, point, time=None, radius=0.0) -> int:
        """Ignite the cell nearest to a 3-D point on the sheet (or every cell within radius).

        time defaults to now. A point farther from the sheet than max(radius, 3 cells, 2 % of
        the sheet's size) raises ValueError. Returns the number of cells lit.
        """
        p = V.vector3(point, "point")
        t = self.time if time is None else V.real(time, "time", low=0.0)
        r = V.real(radius, "radius", low=0.0)
        return self._sim.ignite(p, t, r)

    def step(self, dt) -> None:
        """Advance by dt seconds (> 0); frame-sized steps are fine."""
        d = V.real(dt, "dt", low=0.0, low_open=True)
        set_threads(self._threads)
        self._sim.step(d)

    def run(self, duration, dt=1 / 24, callback=None) -> None:
        """Step until `duration` more seconds have passed; callback(sim) after each step."""
        total = V.real(duration, "duration", low=0.0)
        d = V.real(dt, "dt", low=0.0, low_open=True)
        steps = int(np.ceil(total / d - 1e-9))
        for _ in range(steps):
            self.step(d)
            if callback is not None:
                callback(self)

    @property
    def time(self) -> float:
        """Simulated time, seconds."""
        return self._sim.time

    @property
    def wind(self) -> np.ndarray:
        """Wind velocity (x, y, z) in m/s; may change between steps."""
        return np.array(self._sim.wind)

    @wind.setter
    def wind(self, value) -> None:
        self._sim.wind = V.vector3(value, "wind")

    @property
    def threads(self) -> int:
        return self._threads

    @threads.setter
    def threads(self, value) -> None:
        self._threads = set_threads(value)

    # --- results -------------------------------------------------------------------------
    @property
    def cells(self) -> int:
        """N: the sheet has N×N cells."""
        return self._sim.cells

    @property
    def cell_size(self) -> tuple:
        """(dv, du): a cell's size along rows and columns, metres."""
        return tuple(self._sim.cell_size)

    def inside(self) -> np.ndarray:
        """(N, N) uint8: 1 where the cell is part of the sheet."""
        return self._sim.inside()

    def cell_states(self) -> np.ndarray:
        """(N, N) uint8: 0 unburnt, 1 burning, 2 burnt."""
        return self._sim.cell_states()

    def ignition_times(self) -> np.ndarray:
        """(N, N) float: when each cell ignited, inf where not ignited yet."""
        return self._sim.ignition_times()

    def burn_durations(self) -> np.ndarray:
        """(N, N) float: how long each cell burns, seconds."""
        return self._sim.burn_durations()

    def cell_char(self) -> np.ndarray:
        """(N, N) float in [0, 1]: 0 unburnt, rising while burning, 1 burnt."""
        return self._sim.cell_char()

    def cell_mass(self) -> np.ndarray:
        """(N, N) float: remaining mass per cell, kg (burnt cells keep ash_fraction)."""
        return self._sim.cell_mass()

    def fringe(self) -> np.ndarray:
        """(N, N) bool: burning cells with a neighbour neither burning nor burnt (paper §3.1)."""
        n = self.cells
        mask = np.zeros(n * n, dtype=bool)
        mask[np.asarray(self._sim.fringe(), dtype=np.int64)] = True
        return mask.reshape(n, n)

    def cell_positions(self) -> np.ndarray:
        """(N, N, 3) current cell-centre positions."""
        return self._sim.cell_positions().reshape(self.cells, self.cells, 3)

    def vertex_positions(self) -> np.ndarray:
        """(n, 3) current positions of the input mesh's vertices."""
        return self._sim.vertex_positions()

    def vertex_char(self) -> np.ndarray:
        """(n,) char amount in [0, 1] per input vertex, interpolated from the cells."""
        return self._sim.vertex_char()

    def vertex_ignition_times(self) -> np.ndarray:
        """(n,) when each vertex's cell ignited, inf where not yet."""
        return self._sim.vertex_ignition_times()

    def vertex_burnout_times(self) -> np.ndarray:
        """(n,) when each vertex's cell burns out, inf where not ignited yet."""
        return self._sim.vertex_burnout_times()

    def cells_to_vertices(self, field) -> np.ndarray:
        """Interpolate any (N, N) per-cell field to the input vertices (bilinear over inside cells)."""
        n = self.cells
        f = V.real_array(field, "field", (n, n))
        return self._sim.cells_to_vertices(f.ravel())

    def local_speed(self, row, col) -> tuple:
        """(v, e_row, e_col): the spread law now at a cell (eq 1 and the drive vector)."""
        n = self.cells
        r = V.integer(row, "row", low=0, high=n - 1)
        c = V.integer(col, "col", low=0, high=n - 1)
        return tuple(self._sim.local_speed(r * n + c))

    def stats(self) -> dict:
        """Sizes of the active sets now: what a step costs."""
        return {"front_active": self._sim.front_active(), "burning": self._sim.num_burning()}
