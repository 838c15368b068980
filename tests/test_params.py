"""Where the model's parameters live (issue #11, item 5): the crumple's defaults are the core's
own, so a core Simulation built with nothing set is the Python one; and Simulation.params is a
read-only view of the values in force."""
import numpy as np
import pytest

import thinburn
from thinburn import _core

CRUMPLE_KEYS = ("max_stretch", "crumple_momentum", "bimetal", "anisotropic_curl", "crumple_gain",
                "k_structure", "k_shear", "k_flex", "c_damping", "k_transverse")


def _core_sim(vertices, faces, params):
    n = len(vertices)
    return _core.Simulation(vertices, faces, np.zeros((0, 2)), params, np.zeros(n, np.uint8),
                            np.zeros(0), np.zeros(0))


def test_a_core_simulation_with_the_core_defaults_steps_as_the_python_paper_one(a4):
    """SimulationParams()'s groups hold paper's Table 1 row and the crumple's defaults (bimetal
    curl across the front, max_stretch 1, D capped at 0.4 rad): given the fire's scalars of
    thinburn.Simulation(material="paper") (Python fills those from the Material) and nothing
    else, the core Simulation's motion, bending and particle parameters equal the Python one's
    and 24 frames of a burn give the same mesh to the last bit (one thread, same seed)."""
    v, f = a4
    py_sim = thinburn.Simulation(v, f, cells=24, floor=0.0, threads=1)
    p = _core.SimulationParams()
    for name in dir(p):
        value = getattr(py_sim.params, name, None) if not name.startswith("_") else None
        if name not in ("dynamics", "bending", "particles") and not callable(getattr(p, name)) and (
                value is not None):
            setattr(p, name, value)
    core = _core_sim(v, f, p)
    for group in ("dynamics", "bending", "particles"):
        assert getattr(core.params, group) == dict(getattr(py_sim.params, group)), group
    assert core.params.bending["max_rotation"] == 0.4
    assert {k: core.params.dynamics[k] for k in CRUMPLE_KEYS[:4]} == dict(
        max_stretch=1.0, crumple_momentum=True, bimetal=True, anisotropic_curl=True)
    for sim in (py_sim, core):
        sim.ignite((0.0, 0.0, 0.0), 0.0, 0.02)
        for _ in range(24):
            sim.step(1 / 24, 1) if sim is core else sim.step(1 / 24)
    moved = np.abs(py_sim.vertex_positions() - v).max()
    assert moved > 1e-3  # the burn curled the sheet (measured 6.6 mm), so the match means something
    np.testing.assert_array_equal(core.vertex_positions(1), py_sim.vertex_positions())


@pytest.mark.parametrize("material", sorted(thinburn.MATERIALS))
def test_a_materials_motion_follows_from_its_table_1_row(square, material):
    """set_material (the core's): transverse springs as stiff as the structure ones, crumple gain
    0.05 / K_structure (paper 1, hard paper 0.1, silk 5), exact."""
    m = thinburn.MATERIALS[material]
    d = thinburn.Simulation(*square, material=material, cells=8).params.dynamics
    assert (d["k_structure"], d["k_shear"], d["k_flex"], d["c_damping"]) == (
        m.K_structure, m.K_shear, m.K_flex, m.C_damping)
    assert d["k_transverse"] == m.K_structure
    assert d["crumple_gain"] == 0.05 / m.K_structure
    assert thinburn.Simulation(*square, material=material, cells=8, crumple_gain=0.3).params.dynamics[
        "crumple_gain"] == 0.3  # an override wins over the material's gain


def test_set_material_names_table_1s_coefficient():
    p = _core.SimulationParams()
    with pytest.raises(ValueError, match="K_structure must be > 0"):
        p.set_material(k_structure=0.0, k_shear=0.05, k_flex=0.05, c_damping=1.7)
    with pytest.raises(ValueError, match="C_damping must be >= 0"):
        p.set_material(k_structure=0.05, k_shear=0.05, k_flex=0.05, c_damping=-1.0)
    with pytest.raises(TypeError, match="K_flex must be a real number"):
        p.set_material(k_structure=0.05, k_shear=0.05, k_flex="stiff", c_damping=1.7)
    assert p.dynamics["crumple_gain"] == 1.0  # nothing was set by the failed calls


def test_a_kept_params_view_reads_the_values_in_force(a4):
    """Issue #11: a view kept across set_dynamics read the old wind_drag (a snapshot)."""
    sim = thinburn.Simulation(*a4, cells=16, floor=0.0)
    view = sim.params
    dynamics = view.dynamics
    sim.set_dynamics(wind_drag=2.0, integrator="symplectic")
    assert view.dynamics["wind_drag"] == 2.0 and view.dynamics["integrator"] == "symplectic"
    assert dynamics["wind_drag"] == 1.0  # a group read before is the group as it was then
    with pytest.raises(TypeError):
        view.dynamics["wind_drag"] = 3.0  # a group is read-only too: it could not change the model
    with pytest.raises(AttributeError, match="read-only"):
        view.cells = 32
    assert view.cells == 16 and "dynamics" in dir(view)


def test_the_floor_in_force_shows_in_the_motions_parameters(a4):
    """floor= is the Simulation's; the motion's has_floor / floor_z read it, also after a
    set_dynamics (they read False and 0 before, with a floor under the sheet)."""
    v, f = a4
    sim = thinburn.Simulation(v + [0, 0, 0.3], f, cells=16, floor=0.25)
    assert (sim.params.dynamics["has_floor"], sim.params.dynamics["floor_z"]) == (True, 0.25)
    sim.set_dynamics(wind_drag=2.0)
    assert (sim.params.dynamics["has_floor"], sim.params.dynamics["floor_z"]) == (True, 0.25)
    free = thinburn.Simulation(*a4, cells=16)
    assert free.params.dynamics["has_floor"] is False
