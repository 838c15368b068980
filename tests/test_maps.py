"""Painted maps (issue #14, direct control): speed, fuel and firebreaks per vertex, on both
geometries; cells lit from a painted map or near a mesh igniter's surface."""
import numpy as np
import pytest

import thinburn
from thinburn.scenes import rect_sheet

GEOMETRIES = ("plane", "surface")
QUIET = dict(speed_noise=0.0, duration_noise=0.0)


@pytest.fixture(scope="module")
def square():
    v, f = rect_sheet(0.2, 0.2, nx=41, ny=41)  # 5 mm between vertices
    return v, f, v[:, 0] - v[:, 0].min()


def _cells_x(sim, v):
    p = sim.cell_positions().reshape(-1, 3)
    return p[:, 0] - v[:, 0].min(), p[:, 1] - v[:, 1].min()


@pytest.mark.parametrize("geometry", GEOMETRIES)
def test_firebreak_line_stops_the_front(square, geometry):
    v, f, x = square
    speed = np.where(np.abs(x - 0.1) < 0.003, 0.0, 1.0)  # one column of vertices painted 0
    sim = thinburn.Simulation(v, f, cells=48, shell=False, geometry=geometry, speed_map=speed, **QUIET)
    assert sim.firebreaks().sum() > 0
    sim.ignite(v[np.argmin(x)], time=0.0, radius=0.01)
    sim.run(80.0, dt=0.5)  # the near side burns in 0.1 m / 3.5 mm/s = 29 s; far side never
    t = sim.ignition_times().ravel()
    px, _ = _cells_x(sim, v)
    inside = sim.inside().ravel().astype(bool)
    assert np.isfinite(t[inside & (px < 0.09)]).all()
    # Closed form: a cell behind a line of zero speed is never reached.
    assert not np.isfinite(t[inside & (px > 0.11)]).any()
    assert not np.isfinite(t[sim.firebreaks().ravel()]).any()


@pytest.mark.parametrize("geometry", GEOMETRIES)
def test_double_speed_region_halves_the_arrival_slope(square, geometry):
    v, f, x = square
    sim = thinburn.Simulation(v, f, cells=64, shell=False, geometry=geometry,
                              speed_map=np.where(x > 0.1, 2.0, 1.0), **QUIET)
    start = v[np.argmin(x + np.abs(v[:, 1] - v[:, 1].mean()))]  # middle of the left edge
    sim.ignite(start, time=0.0)
    sim.run(60.0, dt=0.5)
    t = sim.ignition_times().ravel()
    px, py = _cells_x(sim, v)
    band = np.isfinite(t) & (np.abs(py - 0.1) < 0.01)
    slow = np.polyfit(px[band & (px > 0.02) & (px < 0.09)], t[band & (px > 0.02) & (px < 0.09)], 1)[0]
    fast = np.polyfit(px[band & (px > 0.11) & (px < 0.19)], t[band & (px > 0.11) & (px < 0.19)], 1)[0]
    # Measured: ratio 1.989 (plane), 2.000 (surface); the slow side's slope 1/V0 within 1 %.
    assert slow / fast == pytest.approx(2.0, rel=0.02)
    assert slow == pytest.approx(1.0 / sim.material.v0, rel=0.02)


@pytest.mark.parametrize("geometry", GEOMETRIES)
def test_fuel_scales_burn_durations(square, geometry):
    v, f, x = square
    sim = thinburn.Simulation(v, f, cells=32, shell=False, geometry=geometry,
                              fuel_map=np.where(x > 0.1, 3.0, 1.0), **QUIET)
    d = sim.burn_durations().ravel()
    px, _ = _cells_x(sim, v)
    inside = sim.inside().ravel().astype(bool)
    base = sim.material.burn_duration
    np.testing.assert_allclose(d[inside & (px < 0.09)], base, rtol=1e-12)
    np.testing.assert_allclose(d[inside & (px > 0.11)], 3.0 * base, rtol=1e-12)
    # Fuel changes how long flames stay, not the sheet's mass.
    plain = thinburn.Simulation(v, f, cells=32, shell=False, geometry=geometry, **QUIET)
    np.testing.assert_array_equal(sim.cell_mass(), plain.cell_mass())


def test_fuel_zero_is_a_firebreak_and_ignite_lights_none_there(square):
    v, f, x = square
    sim = thinburn.Simulation(v, f, cells=32, shell=False, fuel_map=np.where(x < 0.05, 0.0, 1.0), **QUIET)
    assert sim.ignite(v[np.argmin(x)], time=0.0) == 0  # the nearest cell is a firebreak
    assert sim.ignite(v[np.argmin(x)], time=0.0, radius=0.1) > 0  # the radius reaches fuel
    sim.run(2.0, dt=0.5)
    px, _ = _cells_x(sim, v)
    assert not (sim.cell_states().ravel()[px < 0.04] > 0).any()


def test_unit_maps_are_bit_identical_to_none(square):
    v, f, _ = square
    a = thinburn.Simulation(v, f, cells=32, seed=3, speed_noise=0.2)
    b = thinburn.Simulation(v, f, cells=32, seed=3, speed_noise=0.2, speed_map=np.ones(len(v)),
                            fuel_map=np.ones(len(v)))
    for s in (a, b):
        s.ignite(v[0], time=0.0)
        s.run(1.0, dt=0.25)
    np.testing.assert_array_equal(a.vertex_positions(), b.vertex_positions())
    np.testing.assert_array_equal(a.ignition_times(), b.ignition_times())


@pytest.mark.parametrize("name", ["speed_map", "fuel_map"])
def test_bad_maps_are_named(square, name):
    v, f, _ = square
    with pytest.raises(ValueError, match=f"{name} has invalid shape"):
        thinburn.Simulation(v, f, cells=16, shell=False, **{name: np.ones(len(v) - 1)})
    for bad in (-1.0, np.nan, np.inf):
        m = np.ones(len(v))
        m[7] = bad
        with pytest.raises(ValueError, match=f"{name}: values must be finite and >= 0.*vertex 7"):
            thinburn.Simulation(v, f, cells=16, shell=False, **{name: m})
    with pytest.raises(TypeError, match=name):
        thinburn.Simulation(v, f, cells=16, shell=False, **{name: ["a"] * len(v)})


@pytest.mark.parametrize("geometry", GEOMETRIES)
def test_ignite_map_lights_the_painted_cells(square, geometry):
    v, f, x = square
    sim = thinburn.Simulation(v, f, cells=32, shell=False, geometry=geometry, **QUIET)
    lit = sim.ignite_map(np.where(x < 0.05, 1.0, 0.0), time=0.0)
    px, _ = _cells_x(sim, v)
    inside = sim.inside().ravel().astype(bool)
    # The painted quarter: every cell left of 5 mm inside the paint, none beyond it.
    sim.step(1e-6)
    t = sim.ignition_times().ravel()
    assert lit == np.count_nonzero(t == 0.0) > 0
    assert (t[inside & (px < 0.045)] == 0.0).all()
    assert not np.isfinite(t[inside & (px > 0.055)]).any()


@pytest.mark.parametrize("geometry", GEOMETRIES)
def test_ignite_near_lights_cells_within_radius_of_points(square, geometry):
    v, f, _ = square
    sim = thinburn.Simulation(v, f, cells=32, shell=False, geometry=geometry, **QUIET)
    # Points 1 cm above the sheet's middle line: radius 1.5 cm reaches cells within ~1.1 cm of it.
    ys = np.linspace(v[:, 1].min(), v[:, 1].max(), 80)
    pts = np.stack([np.full_like(ys, v[:, 0].mean()), ys, np.full_like(ys, 0.01)], axis=1)
    assert sim.ignite_near(pts + [0, 0, 1.0], radius=0.015) == 0  # a metre away: nothing
    lit = sim.ignite_near(pts, radius=0.015, time=0.0)
    sim.step(1e-6)
    t = sim.ignition_times().ravel()
    p = sim.cell_positions().reshape(-1, 3)
    dx = np.abs(p[:, 0] - v[:, 0].mean())
    inside = sim.inside().ravel().astype(bool)
    assert lit == np.count_nonzero(t == 0.0)
    assert (t[inside & (dx < 0.010)] == 0.0).all()
    assert not (t[inside & (dx > 0.0115)] == 0.0).any()


# --- finishing within a time (issue #14: "burn in N seconds") ------------------------------------
def _finish_time(sim, limit, dt=1 / 24, each=None):
    """When the fire has stopped: no cell burning, some burnt; each(sim) after every step."""
    inside = sim.inside().astype(bool)
    while sim.time < limit:
        sim.step(dt)
        if each is not None:
            each(sim)
        st = sim.cell_states()[inside]
        if (st == 2).any() and not (st == 1).any():
            return sim.time
    return np.inf


# Measured (frames of 1/24 s): a flat A4 sheet, 64 cells, finishes at 0.992, 0.992, 0.995 of
# 5, 20, 60 s; the same sheet at 48 cells curling on a table with cv = 3 (eq 1 slows its fringe
# to about 0.83 of V0, it lifts 6 cm) at 0.990 of 30 s; a lantern at 0.994 of 20 s; a sheet
# stopped by a firebreak at 0.979 of 6 s. The issue asks for 10 %; the tests allow 0.96-1.02.
def _a4():
    from thinburn import demo
    return demo.default_scene("paper")


@pytest.mark.parametrize("target", [5.0, 20.0, 60.0])
def test_finish_within_times_a_flat_sheet(target):
    sc = _a4()
    sim = thinburn.Simulation(sc.vertices, sc.faces, cells=64, shell=False, finish_within=target)
    sim.ignite(sc.ignite_at, time=0.0, radius=sc.ignite_radius)
    assert _finish_time(sim, 1.5 * target) / target == pytest.approx(0.99, abs=0.03)


def test_finish_within_holds_while_the_sheet_curls():
    sc = _a4()
    sim = thinburn.Simulation(sc.vertices, sc.faces, cells=48, floor=sc.floor, finish_within=30.0, cv=3.0)
    sim.ignite(sc.ignite_at, time=0.0, radius=sc.ignite_radius)
    lift = []
    assert _finish_time(sim, 45.0, each=lambda s: lift.append(s.vertex_positions()[:, 2].max())) / 30.0 \
        == pytest.approx(0.99, abs=0.03)
    assert max(lift) > 0.03  # it did curl (measured 7 cm at 64 cells)


def test_finish_within_on_a_lantern():
    from thinburn import demo
    sc = demo.shell_scene("lantern")
    sim = thinburn.Simulation(sc.vertices, sc.faces, cells=32, floor=sc.floor, finish_within=20.0)
    sim.ignite(sc.ignite_at, time=0.0, radius=sc.ignite_radius)
    assert _finish_time(sim, 30.0) / 20.0 == pytest.approx(0.99, abs=0.03)


def test_finish_within_stops_at_a_firebreak_and_cuts_long_burns(square):
    v, f, x = square
    sim = thinburn.Simulation(v, f, cells=40, shell=False, finish_within=6.0,
                              speed_map=np.where(np.abs(x - 0.1) < 0.003, 0.0, 1.0))
    # The material's 4 s a cell is cut to half the target, the rest is for the spread.
    assert sim.burn_durations().max() == pytest.approx(3.0, rel=1e-12)
    sim.ignite(v[np.argmin(x)], time=1.0, radius=0.01)  # the clock starts at the first ignition
    end = _finish_time(sim, 12.0)
    assert (end - 1.0) / 6.0 == pytest.approx(0.99, abs=0.03)
    px, _ = _cells_x(sim, v)
    assert not (sim.cell_states().ravel()[px > 0.11] > 0).any()


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan, np.inf])
def test_finish_within_refuses_bad_values(square, bad):
    v, f, _ = square
    with pytest.raises(ValueError, match="finish_within"):
        thinburn.Simulation(v, f, cells=16, shell=False, finish_within=bad)
