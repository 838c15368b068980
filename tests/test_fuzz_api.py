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
