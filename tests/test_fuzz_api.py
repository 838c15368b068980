"""Property-based fuzzing of the Python API: random meshes, parameters and bad inputs give
results or clear errors (ValueError / TypeError naming an argument), never a crash or a NaN."""
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import thinburn
from thinburn.scenes import rect_sheet

SETTINGS = settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@st.composite
def meshes(draw):
    nx = draw(st.integers(2, 9))
    ny = draw(st.integers(2, 9))
    w = draw(st.floats(0.01, 3.0))
    h = draw(st.floats(0.01, 3.0))
    v, f = rect_sheet(w, h, nx=nx, ny=ny, vertical=draw(st.booleans()))
    bump = draw(st.floats(0.0, 0.3))
    seed = draw(st.integers(0, 2**16))
    rng = np.random.default_rng(seed)
    v = v + bump * min(w, h) * rng.uniform(-0.5, 0.5, v.shape)
    angle = draw(st.floats(0, 2 * np.pi))
    c, s = np.cos(angle), np.sin(angle)
    v = v @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T
    return v, f


@SETTINGS
@given(mesh=meshes(), cells=st.integers(4, 24), material=st.sampled_from(sorted(thinburn.MATERIALS)),
       front=st.sampled_from(thinburn.FRONT_METHODS), shell=st.booleans(),
       steps=st.integers(1, 6), dt=st.floats(1e-3, 2.0), seed=st.integers(0, 1000))
def test_random_scenes_give_finite_results(mesh, cells, material, front, shell, steps, dt, seed):
    v, f = mesh
    try:
        sim = thinburn.Simulation(v, f, cells=cells, material=material, front=front, shell=shell,
                                  seed=seed, threads=1)
    except ValueError as exc:  # a degenerate random mesh is refused by name
        assert any(name in str(exc) for name in ("vertices", "faces", "uv"))
        return
    sim.ignite(v[len(v) // 2], radius=0.0)
    for _ in range(steps):
        sim.step(dt)
    assert np.all(np.isfinite(sim.vertex_positions()))
    from thinburn._mesh_measures import mesh_edges
    assert np.all(np.isfinite(sim.surface_lengths(mesh_edges(f), samples=2)))
    char = sim.vertex_char()
    assert np.all((char >= 0) & (char <= 1))
    states = sim.cell_states()
    assert set(np.unique(states)) <= {0, 1, 2}
    t = sim.ignition_times()
    assert not np.any(np.isnan(t))
    assert np.all(t[np.isfinite(t)] <= sim.time + 1e-9)
    if shell:
        assert np.all(np.isfinite(sim.lattice_positions()))
        assert np.all(np.isfinite(sim.heat()))


BAD_VALUES = st.one_of(
    st.just(np.nan), st.just(np.inf), st.just(-np.inf), st.just("x"), st.just(None),
    st.just([1.0, 2.0]), st.just(-1.0), st.just(0.0), st.just(True),
)


@SETTINGS
@given(bad=BAD_VALUES, which=st.sampled_from(["dt", "point", "radius", "wind", "time", "cells", "seed"]))
def test_bad_inputs_raise_clear_errors(bad, which):
    v, f = rect_sheet(0.2, 0.2, nx=4, ny=4)
    sim = thinburn.Simulation(v, f, cells=8, shell=False)
    calls = {
        "dt": lambda: sim.step(bad),
        "point": lambda: sim.ignite(bad),
        "radius": lambda: sim.ignite((0.1, 0.1, 0.0), radius=bad),
        "wind": lambda: setattr(sim, "wind", bad),
        "time": lambda: sim.ignite((0.1, 0.1, 0.0), time=bad),
        "cells": lambda: thinburn.Simulation(v, f, cells=bad),
        "seed": lambda: thinburn.Simulation(v, f, seed=bad),
    }
    try:
        calls[which]()
    except (ValueError, TypeError) as exc:
        assert which in str(exc) or which.rstrip("s") in str(exc)
        return
    # Some values are legal for some arguments (e.g. radius 0, time 0): then nothing broke.
    sim.step(0.5)
    assert np.all(np.isfinite(sim.vertex_positions()))


@SETTINGS
@given(shape=st.sampled_from([(0, 3), (5, 2), (5, 4), (3,), (2, 3, 3)]),
       fill=st.sampled_from([0.0, np.nan, np.inf]))
def test_bad_vertex_arrays_raise_value_errors(shape, fill):
    f = np.array([[0, 1, 2]])
    with pytest.raises((ValueError, TypeError), match="vertices|faces"):
        thinburn.Simulation(np.full(shape, fill), f)


# --- the model's keywords and the set_* calls (repro r6) -----------------------------------------

from hypothesis.stateful import RuleBasedStateMachine, invariant, rule  # noqa: E402

from thinburn import _core  # noqa: E402
from thinburn.simulation import BENDING_KEYS, DYNAMICS_KEYS, PARTICLE_KEYS, PARTICLE_PREFIX  # noqa: E402

FIRE_KEYS = ("cv", "v_floor", "speed_noise", "duration_noise", "climb", "wind_spread", "max_drive",
             "ash_fraction", "ash_strength")
MODEL_KEYS = FIRE_KEYS + DYNAMICS_KEYS + BENDING_KEYS + tuple(PARTICLE_PREFIX + k for k in PARTICLE_KEYS)

# Values of every kind: good ones for some keys, bad for others. Integers stay small or are
# plainly out of a C int (a good particle_capacity near 1e8 would allocate gigabytes).
ANY_VALUE = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(-3.0, 3.0),
    st.integers(-3, 40),
    st.sampled_from([2**31, 2**40, -2**31 - 1, 2**63, 2**64, 10**30, 10**400]),
    st.booleans(),
    st.sampled_from([np.bool_(True), np.int64(3), np.int8(-1), np.float32(0.5), np.float64(np.nan),
                     np.uint64(7), 1 + 2j, np.zeros(3), np.zeros(2), np.zeros((3, 1))]),
    st.text(max_size=3),
    st.none(),
    st.lists(st.floats(-10.0, 10.0), min_size=0, max_size=4),
    st.tuples(st.floats(allow_nan=True), st.floats(-1, 1), st.floats(-10, 1)),
    st.just({"x": 1}),
    st.sampled_from(["implicit", "explicit", "symplectic", "auto", "ldlt", "jacobi"]),
)
TINY = rect_sheet(0.2, 0.25, nx=4, ny=5)


def _named_error(exc, keys):
    """A TypeError/ValueError whose message names one of the keys, never pybind's cast error."""
    assert isinstance(exc, (TypeError, ValueError)), repr(exc)
    msg = str(exc)
    assert "Unable to cast" not in msg and "incompatible" not in msg, msg
    assert any(k in msg for k in keys), (keys, msg)


@SETTINGS
@given(params=st.dictionaries(st.sampled_from(MODEL_KEYS), ANY_VALUE, min_size=1, max_size=4))
def test_random_model_keywords_give_a_simulation_or_a_named_error(params):
    try:
        sim = thinburn.Simulation(*TINY, cells=6, threads=1, **params)
    except Exception as exc:  # noqa: BLE001 - the assertion is on its type and message
        _named_error(exc, list(params))
        return
    d = sim.params.dynamics
    assert np.all(np.isfinite(d["gravity"])) and sim.params.particles["capacity"] >= 1
    assert np.all(np.isfinite(sim.vertex_positions()))


def _lattice_dynamics():
    from thinburn.lattice import flat_rest
    return _core.LatticeDynamics(_core.FfdLattice(3, flat_rest(3, 0.1, 0.1, 0.01)))


DYN_PART_KEYS = DYNAMICS_KEYS + ("k_structure", "k_shear", "k_flex", "c_damping", "floor_z", "has_floor",
                                 "integrator", "cg_velocity_tolerance")


@SETTINGS
@given(params=st.dictionaries(st.sampled_from(DYN_PART_KEYS), ANY_VALUE, min_size=1, max_size=3),
       group=st.sampled_from(["LatticeDynamics", "set_params", "set_dynamics", "set_particles", "set_bending"]))
def test_random_set_calls_take_the_value_or_name_the_key(params, group):
    if group == "set_particles":
        params = {k: v for k, v in zip(PARTICLE_KEYS, params.values())}
    elif group == "set_bending":
        params = {k: v for k, v in zip(BENDING_KEYS + ("cp",), params.values())}
    dyn = _lattice_dynamics()
    sp = _core.SimulationParams()
    calls = {
        "LatticeDynamics": lambda: _core.LatticeDynamics(_core.FfdLattice(3, np.zeros((18, 3)) + np.arange(18)[:, None]), **params),
        "set_params": lambda: dyn.set_params(**params),
        "set_dynamics": lambda: sp.set_dynamics(params),
        "set_particles": lambda: sp.set_particles(params),
        "set_bending": lambda: sp.set_bending(params),
    }
    before = (dyn.params, sp.dynamics, sp.particles, sp.bending)
    try:
        calls[group]()
    except Exception as exc:  # noqa: BLE001
        _named_error(exc, list(params) + ["ct and cp"])
        if group == "set_params":
            assert dyn.params == before[0]  # a refused change leaves the parameters as they were
        return
    for d in (dyn.params, sp.dynamics, sp.particles, sp.bending):
        for v in d.values():
            if isinstance(v, float):
                assert np.isfinite(v)


GOOD_DYNAMICS = st.one_of(
    st.tuples(st.sampled_from(["buoyancy", "wind_drag", "friction", "crumple_gain", "k_thickness", "k_transverse"]),
              st.floats(0.0, 5.0)),
    st.tuples(st.sampled_from(["plasticity", "max_stretch", "safety"]), st.floats(0.05, 1.0)),
    st.tuples(st.sampled_from(["substeps", "wake_hold", "refactor_iterations"]), st.integers(0, 4)),
    st.tuples(st.sampled_from(["sleeping", "bimetal", "crumple_momentum"]), st.booleans()),
    st.tuples(st.just("gravity"), st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-12, 0))),
    st.tuples(st.just("preconditioner"), st.sampled_from(["auto", "ldlt", "jacobi"])),
    st.tuples(st.just("integrator"), st.just("implicit")),
)
BAD_DYNAMICS = st.tuples(st.sampled_from(DYNAMICS_KEYS), st.sampled_from(
    ["x", None, np.nan, np.inf, 2**40, 1 + 2j, [1.0], {"a": 1}, -1e308]))


class SimulationMachine(RuleBasedStateMachine):
    """Construct, ignite, step, change the motion and the wind, read the results: every call
    either works or raises a named TypeError/ValueError, and results stay finite."""

    def __init__(self):
        super().__init__()
        self.sim = thinburn.Simulation(*TINY, cells=6, threads=1, seed=1)

    def _call(self, names, fn):
        try:
            fn()
        except Exception as exc:  # noqa: BLE001
            _named_error(exc, names)

    @rule(point=st.one_of(st.tuples(st.floats(-0.05, 0.25), st.floats(-0.05, 0.3), st.floats(-0.02, 0.02)),
                          st.sampled_from([(np.nan, 0, 0), (1e9, 0, 0), "here", (0.1, 0.1)])),
          radius=st.one_of(st.floats(0.0, 0.1), st.sampled_from([-1.0, np.inf, "r"])))
    def ignite(self, point, radius):
        self._call(["point", "radius"], lambda: self.sim.ignite(point, radius=radius))

    @rule(dt=st.one_of(st.floats(1e-3, 0.5), st.sampled_from([0.0, -1.0, np.nan, np.inf, "dt", None, True])))
    def step(self, dt):
        self._call(["dt"], lambda: self.sim.step(dt))

    @rule(change=st.one_of(GOOD_DYNAMICS, BAD_DYNAMICS))
    def set_dynamics(self, change):
        key, value = change
        self._call([key], lambda: self.sim.set_dynamics(**{key: value}))

    @rule(wind=st.one_of(st.tuples(st.floats(-5, 5), st.floats(-5, 5), st.floats(-2, 2)),
                         st.sampled_from([(np.nan, 0, 0), (1e150, 0, 0), 3.0, "east", (1, 2)])))
    def set_wind(self, wind):
        self._call(["wind"], lambda: setattr(self.sim, "wind", wind))

    @invariant()
    def results_are_finite_and_in_range(self):
        s = self.sim
        assert np.all(np.isfinite(s.vertex_positions()))
        assert np.all(np.isfinite(s.lattice_positions()))
        char = s.vertex_char()
        assert np.all((char >= 0.0) & (char <= 1.0))
        cc = s.cell_char()
        assert np.all((cc >= 0.0) & (cc <= 1.0))
        t = s.ignition_times()
        assert not np.any(np.isnan(t)) and np.all(t[np.isfinite(t)] <= s.time + 1e-9)
        pos, temp = s.particles()
        assert np.all(np.isfinite(pos)) and np.all(np.isfinite(temp))
        assert np.all(np.isfinite(s.wind))


SimulationMachine.TestCase.settings = settings(max_examples=20, stateful_step_count=12, deadline=None,
                                               suppress_health_check=[HealthCheck.too_slow])
test_simulation_state_machine = SimulationMachine.TestCase
