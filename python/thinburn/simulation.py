"""The Simulation: a burning sheet stepped in time (numpy arrays in and out)."""
from __future__ import annotations

import threading
from types import MappingProxyType

import numpy as np

from . import _core
from . import _validate as V
from ._threads import resolve_threads
from .colliders import Colliders
from .params import FIELDS, names as _names
from .materials import IGNITION_TEMPERATURE, Material, resolve_material

FRONT_METHODS = tuple(FIELDS["simulation"]["front"].choices)  # cellular, cellular16, fmm1, fmm

INTEGRATORS = ("implicit", "bdf2", "symplectic", "explicit")
# Where the cells and the lattice live (docs/surface_front.md, "Which cells"): "plane", the
# paper's N x N grid over the rest plane (or the UV map) and an M x M lattice; "surface", cells
# on the surface itself and a lattice on a control surface fitted to it; "auto", the plane for
# a flat mesh (or for the cellular fronts, defined on a grid only), the surface for any other.
GEOMETRIES = tuple(FIELDS["simulation"]["geometry"].choices)  # auto, plane, surface

# Coordinates the model can take (r6, measured): offsets up to 1e6 m keep the motion within
# 1e-8 m of the same sheet at the origin (1e8 m: 3e-7 m, 1e10 m: 5e-5 m); a sheet smaller than
# about 1e-7 m moves wrongly (its lattice's free fall stalls, at 1e-9 m it blows up).
MAX_COORDINATE = 1e6  # m, largest |x|, |y| or |z| of a vertex
MIN_EXTENT = 1e-6     # m, smallest allowed largest side of the sheet's bounding box
# The largest lattice: a step costs ~M^2 (measured, one core, an A4 sheet at 128 cells, fire
# started: M = 33 0.3 s a step, 65 about 2 s, 129 about 10 s, 257 over 40 s); the default
# lattice never exceeds 65.
MAX_LATTICE = int(FIELDS["simulation"]["lattice"].high)  # 129
# Wind, m/s: 1e10 still gives finite results, 1e150 fails inside a step (particle normals
# overflow) and 1e300 silently does nothing; no real wind comes near 1000 m/s.
MAX_WIND = 1e3
MAX_CONTACT_SAMPLES = 16  # per control cell side (cpp/shell.hpp kMaxContactSamples)
# Simulation.run: duration / dt beyond this many steps (hours even at a millisecond a step)
# is refused rather than looping for ever (run(1e300) did).
MAX_RUN_STEPS = 10_000_000

# Keyword overrides of the shell's parts, passed on to the core's parameter groups (which
# validate them and name the field in their errors): every field of their tables
# (thinburn.params, cpp/param_table.hpp) but those the Simulation sets from its own arguments or
# its material. See docs/dynamics.md, docs/particles.md, docs/bending.md for units and meanings.
DYNAMICS_KEYS = _names("dynamics", exclude=(
    "k_structure", "k_shear", "k_flex", "c_damping",  # the material's Table 1 row (set_material)
    "has_floor", "floor_z", "integrator"))            # floor=, integrator=
BENDING_KEYS = _names("bending", exclude=("cp",))  # the material's Cp
PARTICLE_PREFIX = "particle_"
PARTICLE_KEYS = _names("particles", exclude=("seed",))  # seed=

# Keyword overrides accepted by Simulation(**params), with their bounds: the scalars of the
# core's table (the fire's, and the mesh's mesh_tolerance) but the Simulation's own arguments
# and what only the material sets.
_FIRE_KEYS = _names("simulation", exclude=(
    "cells", "geometry", "front", "seed", "shell", "lattice", "has_floor", "floor_z",  # arguments
    "finish_within", "ignition_temperature",                    # finish_within=, heat_ignites=
    "v0", "burn_duration", "areal_density",                     # the material's
    "lattice_thickness"))                                       # chosen from the lattice
_PARAM_BOUNDS = {k: FIELDS["simulation"][k].bounds() for k in _FIRE_KEYS}
# The core reads an ignition gain of 0 as "heat does not ignite"; a keyword must give a gain.
_PARAM_BOUNDS["ignition_gain"]["low_open"] = True
# Eq 2's Ct for the cells' temperature when heat ignites, m²/s (docs/heat.md, "Heat ignites"):
# calibrated on two 15 cm paper sheets, the lower lit at its centre (scripts/heat_ignition.py,
# 32 cells): the upper one catches fire 1.3 s later 1 cm above it, 2.3 s later 3 cm above, not
# in 8 s 10 cm above (189 K at most), and 50 cm above it warms by 2.8 K. The particles' heat
# scales with their birth rate (docs/heat.md): change this with particle_birth_rate.
IGNITION_GAIN = 2e-4


class Simulation:
    """A thin shell burning: cells and fire front (paper §3), lattice and motion (§4).

    Parameters
    ----------
    vertices : (n, 3) float array, metres; world up is +z, gravity along -z. Every coordinate
        must lie within ±``MAX_COORDINATE`` (1e6 m) and the sheet's bounding box must be at
        least ``MIN_EXTENT`` (1e-6 m) along its longest side (ValueError naming ``vertices``).
    faces : (m, 3) int array of vertex indices (triangles).
    uv : optional (n, 2) float array; the rest parameterisation. Without it the mesh is
        projected on its best-fit plane.
    material : a preset name from ``thinburn.MATERIALS`` or a ``thinburn.Material``.
    cells : N, the sheet is divided into N×N cells (the paper uses 128); on a curved shell
        about N² cells of even size cover its surface.
    geometry : one of ``GEOMETRIES``. "auto" (the default): a flat mesh gets the paper's grid
        (N×N cells over its plane, an M×M lattice); any other shell (a lantern, a sphere, a
        folded letter, a stack of sheets) gets cells on its surface, where the fire spreads by
        distances on the surface, and a lattice whose couples follow it. "plane" forces the
        grid (the UV map, when given, is its parameterisation), "surface" the surface. Per-cell
        arrays are (N, N) on the grid and (num_cells,) on a surface; lattice arrays are
        (M, M, 2, ...) on the grid and (couples, 2, ...) on a surface.
    seed : seeds every random draw; the same inputs and seed give bit-identical results.
    threads : thread count of the core (None: all logical cores). Results never depend on it.
    front : fire-front method, one of ``FRONT_METHODS``: "fmm" (second-order fast marching,
        the default, converges), "fmm1", "cellular" (the paper's 8-neighbour rule) or
        "cellular16".
    lattice : M, the FFD lattice has M×M couples, 2 <= M <= ``MAX_LATTICE`` (129; None: chosen
        from the sheet's size and ``cells``, at most 65, see docs/lattice.md).
    pinned : input vertices held in place: None, a bool mask of length n, or an integer index
        array of any length (``[]`` pins nothing). An integer array of length n holding only
        0 and 1 is ambiguous (mask or indices?) and raises ValueError: pass ``mask.astype(bool)``
        or ``np.flatnonzero(mask)``.
    floor : None or the height (m) of a horizontal floor with friction under the sheet.
    integrator : "implicit" (backward Euler, first order, the default), "bdf2" (second order,
        docs/dynamics.md §4), "symplectic" or "explicit" (the paper's eqs 13-15); explicit ones
        substep as stability needs or raise.
    shell : False switches the paper's §4 off: no lattice, particles or motion; the sheet keeps
        its rest shape and only the fire runs.
    finish_within : None (the material's speed) or seconds > 0: every cell the fire can reach
        has burnt out that long after the first ignition, whatever the curl does. The speed is
        scaled every step by feedback (``speed_scale`` then reads it), and a cell burns at most
        half that time (docs/fire_front.md, "Finishing within a time").
    heat_ignites : True: an unburnt cell whose temperature from the fire particles (eq 2 at
        the cells, with ``ignition_gain``, cooling at ``heat_loss`` per second) passes its
        material's ignition temperature (``thinburn.materials.IGNITION_TEMPERATURE``) catches
        fire, on a piece of the mesh not yet alight: fire jumps gaps and climbs stacks of
        sheets given as one mesh. Needs shell=True. ``cell_temperature()`` reads it.
    speed_map : None or (n,) values >= 0, one per vertex: painted spread speed, multiplying
        eq 1's V0 where the fire is (2: twice as fast, 0: a firebreak that never burns).
    fuel_map : None or (n,) values >= 0, one per vertex: painted fuel, multiplying how long a
        cell burns (2: flames stay twice as long; 0: nothing to burn, a firebreak). The maps are
        read at every cell from the triangle under it (docs/fire_front.md, "Painted maps");
        ``ignite`` lights no firebreak cell and returns how many it did light.
    **params : overrides of the model's scalars. A wrong type (text, a float where an int is
        due, a bool where a number is, a scalar for ``gravity``'s 3 components) raises
        TypeError, a bad value (NaN, inf, out of range, an int beyond a C int) ValueError; both
        name the keyword. Numpy scalars are accepted where Python ones are.

        * the fire: ``cv``, ``v_floor``, ``speed_noise``, ``duration_noise``, ``climb``
          (flames climb: drive toward world-up, 0 = the paper's symmetric law),
          ``wind_spread`` (front drive per m/s of wind), ``max_drive``, ``ash_fraction``,
          ``ash_strength`` (share of the lattice's stiffness that burnt sheet keeps, 0.1: ash
          holds little together; docs/materials.md);
        * the bending (eqs 2-6): ``ct``, ``alpha``, ``beta``, ``d_min``, ``max_rotation``,
          ``pyrolysis_range`` (m, 0.03: eq 3 counts the burning cells this close; 0 counts
          all, the paper's reading), ``heat_tolerance``, ``heat_fast``;
        * the motion: ``k_thickness``, ``k_transverse``, ``stiffness_unit``,
          ``flexural_rigidity`` (N m, default the material's: the sheet bends with it, not with
          the lattice's own layers, docs/dynamics.md §1.1), ``strain_limit`` (default the
          material's: the largest stretch or squash of the intact sheet's mid-surface between
          neighbouring couples, 0 = none, docs/dynamics.md §3.4), ``k_limit`` (1: beyond
          0.8 of strain_limit the membrane stiffens by k_limit * stiffness_unit N/m, so that
          a hanging fabric rests where it would at any step; 0 = none, §3.4 "The knee"), ``buoyancy``,
          ``wind_drag``, ``friction``, ``slip_ratio`` (3, at least 1: an implicit floor contact
          held by static friction slides where the solve asks more than slip_ratio x friction
          of it, docs/dynamics.md §3), ``crumple_gain``, ``plasticity``, ``crumple_momentum``,
          ``bimetal`` (default True: D shrinks the heated face's springs, docs/dynamics.md §2;
          False: the paper's prescribed chord motion), ``sleep_speed``,
          ``sleeping``, ``substeps`` (0, the default, chooses them per step; a fixed count is
          at most 10000, each one costs a sweep of the lattice), ``max_substeps`` (10000,
          at most 1e6: an explicit step that needs more raises), ``safety``, ``max_stretch``,
          ``cg_tolerance``, ``cg_velocity_tolerance``, ``cg_max_iterations``, ``gravity``,
          ``preconditioner`` of the implicit solve's conjugate gradients ("auto", the default:
          a sparse block LDL^T factorization, kept while it stays good, up to
          ``ldlt_max_vertices`` (2500) awake lattice vertices; above, whichever of it and
          couple-block Jacobi measurably costs fewer multiply-adds a solve; "ldlt"; "jacobi";
          ``step_stats()["ldlt_solves"]`` says which ran), ``refactor_iterations``, ``wake_hold`` (steps a vertex woken
          again soon after falling asleep stays awake, doubling per repeat; after a batch of
          sleepers is stressed awake in bulk, the steps no new batch falls asleep, doubling too);
        * the particles, prefixed ``particle_``: ``particle_capacity``,
          ``particle_birth_rate``, ``particle_temperature0``, ``particle_cooling``,
          ``particle_lifetime``, ``particle_lifetime_jitter``, ``particle_buoyancy``,
          ``particle_drag``, ``particle_turbulence``, ``particle_birth_speed``,
          ``particle_vertical_band``;
        * the mesh: ``mesh_tolerance`` (share of the sheet's size, default 1e-6: a lattice
          couple that drifted less than that since its mesh vertices were last deformed keeps
          them as they are, so each vertex is within twice that of its exact place, 2 µm on a
          1 m sheet; 0: every vertex of a moved couple is redone, bit for bit a full deform;
          a grid lattice's mesh only, docs/lattice.md "The mesh's tolerance");
        * the start: ``imperfection`` (share of the sheet's size a flat sheet starts bowed by
          along its normal, times the share of gravity in its plane; default 1e-3: a sheet
          pinned along its bottom falls once taller than Greenhill's column, docs/dynamics.md
          §1.2; 0: perfectly flat).
    """

    def __init__(self, vertices, faces, uv=None, material="paper", cells=128, seed=0,
                 threads=None, front="fmm", lattice=None, pinned=None, floor=None,
                 integrator="implicit", shell=True, geometry="auto", speed_map=None, fuel_map=None,
                 finish_within=None, heat_ignites=False, **params):
        verts = V.real_array(vertices, "vertices", (-1, 3))
        if len(verts) < 3:
            raise ValueError(f"vertices: an empty mesh (need >= 3 vertices, got {len(verts)})")
        _check_scale(verts)
        tris = V.index_array(faces, "faces", (-1, 3), len(verts))
        if len(tris) == 0:
            raise ValueError("faces: an empty mesh (no triangles)")
        uvs = np.zeros((0, 2)) if uv is None else V.real_array(uv, "uv", (len(verts), 2))
        self.material: Material = resolve_material(material)
        self._threads = resolve_threads(threads)
        p = self._params(self.material, V.integer(cells, "cells", low=2, high=4096),
                         V.integer(seed, "seed", low=0, high=2**63 - 1),
                         V.choice(front, "front", FRONT_METHODS), params)
        p.geometry = V.choice(geometry, "geometry", GEOMETRIES)
        if not isinstance(heat_ignites, (bool, np.bool_)):
            raise TypeError(f"heat_ignites must be a bool, got {type(heat_ignites).__name__}")
        if heat_ignites:
            if not shell:
                raise ValueError("heat_ignites: the heat comes from the fire particles, which need "
                                 "shell=True")
            p.ignition_temperature = IGNITION_TEMPERATURE.get(self.material.name, IGNITION_TEMPERATURE["paper"])
            if p.ignition_gain == 0.0:
                p.ignition_gain = IGNITION_GAIN
        if finish_within is not None:
            p.finish_within = V.real(finish_within, "finish_within", low=0.0, low_open=True)
        if p.geometry == "auto" and front in ("cellular", "cellular16"):
            p.geometry = "plane"  # the paper's rule is defined on the grid
        if not isinstance(shell, (bool, np.bool_)):
            raise TypeError(f"shell must be a bool, got {type(shell).__name__}")
        p.shell = bool(shell)
        if lattice is not None:
            m = V.integer(lattice, "lattice", low=2)
            if m > MAX_LATTICE:
                raise ValueError(f"lattice must be <= {MAX_LATTICE}, got {m}: a step's cost grows as "
                                 "M^2 (one core, an A4 sheet at 128 cells: M = 65 about 2 s a step, M = 129 "
                                 "about 10 s, M = 257 over 40 s); use lattice=None (chosen from the sheet, "
                                 "at most 65) or a smaller M")
            p.lattice = m
        if floor is not None:
            p.has_floor, p.floor_z = True, V.real(floor, "floor")
            if float(verts[:, 2].min()) < p.floor_z - 1e-9:
                raise ValueError(f"floor: the sheet reaches below the floor (z min "
                                 f"{verts[:, 2].min():.6g} < floor {p.floor_z:.6g})")
        _set_group(p.set_dynamics, None, {"integrator": V.choice(integrator, "integrator", INTEGRATORS)})
        pins = _pinned_mask(pinned, len(verts))
        maps = [_vertex_map(m, name, len(verts)) for m, name in ((speed_map, "speed_map"), (fuel_map, "fuel_map"))]
        self._sim = _Serialised(_core.Simulation(verts, tris, uvs, p, pins, *maps))
        self.n_vertices = len(verts)

    @staticmethod
    def _params(mat: Material, cells: int, seed: int, front: str, overrides: dict):
        overrides = dict(overrides)
        groups = {"dynamics": {}, "bending": {}, "particles": {}}
        for key in list(overrides):
            if key in DYNAMICS_KEYS:
                groups["dynamics"][key] = overrides.pop(key)
            elif key in BENDING_KEYS:
                groups["bending"][key] = overrides.pop(key)
            elif key.startswith(PARTICLE_PREFIX) and key[len(PARTICLE_PREFIX):] in PARTICLE_KEYS:
                groups["particles"][key[len(PARTICLE_PREFIX):]] = overrides.pop(key)
        p = Simulation._fire_params(mat, cells, seed, front, overrides)
        # The crumple's and the curl's defaults (bimetal, max_stretch, max_rotation, ...) are the
        # core's; set_material derives the transverse springs and the crumple gain from K_structure.
        _set_group(lambda m: p.set_material(**m), "material",
                   dict(k_structure=mat.K_structure, k_shear=mat.K_shear, k_flex=mat.K_flex,
                        c_damping=mat.C_damping))
        # The sheet's own bending (docs/dynamics.md §1.1; 0: the lattice's).
        _set_group(p.set_dynamics, "material", dict(flexural_rigidity=mat.flexural_rigidity,
                                                    strain_limit=mat.strain_limit))
        _set_group(p.set_bending, "material", dict(cp=mat.Cp, alpha=mat.alpha, beta=mat.beta))
        _set_group(p.set_dynamics, None, groups["dynamics"])
        _set_group(p.set_bending, None, groups["bending"])
        _set_group(p.set_particles, PARTICLE_PREFIX, groups["particles"])
        return p

    @staticmethod
    def _fire_params(mat: Material, cells: int, seed: int, front: str, overrides: dict):
        p = _core.SimulationParams()
        p.cells, p.seed, p.front = cells, seed, front
        fire = FIELDS["simulation"]
        for key, value, name in (("v0", mat.v0, "V0"), ("cv", mat.Cv, "Cv"),
                                 ("burn_duration", mat.burn_duration, "burn_duration"),
                                 ("speed_noise", mat.speed_noise, "speed_noise"),
                                 ("duration_noise", mat.duration_noise, "duration_noise"),
                                 ("areal_density", mat.areal_density, "mass"),
                                 ("ash_fraction", mat.ash_fraction, "ash_fraction"),
                                 ("ash_strength", mat.ash_strength, "ash_strength")):
            setattr(p, key, V.real(value, "material." + name, **fire[key].bounds()))
        for key, value in overrides.items():
            if key not in _PARAM_BOUNDS:
                known = sorted(_PARAM_BOUNDS) + list(DYNAMICS_KEYS) + list(BENDING_KEYS) + [
                    PARTICLE_PREFIX + k for k in PARTICLE_KEYS]
                raise TypeError(f"Simulation() got an unexpected keyword argument {key!r}; "
                                f"model parameters are {known}")
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

    def ignite_map(self, values, time=None, threshold=0.5) -> int:
        """Ignite every cell where a painted per-vertex map (n,) reaches ``threshold``: the map
        is read at the cells as ``speed_map`` is, so a vertex group lights the area painted,
        not only its vertices. Firebreaks stay unlit. Returns the number of cells lit."""
        m = V.real_array(values, "values", (self.n_vertices,))
        t = self.time if time is None else V.real(time, "time", low=0.0)
        thr = V.real(threshold, "threshold")
        field = np.asarray(self._sim.vertex_field(m))
        return self._sim.ignite_cells(np.flatnonzero(field >= thr).astype(np.int32).tolist(), t)

    def ignite_near(self, points, radius, time=None) -> int:
        """Ignite every unburnt cell within ``radius`` (m) of any of ``points`` (k, 3), where the
        cells are now: a mesh igniter's surface, sampled at most about a radius apart, lights
        the cells it touches. Points far from the sheet light nothing (no error). Returns the
        number of cells lit."""
        pts = V.real_array(points, "points", (-1, 3))
        r = V.real(radius, "radius", low=0.0)
        t = self.time if time is None else V.real(time, "time", low=0.0)
        return self._sim.ignite_near(pts, r, t)

    def set_fire_sources(self, points, widths) -> None:
        """Flames that burn on their own (a candle, a burner): each point (k, 3) emits fire
        particles upward as a burning front ``widths`` (k,) metres long would, every step from
        now until replaced (``set_fire_sources(np.zeros((0, 3)), [])`` puts them out). Their
        heat bends the sheet (eq 2) and, with ``heat_ignites``, lights it. Needs shell=True."""
        pts = V.real_array(points, "points", (-1, 3))
        w = V.real_array(widths, "widths", (len(pts),))
        if (w < 0).any():
            raise ValueError("widths must be >= 0 (m of flame front per point)")
        if not self._sim.has_shell:
            raise ValueError("set_fire_sources: flames are fire particles, which need shell=True")
        self._sim.set_fire_sources(pts, w)

    @property
    def speed_scale(self) -> float:
        """Multiplies every cell's spread speed from now on (1: the material's); > 0."""
        return self._sim.speed_scale

    @speed_scale.setter
    def speed_scale(self, value) -> None:
        self._sim.speed_scale = V.real(value, "speed_scale", low=0.0, low_open=True)

    def cells_near(self, point, radius=0.0) -> np.ndarray:
        """The cells ``ignite(point, radius=radius)`` would light: the nearest inside cell, or
        every inside cell within radius; (k, 2) [row, col] on the grid, (k,) cell indices on
        a surface. On the grid it costs about the lattice's size, not the number of cells; on
        a surface it scans the cells. Raises ValueError as ignite does."""
        p = V.vector3(point, "point")
        r = V.real(radius, "radius", low=0.0)
        cells = np.asarray(self._sim.cells_near(p, r), dtype=np.int64)
        if self.geometry == "surface":
            return cells
        return np.stack([cells // self.cells, cells % self.cells], axis=1)

    def step(self, dt) -> None:
        """Advance by dt seconds (> 0); frame-sized steps are fine."""
        d = V.real(dt, "dt", low=0.0, low_open=True)
        self._sim.step(d, self._threads)

    def run(self, duration, dt=1 / 24, callback=None) -> None:
        """Step until `duration` more seconds have passed; callback(sim) after each step.
        At most ``MAX_RUN_STEPS`` (1e7) steps: more raise ValueError naming ``duration``."""
        total = V.real(duration, "duration", low=0.0)
        d = V.real(dt, "dt", low=0.0, low_open=True)
        if callback is not None and not callable(callback):
            raise TypeError(f"callback must be callable or None, got {type(callback).__name__}")
        steps = total / d
        if steps > MAX_RUN_STEPS:
            raise ValueError(f"duration: {total:g} s at dt = {d:g} s is {steps:.3g} steps, more than "
                             f"{MAX_RUN_STEPS:.0e}; use a larger dt or a shorter duration")
        steps = int(np.ceil(steps - 1e-9))
        for _ in range(steps):
            self.step(d)
            if callback is not None:
                callback(self)

    @property
    def params(self) -> "ParamsView":
        """The model's parameters in force, read-only: ``sim.params.cells``,
        ``sim.params.dynamics["wind_drag"]``. A live view: a view kept across a
        ``set_dynamics`` reads the new values."""
        return ParamsView(self._sim)

    @property
    def time(self) -> float:
        """Simulated time, seconds."""
        return self._sim.time

    @property
    def wind(self) -> np.ndarray:
        """Wind velocity (x, y, z) in m/s, |wind| <= ``MAX_WIND`` (1000); may change between steps."""
        return np.array(self._sim.wind)

    @wind.setter
    def wind(self, value) -> None:
        w = V.vector3(value, "wind")
        if float(np.linalg.norm(w)) > MAX_WIND:
            raise ValueError(f"wind: |wind| = {np.linalg.norm(w):.3g} m/s exceeds {MAX_WIND:g} m/s "
                             "(the model's drag and particles overflow far above it)")
        self._sim.wind = w

    def set_wind_field(self, wind) -> None:
        """Wind per lattice control vertex for the sheet's motion, m/s: an array shaped as
        ``lattice_positions()`` ((M, M, 2, 3); (couples, 2, 3) on a surface), used instead of
        ``wind`` by the lattice's wind drag until set again; None: the uniform ``wind`` again.
        The fire front and the fire particles keep the uniform ``wind``."""
        self._require_shell("set_wind_field")
        n = 2 * self._sim.lattice_couples
        if wind is None:
            self._sim.set_wind_field(np.zeros((0, 3)))
            return
        w = np.asarray(wind, dtype=np.float64)
        if w.size != 3 * n or w.shape[-1] != 3:
            raise ValueError(f"wind field: expected one (x, y, z) per control vertex, shaped like "
                             f"lattice_positions() ({n} vectors), got shape {w.shape}")
        w = w.reshape(n, 3)
        if not np.all(np.isfinite(w)):
            raise ValueError("wind field: every value must be finite")
        fastest = float(np.linalg.norm(w, axis=1).max()) if n else 0.0
        if fastest > MAX_WIND:
            raise ValueError(f"wind field: |wind| = {fastest:.3g} m/s exceeds {MAX_WIND:g} m/s")
        self._sim.set_wind_field(np.ascontiguousarray(w))

    def set_colliders(self, colliders=None, *, spheres=(), boxes=(), meshes=(), margin=None, samples=4):
        """Collision objects the sheet rests on or drapes over (docs/dynamics.md §3.2): a
        ``thinburn.colliders.Colliders``, or ``spheres``/``boxes``/``meshes`` lists of dicts
        that build one (see ``Colliders``); None and no lists: none. After every substep a
        lattice control vertex closer than ``margin`` (m; None: half ``lattice_thickness``, so
        that the fine mesh between couples keeps clear of a curved collider) is pushed out
        along the collider's normal, loses its inward speed relative to the collider, and
        Coulomb friction (each collider's ``friction`` times that speed) slows it along the
        surface; then so is each of ``samples`` x ``samples`` points of the sheet's mid-surface
        per control cell (a flat sheet's lattice; a curved shell's: mesh vertices a control
        spacing / ``samples`` apart; 0: the control vertices only), so a collider
        narrower than a control cell (a rod, a table's edge) does not pass between couples.
        Returns the Colliders in force: move one with ``set_transform`` between steps (the
        sheet wakes, and the move is the collider's velocity over the next step, so a moving
        box carries what rests on it). Mutating it from another thread during a step is not
        supported."""
        self._require_shell("set_colliders")
        if colliders is not None and (spheres or boxes or meshes):
            raise TypeError("set_colliders: pass either colliders or spheres/boxes/meshes, not both")
        if colliders is None and (spheres or boxes or meshes):
            colliders = Colliders(spheres=spheres, boxes=boxes, meshes=meshes)
        if colliders is not None and not isinstance(colliders, Colliders):
            raise TypeError(f"colliders must be a thinburn.colliders.Colliders or None, "
                            f"got {type(colliders).__name__}")
        m = 0.5 * self.lattice_thickness if margin is None else V.real(margin, "margin", low=0.0)
        n = V.integer(samples, "samples", low=0, high=MAX_CONTACT_SAMPLES)
        self._sim.set_colliders(None if colliders is None else colliders._core, m, n)
        self._colliders = colliders
        return colliders

    @property
    def threads(self) -> int:
        """This Simulation's thread count (None sets all logical cores); results never depend
        on it, and other Simulations keep their own."""
        return self._threads

    @threads.setter
    def threads(self, value) -> None:
        self._threads = resolve_threads(value)

    # --- the shell ----------------------------------------------------------------------
    @property
    def lattice_size(self) -> int:
        """M: the lattice has M×M couples (0 without a shell)."""
        return self._sim.lattice_size

    @property
    def lattice_thickness(self) -> float:
        """Distance between a couple's top and bottom control vertices, m."""
        return self._sim.lattice_thickness

    @property
    def lattice_fit(self) -> float:
        """How well a curved shell's lattice carries its mesh: the 99th percentile over mesh
        vertices of their distance from the lattice's interpolated mid-surface, in half
        thicknesses (at most 1: the mesh lies in the layer between the couples). Detail finer
        than the lattice (pleats, waves) rides at that offset, and bending stretches it by the
        bend's curvature times the offset; the chosen lattice is made finer until this is at
        most 0.5 (docs/lattice.md, "Detail finer than the lattice"). 0 on a flat sheet's grid."""
        return self._sim.lattice_fit

    @property
    def lattice_rigidity(self) -> float:
        """The lattice's own flexural rigidity, N m: its layers' springs a thickness apart
        (docs/dynamics.md §1.1); 0 without a shell."""
        return self._sim.lattice_rigidity

    @property
    def bending_share(self) -> float:
        """flexural_rigidity / lattice_rigidity, at most 1: the share of the lattice's own
        bending its layers keep (1: the lattice bends as its own)."""
        return self._sim.bending_share

    @property
    def lattice_couples(self) -> int:
        """Number of couples of the lattice (M² on the grid; 0 without a shell)."""
        return self._sim.lattice_couples

    def _couples(self, values, what: str, *tail) -> np.ndarray:
        # (M, M, *tail) on the grid, (couples, *tail) on a control surface.
        m = self._require_shell(what)
        lead = (m, m) if m else (self._sim.lattice_couples,)
        return np.asarray(values()).reshape(*lead, *tail)

    def lattice_positions(self) -> np.ndarray:
        """(M, M, 2, 3) control vertices: [row, column, 0 bottom / 1 top, xyz]; (couples, 2, 3)
        on a surface."""
        return self._couples(self._sim.lattice_positions, "lattice_positions", 2, 3)

    def lattice_rest_positions(self) -> np.ndarray:
        """(M, M, 2, 3) control vertices at rest; (couples, 2, 3) on a surface."""
        return self._couples(self._sim.lattice_rest_positions, "lattice_rest_positions", 2, 3)

    def lattice_springs(self) -> np.ndarray:
        """(s, 2) the lattice's springs as pairs of control vertices, each numbered
        2 * couple + layer (0 bottom, 1 top) in the couples' order of lattice_positions (row by
        row on the grid): what ties which couples, to check a lattice's topology."""
        self._require_shell("lattice_springs")
        return np.asarray(self._sim.lattice_springs())

    def heat(self) -> np.ndarray:
        """(M, M, 2) heat accumulated at the control vertices (eq 2); (couples, 2) on a surface."""
        return self._couples(self._sim.heat, "heat", 2)

    def pyrolysis(self) -> np.ndarray:
        """(M, M, 2) pyrolysis at the control vertices now (eq 3); (couples, 2) on a surface."""
        return self._couples(self._sim.pyrolysis, "pyrolysis", 2)

    def rotation(self) -> np.ndarray:
        """(M, M) the rotation D per couple (eqs 4-6), radians; (couples,) on a surface."""
        return self._couples(self._sim.rotation, "rotation")

    def control_masses(self) -> np.ndarray:
        """(M, M, 2) sheet mass mapped onto each control vertex, kg (falls as cells burn)."""
        return self._couples(self._sim.control_masses, "control_masses", 2)

    def control_strength(self) -> np.ndarray:
        """(M, M, 2) share of the lattice springs' stiffness each control vertex keeps: 1 where
        the sheet is intact, down to ash_strength where all it carries burnt."""
        return self._couples(self._sim.control_strength, "control_strength", 2)

    def lattice_awake(self) -> np.ndarray:
        """(M, M, 2) bool: the control vertices the next step integrates; the others sleep
        or are pinned (docs/dynamics.md §5). ``step_stats()["awake"]`` counts the last step's."""
        return self._couples(self._sim.lattice_awake, "lattice_awake", 2)

    def particles(self):
        """(positions (k, 3), temperatures (k,)) of the live fire particles."""
        return self._sim.particles()

    def particle_velocities(self) -> np.ndarray:
        """(k, 3) velocities of the live fire particles, m/s."""
        return self._sim.particle_velocities()

    def particle_ids(self) -> np.ndarray:
        """(k,) uint64 birth serial numbers of the live fire particles, in ``particles()``'s
        order: a particle keeps its number for its life, where its row moves as others die."""
        return self._sim.particle_ids()

    def set_dynamics(self, **params) -> None:
        """Change motion parameters between steps (the DYNAMICS_KEYS and ``integrator``)."""
        self._require_shell("set_dynamics")
        for key in params:
            if key not in DYNAMICS_KEYS and key != "integrator":
                raise TypeError(f"set_dynamics() got an unexpected keyword argument {key!r}")
        if "integrator" in params:
            V.choice(params["integrator"], "integrator", INTEGRATORS)
        _set_group(self._sim.set_dynamics, None, params)

    def step_stats(self) -> dict:
        """What the last step's motion did: substeps, awake vertices, CG iterations, ω bound,
        and ``substeps_by``, what set the substeps: "none" (nothing awake), "set" (the
        ``substeps`` parameter), "one" (nothing asked for more), "stability" (an explicit
        integrator's limit), "accuracy" (implicit: a spring would change by more than
        ``max_stretch`` in a substep), "contact" (a vertex near a collider) or "stretch_redo"
        (the step overstretched a spring and was redone with more; docs/dynamics.md §4)."""
        self._require_shell("step_stats")
        return dict(self._sim.step_stats())

    def phase_seconds(self) -> dict:
        """Wall-clock seconds spent in each phase of the steps and ``vertex_positions`` calls
        since the simulation was built: ``fire_front``, ``cells``, ``sources``, ``particles``,
        ``heat``, ``dynamics``, ``mesh`` (a profile; benchmarks/bench_film.py, docs/bench.md)."""
        return dict(self._sim.phase_seconds())

    def _require_shell(self, what: str) -> int:
        if not self._sim.has_shell:
            raise ValueError(f"{what}: this simulation was made with shell=False")
        return self._sim.lattice_size

    def _cell_shape(self, *tail) -> tuple:
        n = self.cells
        return (n, n, *tail) if self.geometry == "plane" else (self.num_cells, *tail)

    # --- results -------------------------------------------------------------------------
    @property
    def geometry(self) -> str:
        """"plane" (the N×N grid) or "surface" (cells on the surface), as chosen."""
        return self._sim.geometry

    @property
    def cells(self) -> int:
        """N: the sheet has N×N cells (on a surface: about N² cells, see num_cells)."""
        return self._sim.cells

    @property
    def num_cells(self) -> int:
        """Number of cells (N² on the grid)."""
        return self._sim.num_cells

    @property
    def cell_spacing(self) -> float:
        """Distance between neighbouring cells, m (on the grid sqrt(du dv))."""
        return self._sim.cell_spacing

    def cell_areas(self) -> np.ndarray:
        """Area of each cell, m² (per-cell shape)."""
        return self._sim.cell_areas()

    def cell_normals(self) -> np.ndarray:
        """Unit normal of each cell now (per-cell shape, then 3)."""
        return self._sim.cell_normals().reshape(self._cell_shape(3))

    def cell_speed(self, cell) -> float:
        """Eq 1's spread speed at a cell now, m/s; cell is a flat index (row * N + col on the grid)."""
        c = V.integer(cell, "cell", low=0, high=self.num_cells - 1)
        return self._sim.cell_speed(c)

    @property
    def cell_size(self) -> tuple:
        """(dv, du): a cell's size along rows and columns, metres."""
        return tuple(self._sim.cell_size)

    def inside(self) -> np.ndarray:
        """(N, N) uint8: 1 where the cell is part of the sheet."""
        return self._sim.inside()

    def cell_temperature(self) -> np.ndarray:
        """Per cell, K above ambient from the fire particles (heat_ignites; zeros otherwise)."""
        return self._sim.cell_temperature()

    def firebreaks(self) -> np.ndarray:
        """(N, N) bool, (num_cells,) on a surface: cells that never burn (a painted 0 in
        ``speed_map`` or ``fuel_map``)."""
        return self._sim.firebreaks().astype(bool)

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
        """(N, N) bool: burning cells with a neighbour neither burning nor burnt (paper §3.1);
        (num_cells,) on a surface."""
        mask = np.zeros(self.num_cells, dtype=bool)
        mask[np.asarray(self._sim.fringe(), dtype=np.int64)] = True
        return mask.reshape(self._cell_shape())

    def cell_positions(self) -> np.ndarray:
        """(N, N, 3) current cell-centre positions; (num_cells, 3) on a surface."""
        return self._sim.cell_positions().reshape(self._cell_shape(3))

    def vertex_positions(self, out=None) -> np.ndarray:
        """(n, 3) current positions of the input mesh's vertices.

        out: an (n, 3) C-contiguous float64 array to write them into (and return), reused
        from frame to frame: a fresh million-vertex array costs more than the deform
        (docs/bench.md, "film")."""
        if out is None:
            return self._sim.vertex_positions(self._threads)
        n = self.n_vertices
        if not (isinstance(out, np.ndarray) and out.dtype == np.float64 and out.shape == (n, 3)
                and out.flags.c_contiguous and out.flags.writeable):
            got = (f"{out.dtype} {out.shape}" if isinstance(out, np.ndarray) else type(out).__name__)
            raise ValueError(f"out: expected a writeable C-contiguous float64 array of shape ({n}, 3) "
                             f"(np.empty(({n}, 3))), got {got}")
        self._sim.vertex_positions_into(out, self._threads)
        return out

    def mesh_points(self, vertices, weights) -> np.ndarray:
        """(n, 3) where material points of the mesh are now: row i at rest is
        ``sum_k weights[i, k] * rest vertex vertices[i, k]`` (a point of a face or an edge, its
        weights summing to 1), mapped as the mesh's vertices are (on a curved shell's control
        surface, each point embedded as a vertex is, from its weightiest vertex's couples). A
        measure of the surface between the vertices: ``surface_lengths`` takes each edge's
        length along it (docs/lattice.md, "Creases between couples")."""
        idx = V.index_array(vertices, "vertices", (-1, -1), self.n_vertices)
        w = V.real_array(weights, "weights", idx.shape)
        if w.size and w.min() < 0.0:
            raise ValueError(f"weights: must be >= 0 (a point between its vertices), got {w.min():g}")
        if len(w) and not np.allclose(w.sum(axis=1), 1.0, rtol=0.0, atol=1e-9):
            raise ValueError("weights: each row must sum to 1 (a point between its vertices), got sums "
                             f"from {w.sum(axis=1).min():g} to {w.sum(axis=1).max():g}")
        return self._sim.mesh_points(idx, w, self._threads)

    def surface_lengths(self, edges, samples=16) -> np.ndarray:
        """(n,) each edge's length along the sheet's surface now: its rest segment between the
        vertices ``edges[i]`` in ``samples`` pieces through ``mesh_points``. Where the lattice
        creases between couples an edge across the crease is a chord, shorter than this
        (docs/lattice.md, "Creases between couples")."""
        e = V.index_array(edges, "edges", (-1, 2), self.n_vertices)
        k = V.integer(samples, "samples", low=1)
        t = np.linspace(0.0, 1.0, k + 1)
        w = np.tile(np.stack([1.0 - t, t], 1), (len(e), 1))
        p = self.mesh_points(np.repeat(e, k + 1, axis=0), w).reshape(len(e), k + 1, 3)
        return np.linalg.norm(np.diff(p, axis=1), axis=2).sum(axis=1)

    @property
    def mesh_points_redone(self) -> int:
        """Mesh vertices the last ``vertex_positions`` recomputed; the others kept their
        positions from the call before, their couples having not moved (a flat sheet's
        lattice; -1 where the lattice follows a control surface or there is no shell)."""
        return int(self._sim.mesh_points_redone())

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
        """Interpolate any per-cell field ((N, N) on the grid, (num_cells,) on a surface) to the
        input vertices (bilinear over inside cells; on a surface, over the cells' triangles)."""
        f = V.real_array(field, "field", self._cell_shape())
        return self._sim.cells_to_vertices(f.ravel())

    def local_speed(self, row, col) -> tuple:
        """(v, e_row, e_col): the spread law now at a cell (eq 1 and the drive vector in grid
        axes). The grid only (geometry "plane"); cell_speed serves both."""
        if self.geometry != "plane":
            raise ValueError("local_speed: row and col exist on the grid only (geometry 'plane'); use cell_speed(cell)")
        n = self.cells
        r = V.integer(row, "row", low=0, high=n - 1)
        c = V.integer(col, "col", low=0, high=n - 1)
        return tuple(self._sim.local_speed(r * n + c))

    def stats(self) -> dict:
        """Sizes of the active sets now: what a step costs."""
        out = {"front_active": self._sim.front_active(), "burning": self._sim.num_burning(),
               "fringe": int(len(self._sim.fringe()))}
        if self._sim.has_shell:
            out.update(self._sim.step_stats())
            out["particles"] = int(len(self._sim.particles()[1]))
        return out


class ParamsView:
    """A read-only view of a Simulation's parameters: every read asks the core for the values in
    force then (a view kept across ``set_dynamics`` does not go stale); the groups (``dynamics``,
    ``bending``, ``particles``) read as read-only mappings."""

    __slots__ = ("_sim",)

    def __init__(self, core_sim):
        object.__setattr__(self, "_sim", core_sim)

    def __getattr__(self, name):
        value = getattr(self._sim.params, name)
        if callable(value):  # the core struct's setters: not part of a read-only view
            raise AttributeError(f"Simulation.params has no {name!r}; change the motion's parameters "
                                 "with sim.set_dynamics(...)")
        return MappingProxyType(value) if isinstance(value, dict) else value

    def __setattr__(self, name, value):
        raise AttributeError(f"Simulation.params is read-only ({name!r}): pass model parameters to "
                             "Simulation(...), or change the motion's with sim.set_dynamics(...)")

    def __dir__(self):
        p = self._sim.params
        return [n for n in dir(p) if not n.startswith("_") and not callable(getattr(p, n))]

    def __repr__(self):
        p = self._sim.params
        return f"ParamsView(cells={p.cells}, front={p.front!r}, dynamics={p.dynamics})"


class _Serialised:
    """One core Simulation behind a lock: calls from several Python threads run one at a time.

    The core releases the GIL while it steps, so without the lock a second thread could read
    or step a Simulation halfway through a step (which crashed). Waiting for the lock releases
    the GIL too. Many Simulations still run in parallel, one per thread.
    """

    __slots__ = ("_core", "_lock")

    def __init__(self, core):
        object.__setattr__(self, "_core", core)
        object.__setattr__(self, "_lock", threading.Lock())

    def __getattr__(self, name):
        with self._lock:
            attr = getattr(self._core, name)
        if not callable(attr):
            return attr

        def locked(*args, **kwargs):
            with self._lock:
                return attr(*args, **kwargs)
        return locked

    def __setattr__(self, name, value):
        with self._lock:
            setattr(self._core, name, value)


def _check_scale(verts: np.ndarray) -> None:
    """Refuse coordinates the model cannot simulate, naming ``vertices`` (r6)."""
    big = float(np.abs(verts).max())
    if big > MAX_COORDINATE:
        raise ValueError(f"vertices: coordinates up to {big:.3g} m; the model takes |x|, |y|, |z| <= "
                         f"{MAX_COORDINATE:g} m (scene unit = 1 m): move the sheet near the origin "
                         "or scale the scene down")
    extent = float((verts.max(axis=0) - verts.min(axis=0)).max())
    if extent < MIN_EXTENT:
        raise ValueError(f"vertices: the sheet spans only {extent:.3g} m (too small or degenerate); "
                         f"the model needs at least {MIN_EXTENT:g} m (scene unit = 1 m): scale the scene up")


def _set_group(setter, prefix, values: dict) -> None:
    """Apply a parameter group; the core's errors get the user's name for the argument
    (``particle_`` keys are named with their prefix, material fields with ``material:``)."""
    if not values:
        return
    try:
        setter(values)
    except (ValueError, TypeError) as exc:
        msg = str(exc)
        if prefix == PARTICLE_PREFIX:
            for key in values:
                if PARTICLE_PREFIX + key not in msg:
                    msg = msg.replace(key, PARTICLE_PREFIX + key)
        elif prefix == "material":
            msg = f"material: {msg}"
        raise type(exc)(msg) from None


def _vertex_map(values, name: str, n: int) -> np.ndarray:
    """A painted per-vertex map (speed_map, fuel_map): None is empty (the map is off)."""
    if values is None:
        return np.zeros(0)
    a = V.real_array(values, name, (n,), finite=False)
    bad = np.flatnonzero(~np.isfinite(a) | (a < 0))
    if len(bad):
        raise ValueError(f"{name}: values must be finite and >= 0 (0 = never burns); vertex {bad[0]} "
                         f"holds {a[bad[0]]:g}")
    return np.ascontiguousarray(a, dtype=np.float64)


def _pinned_mask(pinned, n: int) -> np.ndarray:
    """A uint8 flag per vertex from None, a boolean mask or an index array.

    The rule (r7): a bool array is a mask and must have length n; an integer array (or a list,
    or integral floats) is an index array of any length, the empty one included. An integer
    array of length n holding only 0s and 1s is refused with a ValueError: it reads as a mask
    as well as indices of vertices 0 and 1, so pass ``mask.astype(bool)`` or
    ``np.flatnonzero(mask)`` instead.
    """
    if pinned is None:
        return np.zeros(0, dtype=np.uint8)
    try:
        a = np.asarray(pinned)
    except Exception as exc:  # ragged lists and the like
        raise TypeError(f"pinned must be None, a bool mask or an index array: {exc}") from None
    if a.dtype == bool:
        if a.shape != (n,):
            raise ValueError(f"pinned has invalid shape: a boolean mask needs ({n},), got {a.shape}")
        return a.astype(np.uint8)
    if a.size == 0 and a.ndim == 1:  # [] or an empty array of any dtype: nothing pinned
        if a.dtype.kind not in "iuf":
            raise TypeError(f"pinned must be None, a bool mask or an index array, got dtype {a.dtype}")
        return np.zeros(n, dtype=np.uint8)
    idx = V.index_array(a, "pinned", (-1,), n)
    if len(idx) == n and n > 2 and np.all((idx == 0) | (idx == 1)):
        raise ValueError(f"pinned: an integer array of length n = {n} holding only 0 and 1 is "
                         "ambiguous (a 0/1 mask, or indices of vertices 0 and 1?); pass a bool "
                         "mask (pinned.astype(bool)) or the indices (np.flatnonzero(pinned))")
    mask = np.zeros(n, dtype=np.uint8)
    mask[idx] = 1
    return mask
