"""The shell's motion as a whole: a burning sheet bends in place; the crumple cannot move it.

Regression for the drift of a burning A4 sheet across the table (docs/dynamics.md §2, the
bimetal crumple): with the paper's prescribed chord motion (bimetal=False) the same scene's
vertex centroid moved 30 cm in 40 s at cells=48.
"""
import numpy as np
import pytest

from thinburn.demo import build, default_scene


def _burn(seconds, **params):
    scene = default_scene("paper")
    scene.params.update(params)
    if params.get("gravity") is not None:
        scene.floor = None
    sim = build(scene, "paper", cells=48)
    x0 = sim.vertex_positions()
    lat = sim.lattice_positions().reshape(-1, 3).copy()
    com = np.zeros(3)  # mass-weighted displacement of the lattice, summed step by step
    for _ in range(int(round(seconds * 24))):
        m = sim.control_masses().reshape(-1)
        m = np.maximum(m, 1e-3 * m.max())  # the mass floor the Simulation gives the dynamics
        sim.step(1 / 24)
        new = sim.lattice_positions().reshape(-1, 3).copy()
        com += (m[:, None] * (new - lat)).sum(0) / m.sum()
        lat = new
    x = sim.vertex_positions()
    return sim, x, x0, com


def test_a4_on_the_table_curls_in_place():
    # Measured (cells=48, M=4, 40 s): centroid of the vertices moved 20.2 mm horizontally
    # (-14.1, -14.5 mm, toward the lit corner), lattice centre of mass 24 mm; max z 0.125 m.
    # With the paper's crumple (bimetal=False) the centroid moved 300 mm. The rest is the air
    # drag (wind_drag, linear, 1 Pa s/m) on the rising curl rolling the curled sheet: see the
    # next test. The bound is 25 mm, not the 20 mm aimed at (a known weakness, docs/dynamics.md).
    sim, x, x0, _ = _burn(40.0)
    drift = np.linalg.norm((x - x0)[:, :2].mean(0))
    assert drift < 0.025
    assert x[:, 2].max() > 0.01
    assert np.all(np.isfinite(x))


def test_a4_on_the_table_without_air_drag_stays_within_a_centimetre():
    # Measured (40 s): centroid 6.1 mm (3.4, 5.0 mm), max z 0.125 m.
    sim, x, x0, _ = _burn(40.0, wind_drag=0.0)
    drift = np.linalg.norm((x - x0)[:, :2].mean(0))
    assert drift < 0.01
    assert x[:, 2].max() > 0.01


def test_free_sheet_centre_of_mass_stays_put():
    # No floor, no gravity, and no other external force (buoyancy, air drag): only the springs
    # act, so the centre of mass cannot move. Measured (40 s): 0.12 mm (-0.06, -0.10, 0.03 mm) with cg_tolerance=1e-10
    # (the Simulation's 1e-4 leaves ~2 mm of solver error), while the sheet curls 0.12 m.
    sim, x, x0, com = _burn(40.0, gravity=(0.0, 0.0, 0.0), buoyancy=0.0, wind_drag=0.0,
                            cg_tolerance=1e-10)
    assert np.linalg.norm(com) < 1e-3
    assert x[:, 2].max() - x[:, 2].min() > 0.01
