"""Simulation.set_wind_field: a wind per lattice control vertex for the sheet's motion (the
add-on evaluates Blender's force fields there, issue #14)."""
import numpy as np
import pytest

import thinburn
from thinburn.scenes import rect_sheet


def _curtain():
    v, f = rect_sheet(0.3, 0.4, nx=7, ny=9, vertical=True, z=0.1)
    top = np.flatnonzero(np.isclose(v[:, 2], v[:, 2].max()))
    return thinburn.Simulation(v, f, cells=16, material="curtain", pinned=top, lattice=4,
                               gravity=(0.0, 0.0, 0.0)), v


def _blow(sim, wind=None, field=None, steps=24):
    if wind is not None:
        sim.wind = wind
    if field is not None:
        sim.set_wind_field(field)
    for _ in range(steps):
        sim.step(1 / 24)
    return sim.vertex_positions()


def test_a_field_equal_everywhere_is_the_uniform_wind_bit_for_bit():
    a, _ = _curtain()
    b, _ = _curtain()
    shape = b.lattice_positions().shape
    uniform = _blow(a, wind=(0.0, 2.0, 0.0))
    field = _blow(b, field=np.broadcast_to([0.0, 2.0, 0.0], shape))
    assert np.array_equal(uniform, field)


def test_a_zero_field_overrides_the_uniform_wind_on_the_motion_and_none_gives_it_back():
    sim, v = _curtain()
    still = _blow(sim, wind=(0.0, 2.0, 0.0), field=np.zeros(sim.lattice_positions().shape))
    assert np.array_equal(still, v)  # without gravity or fire, only wind moves the curtain
    sim.set_wind_field(None)
    assert np.abs(_blow(sim) - v).max() > 1e-3  # the uniform 2 m/s again


def test_the_field_blows_where_it_is_set():
    sim, v = _curtain()
    lat = sim.lattice_positions()
    field = np.zeros(lat.shape)
    left = lat[..., 0] < 0.15  # half of the control vertices, by x
    field[left] = (0.0, 3.0, 0.0)
    x = _blow(sim, field=field)
    moved = np.abs(x[:, 1] - v[:, 1])
    near, far = v[:, 0] < 0.05, v[:, 0] > 0.25
    # Measured: the left edge moved 1.28x as far as the right (172 vs 134 mm; the curtain is one
    # piece, hanging from one pinned top, so the calm side is dragged along; 2.5x, 80 vs 32 mm,
    # with the lattice's own, stiffer, bending).
    assert moved[near].mean() > 1.2 * moved[far].mean()


def test_bad_wind_fields_say_what_is_expected():
    sim, _ = _curtain()
    with pytest.raises(ValueError, match="one .* per control vertex"):
        sim.set_wind_field(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="finite"):
        sim.set_wind_field(np.full(sim.lattice_positions().shape, np.nan))
    with pytest.raises(ValueError, match="exceeds"):
        sim.set_wind_field(np.full(sim.lattice_positions().shape, 1e4))
    v, f = rect_sheet(0.3, 0.4, nx=4, ny=4)
    with pytest.raises(ValueError, match="shell=False"):
        thinburn.Simulation(v, f, cells=8, shell=False).set_wind_field(None)
