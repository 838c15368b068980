"""The sheet's cells over its rest parameterisation (paper §3.1)."""
import numpy as np
import pytest

import thinburn
from thinburn.scenes import disk_sheet, grid_uv, rect_sheet


def test_rectangle_fills_every_cell(a4):
    sim = thinburn.Simulation(*a4, cells=32)
    assert sim.inside().all()
    dv, du = sim.cell_size
    assert du == pytest.approx(0.210 / 32, rel=1e-12)
    assert dv == pytest.approx(0.297 / 32, rel=1e-12)


def test_disk_outline_covers_its_area():
    # Fraction of the bounding square that a disk covers is pi/4; the polygonal disk
    # (48 segments) has area 48/(2 pi) sin(2 pi/48) of that; cells sample it to ~1/N.
    v, f = disk_sheet(0.1, rings=16, segments=48)
    sim = thinburn.Simulation(v, f, cells=96)
    polygon_area = 0.5 * 48 * 0.1**2 * np.sin(2 * np.pi / 48)
    frac = sim.inside().mean()
    assert frac == pytest.approx(polygon_area / 0.2**2, abs=0.02)


def test_cell_rest_positions_lie_on_a_flat_sheet(a4):
    sim = thinburn.Simulation(*a4, cells=16)
    p = sim.cell_positions()
    assert np.allclose(p[..., 2], 0.0, atol=1e-12)
    # Cell (r, c) centre sits at ((c + 1/2) du, (r + 1/2) dv) for this axis-aligned sheet.
    dv, du = sim.cell_size
    assert np.allclose(p[3, 5, :2], [5.5 * du, 3.5 * dv], atol=1e-12)


def test_uv_and_planar_projection_agree(a4):
    v, f = rect_sheet(0.210, 0.297, nx=22, ny=31)
    a = thinburn.Simulation(v, f, cells=24)
    b = thinburn.Simulation(v, f, uv=grid_uv(22, 31) * 7.0, cells=24)  # UV units are arbitrary
    assert np.allclose(a.cell_positions(), b.cell_positions(), atol=1e-9)
    assert np.allclose(a.cell_size, b.cell_size, rtol=1e-9)


def test_hanging_sheet_has_rows_growing_upward():
    v, f = rect_sheet(0.3, 0.5, nx=7, ny=11, vertical=True)
    sim = thinburn.Simulation(v, f, cells=16)
    z = sim.cell_positions()[..., 2]
    assert np.all(np.diff(z[:, 0]) > 0)


def test_vertex_values_interpolate_cells(a4):
    # A field linear in the cell centres is reproduced exactly at vertices between cell
    # centres (bilinear interpolation), and a constant field everywhere (partition of unity).
    v, f = a4
    sim = thinburn.Simulation(v, f, cells=16)
    assert np.allclose(sim.cells_to_vertices(np.full((16, 16), 2.5)), 2.5, rtol=1e-14)
    p = sim.cell_positions()
    field = 3.0 * p[..., 0] - 2.0 * p[..., 1] + 1.0
    got = sim.cells_to_vertices(field)
    dv, du = sim.cell_size
    interior = ((v[:, 0] >= 0.5 * du) & (v[:, 0] <= 0.210 - 0.5 * du)
                & (v[:, 1] >= 0.5 * dv) & (v[:, 1] <= 0.297 - 0.5 * dv))
    assert interior.sum() > 100
    assert np.allclose(got[interior], 3.0 * v[interior, 0] - 2.0 * v[interior, 1] + 1.0, atol=1e-12)


def test_cells_to_vertices_rejects_wrong_shape(a4):
    sim = thinburn.Simulation(*a4, cells=16)
    with pytest.raises(ValueError, match="field"):
        sim.cells_to_vertices(np.zeros((15, 16)))
