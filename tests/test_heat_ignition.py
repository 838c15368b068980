"""Heat ignites (issue #14, fire between objects): eq 2 at the cells lights an unburnt piece
of the mesh at its material's ignition temperature."""
import numpy as np
import pytest

import thinburn
from thinburn.materials import IGNITION_TEMPERATURE
from thinburn.scenes import rect_sheet


def _stack(gap, n=17, size=0.15):
    a, fa = rect_sheet(size, size, nx=n, ny=n, z=0.0)
    b, fb = rect_sheet(size, size, nx=n, ny=n, z=gap)
    return np.vstack([a, b]), np.vstack([fa, fb + len(a)])


def _upper_lit_at(gap, seconds, heat_ignites=True):
    v, f = _stack(gap)
    sim = thinburn.Simulation(v, f, cells=24, floor=0.0, pinned=v[:, 2] > gap / 2,
                              heat_ignites=heat_ignites, threads=1)
    sim.ignite((0.0, 0.0, 0.0), time=0.0, radius=0.008)  # the lower sheet only
    upper = sim.cell_positions()[:, 2] > gap / 2
    hottest = 0.0
    while sim.time < seconds:
        sim.step(1 / 24)
        if (sim.cell_states()[upper] > 0).any():
            return sim.time, hottest
        hottest = max(hottest, float(sim.cell_temperature()[upper].max()))
    return None, hottest


def test_a_sheet_1cm_above_a_burning_one_catches_fire():
    # Measured (scripts/heat_ignition.py, 32 cells, paper): 1 cm lights at 1.29 s, 3 cm at
    # 2.33 s, 10 cm not in 8 s (189 K at most); here at 24 cells, 1 cm at 1.17 s.
    t, _ = _upper_lit_at(0.01, 3.0)
    assert t is not None and t <= 2.5


def test_a_sheet_50cm_above_stays_unlit_and_cool():
    t, hottest = _upper_lit_at(0.5, 4.0)
    assert t is None
    # Measured 1.1 K in 4 s here (2.8 K in 8 s at 32 cells): far below paper's 213 K.
    assert hottest < 0.1 * IGNITION_TEMPERATURE["paper"]


def test_without_heat_ignition_the_gap_is_never_crossed():
    t, hottest = _upper_lit_at(0.01, 1.5, heat_ignites=False)
    assert t is None and hottest == 0.0


def test_one_sheet_burns_as_without_it():
    # Heat never lights cells on a piece already alight: a single sheet's fire is eq 1's alone.
    v, f = rect_sheet(0.1, 0.1, nx=11, ny=11)
    runs = []
    for on in (False, True):
        sim = thinburn.Simulation(v, f, cells=24, floor=0.0, heat_ignites=on, threads=1)
        sim.ignite(v[0], time=0.0)
        sim.run(1.0, dt=0.25)
        runs.append((sim.ignition_times(), sim.vertex_positions()))
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])


def test_heat_ignition_errors_name_the_argument():
    v, f = rect_sheet(0.1, 0.1, nx=5, ny=5)
    with pytest.raises(ValueError, match="heat_ignites.*shell=True"):
        thinburn.Simulation(v, f, cells=8, shell=False, heat_ignites=True)
    with pytest.raises(TypeError, match="heat_ignites must be a bool"):
        thinburn.Simulation(v, f, cells=8, heat_ignites="yes")
    with pytest.raises(ValueError, match="heat_loss"):
        thinburn.Simulation(v, f, cells=8, heat_ignites=True, heat_loss=-1.0)


def _curtain_and_candle(candle, seconds):
    """A 30 cm curtain hanging from its top edge (bottom at 10 cm) and a candle flame 1 cm wide."""
    v, f = rect_sheet(0.3, 0.3, nx=25, ny=25, vertical=True, z=0.10)
    sim = thinburn.Simulation(v, f, material="curtain", cells=32, pinned=np.isclose(v[:, 2], v[:, 2].max()),
                              heat_ignites=True, threads=1)
    sim.set_fire_sources([candle], [0.01])
    hottest = 0.0
    while sim.time < seconds:
        sim.step(1 / 24)
        if (sim.cell_states() > 0).any():
            return sim.time, hottest
        hottest = max(hottest, float(sim.cell_temperature().max()))
    return None, hottest


def test_a_candle_under_a_curtain_lights_it():
    # Measured: a candle 3 cm under the middle of the bottom edge lights it at 3.08 s; one
    # 50 cm beside it leaves it unlit and warms it by 0.7 K in 6 s (cotton: 235 K).
    t, _ = _curtain_and_candle((0.15, 0.0, 0.07), 6.0)
    assert t is not None and t < 5.0
    t, hottest = _curtain_and_candle((0.8, 0.0, 0.07), 6.0)
    assert t is None and hottest < 0.1 * IGNITION_TEMPERATURE["curtain"]


def test_fire_sources_errors_name_the_argument():
    v, f = rect_sheet(0.1, 0.1, nx=5, ny=5)
    sim = thinburn.Simulation(v, f, cells=8)
    with pytest.raises(ValueError, match="widths"):
        sim.set_fire_sources([(0, 0, 0)], [-1.0])
    with pytest.raises(ValueError, match="widths has invalid shape"):
        sim.set_fire_sources([(0, 0, 0)], [1.0, 2.0])
    with pytest.raises(ValueError, match="shell=True"):
        thinburn.Simulation(v, f, cells=8, shell=False).set_fire_sources([(0, 0, 0)], [0.01])
