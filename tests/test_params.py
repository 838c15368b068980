"""Where the model's parameters live (issue #11, item 5): one table per parameter struct
(cpp/param_table.hpp) feeds validation, keyword parsing, the params dicts and the Python key
lists; the crumple's defaults are the core's own, so a core Simulation built with nothing set is
the Python one; and Simulation.params is a read-only view of the values in force."""
import math

import numpy as np
import pytest

import thinburn
from thinburn import _core, bending, particles, simulation
from thinburn.params import FIELDS, GROUPS, names
from lattice_cases import grid_rest

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


# --- the tables ------------------------------------------------------------------------------
# How each group's keywords reach the core, and its params dict back: the SimulationParams'
# groups, and the parts built on their own.
def _via_simulation_params(group, kw):
    p = _core.SimulationParams()
    getattr(p, "set_" + group)(kw)
    return getattr(p, group)


def _via_part(group, kw):
    if group == "dynamics":
        return _core.LatticeDynamics(_core.FfdLattice(3, grid_rest(3, 0.03, 0.003, centred=False)), **kw).params
    if group == "particles":
        return _core.ParticleSystem(**kw).params
    return _core.Bending(1, **kw).params


def _inside(f):
    """A value other than the default that the field's bounds admit."""
    if f.kind == "flag":
        return not f.default
    if f.kind == "vector":
        return (0.25, -0.5, -3.0)
    if f.kind == "choice":
        return next(c for c in f.choices if c != f.default)
    if f.kind == "seed":
        return 2**64 - 3  # beyond int64: the whole uint64 range comes through
    lo = f.low if f.low is not None else f.default - 1.0
    hi = f.high if f.high is not None else max(lo, f.default) + 2.0
    if f.kind == "int":
        v = int(lo) + 1 if int(lo) + 1 != f.default else int(lo) + 2
        assert v <= hi
        return v
    return lo + 0.375 * (hi - lo)


PART_FIELDS = [(g, k) for g in ("dynamics", "particles", "bending") for k in FIELDS[g]]


@pytest.mark.parametrize("via", [_via_simulation_params, _via_part])
@pytest.mark.parametrize("group,key", PART_FIELDS)
def test_every_field_round_trips_from_its_keyword_to_the_params_dict(group, key, via):
    """A keyword sets its field and only it: the params dict reads the value back exactly and
    every other field keeps its default (a table entry pointing at the wrong member fails)."""
    f = FIELDS[group][key]
    value = _inside(f)
    out = via(group, {key: value})
    assert out[key] == value
    assert {k: v for k, v in out.items() if k != key} == {
        k: g.default for k, g in FIELDS[group].items() if k != key}


@pytest.mark.parametrize("key", list(FIELDS["simulation"]))
def test_every_simulation_scalar_round_trips_through_its_property(key):
    f = FIELDS["simulation"][key]
    p = _core.SimulationParams()
    assert getattr(p, key) == f.default
    setattr(p, key, _inside(f))
    assert getattr(p, key) == _inside(f)
    p.validate()
    others = {k: getattr(p, k) for k in FIELDS["simulation"] if k != key}
    assert others == {k: g.default for k, g in FIELDS["simulation"].items() if k != key}


def _edges(f):
    """(value, admitted) pairs at each finite bound: the bound itself and its neighbour outside
    (closed) or inside (open); an int's neighbour is one away, a real's the next double."""
    out = []
    for end, sign, is_open in ((f.low, -1.0, f.low_open), (f.high, 1.0, f.high_open)):
        if end is None:
            continue
        if f.kind == "int":
            out += [(int(end), True), (int(end) + int(sign), False)]
        else:
            out += [(end, not is_open), (math.nextafter(end, sign * math.inf), False) if not is_open
                    else (math.nextafter(end, -sign * math.inf), True)]
    return out


BOUNDED = [(g, k, v, ok) for g in GROUPS for k, f in FIELDS[g].items() for v, ok in _edges(f)]


def _check(group, key, value):
    if group == "simulation":
        p = _core.SimulationParams()
        setattr(p, key, value)
        p.validate()
    else:
        _via_simulation_params(group, {key: value})


@pytest.mark.parametrize("group,key,value,admitted", BOUNDED)
def test_bounds_reject_just_outside_and_accept_just_inside(group, key, value, admitted):
    if admitted:
        _check(group, key, value)
    else:
        with pytest.raises(ValueError, match=f"^{key} must be "):
            _check(group, key, value)


def test_a_bound_error_names_the_field_the_bound_and_the_value():
    with pytest.raises(ValueError, match=r"^plasticity must be in \[0, 1\], got 1.5$"):
        _via_simulation_params("dynamics", {"plasticity": 1.5})
    with pytest.raises(ValueError, match=r"^lifetime must be finite and > 0, got 0$"):
        _via_simulation_params("particles", {"lifetime": 0.0})
    with pytest.raises(ValueError, match=r"^heat_tolerance must be in \(0, 1\), got 1$"):
        _core.Bending(1, heat_tolerance=1.0)
    with pytest.raises(ValueError, match=r"^v_floor must be in \(0, 1\], got 0$"):
        p = _core.SimulationParams()
        p.v_floor = 0.0
        p.validate()


@pytest.mark.parametrize("group", ["dynamics", "particles", "bending"])
def test_an_unknown_keyword_names_itself_and_the_known_ones(group):
    first = next(iter(FIELDS[group]))
    for via in (_via_simulation_params, _via_part):
        with pytest.raises(TypeError, match=f"unexpected keyword argument 'k_bogus'.*'{first}'"):
            via(group, {"k_bogus": 1.0})


def test_the_python_key_lists_are_the_tables_names():
    """The lists are derived (thinburn.params); their contents are those the hand-kept lists
    had, and cg_velocity_tolerance, which the core took and Simulation(**params) did not."""
    assert set(simulation.DYNAMICS_KEYS) == set(FIELDS["dynamics"]) - {
        "k_structure", "k_shear", "k_flex", "c_damping", "has_floor", "floor_z", "integrator"}
    assert set(simulation.DYNAMICS_KEYS) == {
        "k_thickness", "k_transverse", "stiffness_unit", "flexural_rigidity", "buoyancy", "wind_drag",
        "friction", "slip_ratio", "self_collision", "self_distance", "contact_rounds", "strain_limit", "k_limit", "crumple_gain", "plasticity",
        "crumple_momentum",
        "bimetal", "anisotropic_curl", "sleep_speed", "sleeping", "substeps", "max_substeps", "safety",
        "max_stretch", "cg_tolerance", "cg_max_iterations", "gravity", "preconditioner",
        "ldlt_max_vertices", "refactor_iterations", "wake_hold", "cg_velocity_tolerance"}
    assert simulation.BENDING_KEYS == names("bending", exclude=("cp",))
    assert bending.KEYS == tuple(_core.Bending(1).params) == tuple(FIELDS["bending"])
    assert simulation.PARTICLE_KEYS + ("seed",) == tuple(_core.ParticleSystem().params)
    assert set(simulation._PARAM_BOUNDS) == {
        "cv", "v_floor", "speed_noise", "duration_noise", "climb", "wind_spread", "max_drive",
        "ash_fraction", "ash_strength", "ignition_gain", "heat_loss", "mesh_tolerance", "imperfection",
        "crease_angle"}
    assert simulation._PARAM_BOUNDS["ignition_gain"] == dict(low=0.0, high=None, low_open=True, high_open=False)
    assert simulation.MAX_LATTICE == 129
    assert set(simulation.INTEGRATORS) == set(FIELDS["dynamics"]["integrator"].choices)
    assert set(particles._REAL_RANGES) == set(particles.DEFAULTS) - {"capacity", "seed"}
    for group in ("dynamics", "particles", "bending"):
        assert tuple(_via_simulation_params(group, {})) == names(group)
    with pytest.raises(KeyError, match="no fields"):
        names("bending", exclude=("heat_fst",))


def test_cg_velocity_tolerance_is_a_simulation_keyword(square):
    sim = thinburn.Simulation(*square, cells=8, cg_velocity_tolerance=1e-6)
    assert sim.params.dynamics["cg_velocity_tolerance"] == 1e-6


def test_a_choice_takes_its_python_enum_and_names_its_values():
    p = _core.SimulationParams()
    p.set_dynamics({"integrator": _core.Integrator.Bdf2, "preconditioner": "jacobi"})
    assert (p.dynamics["integrator"], p.dynamics["preconditioner"]) == ("bdf2", "jacobi")
    with pytest.raises(ValueError, match="^integrator must be 'explicit', 'symplectic', 'implicit' or 'bdf2', got 'rk4'"):
        p.set_dynamics({"integrator": "rk4"})
    with pytest.raises(TypeError, match="^preconditioner must be a str .* or Preconditioner, got Integrator"):
        p.set_dynamics({"preconditioner": _core.Integrator.Bdf2})
