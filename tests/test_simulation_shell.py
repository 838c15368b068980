"""The Simulation with its shell (paper §4): lattice, holds, mass, coupling, robustness."""
import numpy as np
import pytest

import thinburn
from thinburn.demo import build, default_scene
from thinburn.scenes import rect_sheet

QUIET = dict(speed_noise=0.0, duration_noise=0.0)


def test_lattice_shape_and_size_rule(a4):
    sim = thinburn.Simulation(*a4, cells=128)
    # N/16 + 1 = 9 couples per side (no finer than 2 cm: 0.21 m / 0.02 + 1 = 11).
    assert sim.lattice_size == 9
    assert sim.lattice_positions().shape == (9, 9, 2, 3)
    assert thinburn.Simulation(*a4, cells=32, lattice=5).lattice_positions().shape == (5, 5, 2, 3)
    with pytest.raises(ValueError, match="lattice"):
        thinburn.Simulation(*a4, lattice=1)


def test_lattice_is_draped_over_the_sheet(a4):
    sim = thinburn.Simulation(*a4, cells=32)
    L = sim.lattice_positions()
    h = sim.lattice_thickness
    assert np.allclose(L[..., 1, 2] - L[..., 0, 2], h, rtol=1e-12)
    assert np.allclose(0.5 * (L[..., 0, 2] + L[..., 1, 2]), 0.0, atol=1e-12)
    assert np.allclose(L[0, -1, 0, :2], [0.210, 0.0], atol=1e-12)   # corner couple over the corner
    assert np.allclose(L[-1, 0, 0, :2], [0.0, 0.297], atol=1e-12)


def test_rest_mesh_is_reproduced_before_any_step(a4):
    v, f = a4
    sim = thinburn.Simulation(v, f, cells=32)
    assert np.array_equal(sim.vertex_positions(), v)


def test_no_heat_and_no_gravity_means_no_motion(a4):
    v, f = a4
    sim = thinburn.Simulation(v, f, cells=32, gravity=(0.0, 0.0, 0.0))
    sim.run(1.0, dt=1 / 24)
    assert np.array_equal(sim.vertex_positions(), v)


def test_nothing_goes_through_the_floor(a4):
    v, f = a4
    sim = thinburn.Simulation(v, f, cells=32, floor=0.0)
    sim.ignite((0.0, 0.0, 0.0), radius=0.01)
    for _ in range(12 * 6):
        sim.step(1 / 12)
        assert sim.vertex_positions()[:, 2].min() >= 0.0
        assert sim.lattice_positions()[..., 2].min() >= -0.5 * sim.lattice_thickness - 1e-12


@pytest.mark.parametrize("material, bound", [("paper", 6e-4), ("silk", 0.022)])
def test_a_sheet_landing_on_its_edge_keeps_its_bottom_row(material, bound):
    """A 20 cm sheet standing upright, dropped 5 cm onto the floor: the floor holds its mesh
    (the lattice's mid-surface) at the floor, so the mesh's two bottom rows (5 mm edges) keep
    their lengths: worst over 2 s measured 0.041 % (paper) and 1.83 % (silk, soft in-plane;
    its p99 over the whole sheet 0.70 %). While every control vertex's floor lay half a lattice
    thickness below the sheet's, the standing sheet sank 5 mm into it and the mesh's clamp to
    the floor crushed those rows flat (100 %)."""
    from thinburn._mesh_measures import EdgeStrain
    v, f = rect_sheet(0.2, 0.2, nx=41, ny=41, vertical=True, z=0.05)
    sim = thinburn.Simulation(v, f, material=material, cells=32, floor=0.0)
    measure = EdgeStrain(v, f)
    e = measure.edges
    bottom = (v[e[:, 0], 2] < 0.061) & (v[e[:, 1], 2] < 0.061)
    worst = 0.0
    for _ in range(48):
        sim.step(1 / 24)
        worst = max(worst, measure(sim.vertex_positions())[bottom].max())
    assert sim.vertex_positions()[:, 2].min() < 1e-4  # it landed
    assert worst < bound


@pytest.mark.parametrize("material, median_bound", [("cloth", 0.025), ("silk", 0.025)])
def test_a_fabric_collapsing_into_a_pile_keeps_its_edge_lengths(material, median_bound):
    """A 20 cm fabric dropped upright (cells 128: 9 x 9 couples) collapses into a pile 1-3 cm
    high, its lattice folded through up to 107 degrees between couples. Where the lattice
    folds the mesh follows the couples (FoldBlend); on the B-spline alone, which cuts each
    fold's corner, one drop's p99 |l/L - 1| after 4 s was 32.0 % (cloth) and 61.9 % (silk).
    A pile is chaotic, so this takes the median over six drop heights (z0 = 5.0 .. 6.0 cm,
    `python scripts/pile_ensemble.py --sizes 0.2`). Since the strain limit and self-contact
    take turns while layers touch (docs/dynamics.md §3.4): cloth 0.65-2.98 %, median 2.13 %
    (0.66 % before, but one drop 4.77 %: its bottom row now sits at the 3 % limit in three
    drops), silk 2.27-4.91 %, median 3.17 % (7.53 % before, drops up to 14.8 %); since the
    membrane's knee (§3.4, "The knee") silk 0.42-2.91 %, median 1.86 %; since the corners'
    limit and knee (§3.4, "Corners") silk 0.45-2.40 %, median 1.54 %; since sticking floor
    contacts held beyond friction slide (docs/dynamics.md §3) silk 0.42-2.87 %, median 1.87 %,
    cloth 0.65-2.98 %, median 0.95 %. The median is itself chaotic: with the slide's threshold
    at 1, 1.5, 2 or 5 times friction instead of 3 the silk's median was 2.2, 2.3, 2.6 and
    1.9 % (drops 0.42-3.73 %). Issue #12 asks 5 % of fabrics: every drop must stay under 5.5 %."""
    from thinburn._mesh_measures import EdgeStrain
    strains = []
    for k in range(6):
        v, f = rect_sheet(0.2, 0.2, nx=41, ny=41, vertical=True, z=0.05 + 0.002 * k)
        sim = thinburn.Simulation(v, f, material=material, cells=128, floor=0.0)
        sim.run(4.0, dt=1 / 24)
        x = sim.vertex_positions()
        assert x[:, 2].max() < 0.05  # it collapsed (from 25 cm; median heights 2.8 cm cloth, 1.2 cm silk)
        strains.append(np.percentile(EdgeStrain(v, f)(x), 99))
    assert np.median(strains) < median_bound
    assert max(strains) < 0.055


def test_a_folding_fabric_is_the_same_on_one_and_two_threads():
    # The fold blend's pass over the mesh runs in parallel: each point writes its own row, so
    # a cloth folding past 40 degrees between couples (the blend whole; measured 107 by 3 s)
    # gives the same bits.
    v, f = rect_sheet(0.2, 0.2, nx=41, ny=41, vertical=True, z=0.05)
    runs = []
    for threads in (1, 2):
        sim = thinburn.Simulation(v, f, material="cloth", cells=128, floor=0.0, threads=threads)
        sim.run(3.0, dt=1 / 24)
        runs.append(sim.vertex_positions())
    assert runs[0][:, 2].max() < 0.1  # it folded down
    np.testing.assert_array_equal(runs[0], runs[1])


@pytest.mark.parametrize("pleats", [0.0, 0.01])
def test_pinned_vertices_stay_in_place(pleats):
    # Flat: the grid lattice. Pleated (1 cm, 10 cm apart): a control surface, where a pinned
    # vertex holds every couple in its window; holding only those carrying more than 5 % of it
    # let its top move 5.3 mm here.
    v, f = rect_sheet(0.5, 0.7, nx=21, ny=29, vertical=True, z=0.1)
    v[:, 1] = pleats * np.sin(2 * np.pi * v[:, 0] / 0.1)
    top = np.flatnonzero(np.isclose(v[:, 2], v[:, 2].max()))
    sim = thinburn.Simulation(v, f, cells=32, material="curtain", pinned=top)
    assert sim.geometry == ("plane" if pleats == 0 else "surface")
    sim.wind = (0.0, 2.0, 0.0)
    sim.ignite(v[5], radius=0.03)
    sim.run(3.0, dt=1 / 24)
    x = sim.vertex_positions()
    assert np.array_equal(x[top], v[top])
    assert np.abs(x - v).max() > 0.01  # the rest of it moves
    mask = np.zeros(len(v), bool)
    mask[top] = True
    same = thinburn.Simulation(v, f, cells=32, material="curtain", pinned=mask)
    same.wind = (0.0, 2.0, 0.0)
    same.ignite(v[5], radius=0.03)
    same.run(3.0, dt=1 / 24)
    assert np.array_equal(same.vertex_positions(), x)


def test_bad_holds(a4):
    v, f = a4
    with pytest.raises(ValueError, match="pinned.*out of range"):
        thinburn.Simulation(v, f, pinned=[len(v)])
    with pytest.raises(ValueError, match="pinned.*shape"):
        thinburn.Simulation(v, f, pinned=np.zeros(3, bool))
    with pytest.raises(ValueError, match="floor.*below"):
        thinburn.Simulation(v, f, floor=0.01)
    with pytest.raises(TypeError, match="floor"):
        thinburn.Simulation(v, f, floor="table")
    with pytest.raises(ValueError, match="integrator"):
        thinburn.Simulation(v, f, integrator="rk4")
    with pytest.raises(TypeError, match="shell"):
        thinburn.Simulation(v, f, shell=1)
    sim = thinburn.Simulation(v, f, cells=16, shell=False)
    with pytest.raises(ValueError, match="shell=False"):
        sim.lattice_positions()


def test_burnt_cells_lighten_the_lattice(square):
    sim = thinburn.Simulation(*square, cells=32, floor=0.0, **QUIET)
    full = sim.control_masses().sum()
    assert full == pytest.approx(sim.cell_mass().sum(), rel=1e-12)
    assert full == pytest.approx(0.2 * 0.2 * sim.material.areal_density, rel=1e-12)
    sim.ignite((0.1, 0.1, 0.0))
    sim.run(25.0, dt=0.25)
    burnt = sim.cell_states() == 2
    assert burnt.sum() > 20
    # Each burnt cell keeps ash_fraction of its mass; the couples carry exactly what the cells do.
    assert sim.control_masses().sum() == pytest.approx(sim.cell_mass().sum(), rel=1e-10)
    cell = 0.2 * 0.2 / 32**2 * sim.material.areal_density
    lost = burnt.sum() * cell * (1 - sim.material.ash_fraction)
    assert full - sim.control_masses().sum() == pytest.approx(lost, rel=1e-9)


def test_burnt_sheet_keeps_ash_strength_of_the_lattice_stiffness(square):
    sim = thinburn.Simulation(*square, cells=32, lattice=5, floor=0.0, ash_strength=0.25, **QUIET)
    assert np.array_equal(sim.control_strength(), np.ones((5, 5, 2)))
    sim.ignite((0.1, 0.1, 0.0), radius=0.3)  # every cell at once
    sim.run(sim.burn_durations().max() + 0.5, dt=0.25)
    assert (sim.cell_states() == 2).all()
    # Every couple carries only burnt sheet now: strength = 1 - (1 - 0.25) * 1.
    np.testing.assert_allclose(sim.control_strength(), 0.25, rtol=1e-12)


def test_pyrolysis_does_not_depend_on_the_grid(a4):
    # Eq 3 sums over burning cells; weighted by their share of a paper (128²) cell, the same
    # burning area gives the same field at any N (the lattice is held at 9 and flat, crumple
    # off, so the targets are the same). The lit disc's area itself differs by 8 % between the
    # grids, so the field is compared per unit burning area: measured within 0.1 % when every
    # burning cell counts (pyrolysis_range=0), within 1.6 % at the default 3 cm range, where
    # which cells of each grid fall inside the range adds its own rounding.
    for reach, bound in ((0.0, 1.005), (0.03, 1.02)):
        per_area = []
        for N in (64, 128, 256):
            sim = thinburn.Simulation(*a4, cells=N, lattice=9, floor=0.0, crumple_gain=0.0,
                                      pyrolysis_range=reach, **QUIET)
            sim.ignite((0.05, 0.05, 0.0), radius=0.02)
            sim.run(2.0, dt=1 / 24)
            burning_paper_cells = (sim.cell_states() == 1).sum() * (128 / N) ** 2
            per_area.append(sim.pyrolysis().mean() / burning_paper_cells)
        assert min(per_area) > 0
        assert max(per_area) / min(per_area) < bound


def test_wake_hold_cuts_redone_steps_on_a_held_cloth():
    # Cloth held at its corners, burning: nearly the whole lattice moves, and without the hold
    # its stragglers fall asleep and are stressed awake again, redoing steps and refactoring.
    from thinburn.demo import build, default_scene
    counts = {}
    for hold in (0, 12):
        sim = build(default_scene("cloth"), "cloth", cells=64, threads=1)
        # The lattice's own bending: the soft cloth's whole lattice keeps moving, so few vertices
        # flicker (measured 161 against 189 passes) and the hold has little to cut.
        sim.set_dynamics(wake_hold=hold, flexural_rigidity=0.0)
        passes = factorizations = 0
        for _ in range(150):
            sim.step(1 / 24)
            passes += sim.stats()["passes"]
            factorizations += sim.stats()["factorizations"]
        counts[hold] = (passes, factorizations)
    assert counts[12][0] < 0.75 * counts[0][0]  # measured 163 against 284
    assert counts[12][1] < 0.5 * counts[0][1]   # measured 17 against 135


def test_heat_reaches_the_lattice_and_bends_it(a4):
    v, f = a4
    sim = thinburn.Simulation(v, f, cells=48, floor=0.0)
    sim.ignite((0.105, 0.15, 0.0), radius=0.01)
    # 9 s: the fire (3.5 mm/s) comes within the 3 cm pyrolysis range of the couples around its
    # centre (5 cm away): the sheet moves 2.5 mm (5 um at 6 s).
    sim.run(9.0, dt=1 / 24)
    heat = sim.heat()
    assert heat.max() > 0 and np.all(np.isfinite(heat))
    # Flames sit on the upper face: the top layer gets more heat than the bottom where it burns.
    assert (heat[..., 1] - heat[..., 0]).max() > 0
    assert np.abs(sim.rotation()).max() > 0.01
    assert np.abs(sim.vertex_positions() - v).max() > 1e-3


def test_same_inputs_bit_identical_at_one_and_two_threads(a4):
    runs = []
    for threads in (1, 2, 1):
        sim = thinburn.Simulation(*a4, cells=48, floor=0.0, seed=3, threads=threads)
        sim.ignite((0.0, 0.0, 0.0), radius=0.01)
        sim.run(4.0, dt=1 / 24)
        runs.append((sim.vertex_positions(), sim.ignition_times(), sim.particles()[0]))
    for other in runs[1:]:
        for a, b in zip(runs[0], other):
            assert np.array_equal(a, b)


def test_symmetric_input_gives_symmetric_output():
    # A square lit at its centre, no noise and no particles (their births are random): the
    # pyrolysis, D and motion are mirror-symmetric about x = w/2. The lattice dynamics alone is
    # symmetric to 1e-12 (tests/test_dynamics.py); here the fire front accepts mirror cells in
    # index order within a step while the shape they read moves, so the coupled result is
    # symmetric to a stated 5 % of the motion (measured: 0.64 % of 5.5 mm). beta = 3e-4 keeps
    # the bend short of a fold: at the preset's 1e-3 this 4 x 4 lattice folds in two, and which
    # way it buckles is a bifurcation that rounding decides. 8 s: the couples nearest the centre
    # are 4.7 cm from it, and pyrolysis reaches 3 cm (at 4 s the sheet had moved 1.2 um).
    v, f = rect_sheet(0.2, 0.2, nx=21, ny=21)
    sim = thinburn.Simulation(v, f, cells=40, floor=0.0, particle_birth_rate=0.0, beta=3e-4, **QUIET)
    sim.ignite((0.1, 0.1, 0.0), radius=0.012)
    sim.run(8.0, dt=1 / 24)
    x = sim.vertex_positions()
    mirror = np.lexsort((v[:, 1], 0.2 - v[:, 0]))
    order = np.lexsort((v[:, 1], v[:, 0]))
    xm = x[mirror].copy()
    xm[:, 0] = 0.2 - xm[:, 0]
    motion = np.abs(x - v).max()
    assert motion > 1e-4
    assert np.abs(x[order] - xm).max() < 0.05 * motion


@pytest.mark.parametrize("material", sorted(thinburn.MATERIALS))
def test_every_preset_runs_ten_seconds_without_nan(material):
    sim = build(default_scene(material), material, cells=32)
    v0 = sim.vertex_positions()
    edges = _edges(default_scene(material).faces)
    rest = np.linalg.norm(v0[edges[:, 0]] - v0[edges[:, 1]], axis=1)
    worst = 0.0
    for _ in range(240):
        sim.step(1 / 24)
        x = sim.vertex_positions()
        assert np.all(np.isfinite(x))
        length = np.linalg.norm(x[edges[:, 0]] - x[edges[:, 1]], axis=1)
        worst = max(worst, float(np.max(np.abs(length / rest - 1))))
    # Mesh edges stretch or shrink by less than 60 % over the crumple (measured at cells=32:
    # paper 2.5 %, silk 10.6 %, the others under 0.2 %).
    assert worst < 0.6
    assert np.all(np.isfinite(sim.heat())) and np.all(np.isfinite(sim.particles()[0]))


def _edges(faces):
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    return np.unique(np.sort(e, axis=1), axis=0)


def test_the_crumpled_sheet_changes_the_fires_route(a4):
    # Fig. 8: deformation changes the route. The same fire on the deforming sheet and on the
    # rigid one (shell=False) burns different cells by the same time.
    v, f = a4
    times = []
    for shell in (True, False):
        sim = thinburn.Simulation(v, f, cells=48, floor=0.0, shell=shell, **QUIET)
        sim.ignite((0.0, 0.0, 0.0), radius=0.01)
        sim.run(30.0, dt=1 / 12)
        times.append(sim.ignition_times())
    lit = [np.isfinite(t) for t in times]
    assert not np.array_equal(lit[0], lit[1])


def _lift_after(material, seconds=20.0, **kw):
    v, f = rect_sheet(0.21, 0.297, nx=22, ny=31)
    sim = thinburn.Simulation(v, f, cells=48, floor=0.0, material=material, seed=1, **kw)
    sim.ignite((0.0, 0.0, 0.0), radius=0.01)
    sim.run(seconds, dt=1 / 12)
    return sim.vertex_positions()[:, 2].max()


def test_hard_paper_bends_less_than_paper():
    # Table 1: hard paper has ten times the structure stiffness and 23 times the mass (Fig. 10).
    paper, hard = _lift_after("paper"), _lift_after("hard_paper")
    assert paper > 0.01
    assert hard < 0.5 * paper


def test_a_curtain_in_wind_moves_more_than_in_still_air():
    scene = default_scene("curtain")
    moves = []
    for wind in ((0.0, 0.0, 0.0), scene.wind):
        sim = thinburn.Simulation(scene.vertices, scene.faces, material="curtain", cells=32,
                                  pinned=scene.pinned)
        sim.wind = wind
        sim.ignite(scene.ignite_at, radius=scene.ignite_radius)
        sim.run(5.0, dt=1 / 12)
        moves.append(np.abs(sim.vertex_positions() - scene.vertices)[:, 1].max())
    assert moves[1] > 2 * moves[0] and moves[1] > 0.05


def _everything(sim):
    """Every observable of a Simulation, as bytes."""
    parts = [sim.time, sim.cell_states(), sim.ignition_times(), sim.cell_char(), sim.cell_mass(),
             sim.vertex_positions(), sim.lattice_positions(), sim.heat(), sim.pyrolysis(),
             sim.rotation(), sim.control_masses(), sim.control_strength(), *sim.particles(),
             sim.particle_velocities(), sorted(sim.step_stats().items())]
    return [np.asarray(p).tobytes() for p in parts]


# From ../shared/repro/r3_failed_step_not_atomic.py: a step that raised ("needs 61268 substeps")
# had already advanced the time and the fire.
@pytest.mark.parametrize("integrator", ["symplectic", "explicit"])
def test_a_step_that_raises_leaves_the_simulation_as_it_was(integrator):
    def make():
        v, f = rect_sheet(0.21, 0.297, nx=15, ny=21)
        sim = thinburn.Simulation(v, f, cells=32, floor=0.0, integrator=integrator, seed=1)
        sim.ignite((0.0, 0.0, 0.0), time=0.0, radius=0.03)
        for _ in range(30):  # burning, moving and partly asleep by now
            sim.step(1 / 240)
        return sim
    sim, twin = make(), make()
    before = _everything(sim)
    with pytest.raises(RuntimeError, match="max_substeps"):
        sim.step(5.0)
    assert _everything(sim) == before
    # Hidden state too (sleep, holds, masses handed to the dynamics): the two go on alike.
    for _ in range(10):
        sim.step(1 / 240)
        twin.step(1 / 240)
    assert _everything(sim) == _everything(twin)


def test_params_are_a_read_only_view_of_the_live_values(a4):
    sim = thinburn.Simulation(*a4, cells=16, floor=0.0, wind_drag=1.0)
    assert sim.params.dynamics["wind_drag"] == 1.0 and sim.params.cells == 16
    sim.set_dynamics(wind_drag=2.0, integrator="symplectic")
    assert sim.params.dynamics["wind_drag"] == 2.0  # it stayed at 1.0 before issue #10/#11
    assert sim.params.dynamics["integrator"] == "symplectic"
    with pytest.raises(AttributeError, match="read-only"):
        sim.params.cells = 32
    with pytest.raises(AttributeError, match="set_dynamics"):
        sim.params.set_dynamics({"wind_drag": 3.0})
    assert "set_dynamics" not in dir(sim.params) and "cells" in dir(sim.params)


# --- large steps; and a curtain that must hang again (repro r10, issue #12) ----------------------

@pytest.mark.parametrize("dt", [1.0, 2.0, 10.0])
def test_one_big_implicit_step_stays_within_reach_of_the_pin(dt):
    # Repro r4: cloth 1 m x 2 m pinned at a corner cannot reach farther than its diagonal
    # (2.24 m); it reached 2.65 m at dt = 1 s and 9.45 m at 10 s (edges stretched ~10x, one
    # substep). An implicit step that ends with a spring strained by more than 1 % (and 1.5x
    # its start) is now redone with more substeps: measured 0.944, 1.003 and 1.016 diagonals at
    # dt = 1, 2, 10 s (198, 875, 4400 substeps; worst spring strain 2.2, 4.1, 4.4 %, where the
    # cloth's own sag sits). At dt = 1/24 s it keeps 1.000.
    v, f = rect_sheet(1.0, 2.0, nx=6, ny=11)
    sim = thinburn.Simulation(v, f, material="cloth", cells=16, pinned=[0])
    sim.step(dt)
    p = sim.vertex_positions()
    assert np.linalg.norm(p - p[0], axis=1).max() <= 1.02 * np.hypot(1.0, 2.0)
    stats = sim.step_stats()
    assert stats["stretch_redos"] >= 1 and stats["substeps"] > 1 and stats["max_strain"] < 0.05


def test_a_curtain_falls_back_below_its_pins_when_the_wind_stops():
    # Repro r10, smaller (11 x 15 vertices, 32 cells, 5 s after the wind rather than 10 s).
    # Pinned along its top edge at z = 1.45 m, the paper must hang again: its bottom edge at
    # least half the height (0.7 m) below the pins. With the layer a quarter of the couples'
    # spacing thick (8.3 cm here) its hem stood at 2.84 m; at most 1 cm thick (the default now)
    # it hangs at 0.124 m, 5 cm above its rest height.
    v, f = rect_sheet(1.0, 1.4, nx=11, ny=15, vertical=True, z=0.05)
    top = np.flatnonzero(np.isclose(v[:, 2], v[:, 2].max()))
    bot = np.flatnonzero(np.isclose(v[:, 2], v[:, 2].min()))
    sim = thinburn.Simulation(v, f, material="paper", cells=32, pinned=top)
    sim.wind = (0.0, 5.0, 0.0)
    sim.run(3.0, dt=1 / 24)
    sim.wind = (0.0, 0.0, 0.0)
    sim.run(5.0, dt=1 / 24)
    assert sim.vertex_positions()[bot, 2].mean() < 1.45 - 0.7


def _swinging_cloth(integrator, dt, T=1.0):
    """A 0.4 m cloth pinned at two corners, released flat: 1 s of swinging, no fire. With the
    lattice's own bending (flexural_rigidity=0): the preset's soft cloth flops in two, and at
    these steps its errors are still pre-asymptotic (backward Euler 202, 126, 63, 34 mm at
    1/24..1/192 s, orders 0.68, 0.98, 0.90; BDF2 0.77, 1.14, 1.93)."""
    v, f = rect_sheet(0.4, 0.4, nx=21, ny=21)
    sim = thinburn.Simulation(v, f, material="cloth", cells=32, pinned=[0, 20], threads=1, lattice=5,
                              flexural_rigidity=0.0)
    sim.set_dynamics(integrator=integrator, substeps=1, sleeping=False)
    sim.run(T, dt=dt)
    return sim.vertex_positions()


def test_both_implicit_integrators_converge_in_dt_to_one_motion():
    """The order of convergence in dt, against a dt = 1/3840 s reference. The stiff stretch
    modes (w dt >> 1) keep both below their nominal order at frame-sized steps (order
    reduction). Measured max vertex errors at dt = 1/24..1/192: backward Euler 38, 16, 5.9,
    2.1 mm (orders 1.26, 1.42, 1.48); BDF2 25, 9.2, 3.2, 1.2 mm (1.47, 1.54, 1.46)."""
    ref = _swinging_cloth("bdf2", 1 / 3840)
    dts = [1 / 24, 1 / 48, 1 / 96, 1 / 192]
    err = {i: np.array([np.abs(_swinging_cloth(i, dt) - ref).max() for dt in dts])
           for i in ("implicit", "bdf2")}
    for name, lo, hi in (("implicit", 1.15, 1.6), ("bdf2", 1.35, 1.65)):
        orders = np.log2(err[name][:-1] / err[name][1:])
        assert np.all((orders > lo) & (orders < hi)), (name, orders)
    assert np.all(err["bdf2"] < 0.75 * err["implicit"])  # measured 0.54-0.67


def test_fig9_cloth_held_at_its_corners_sinks_as_it_burns():
    """Fig. 9: the demo's 40 cm cloth held at its corners, lit in the middle, sinks once burnt
    cells have lost their mass and most of their strength. Lowest point after 8 s (the sag has
    settled) and after the whole burn (90 s): 217.8 -> 210.6 mm measured, 7.2 mm down (10.7 mm
    before the lattice's corners had a limit and a knee of their own, docs/dynamics.md §3.4
    "Corners", which hold the pinned corner cells' diagonals; 14.7 mm before the membrane's knee
    held burnt pairs at 2.4 % rather than 3 %;
    it rises 8 mm while it burns, lifted by its heat). With the lattice's own bending it sank 2.65 mm;
    with soft bending and ash as strong as it is heavy (ash_strength 0.1) it hung back at
    217.77 mm (docs/materials.md, ash_strength)."""
    scene = default_scene("cloth")
    sim = thinburn.Simulation(scene.vertices, scene.faces, material="cloth", cells=48,
                              floor=scene.floor, pinned=scene.pinned, **scene.params)
    sim.ignite(scene.vertices.mean(0), time=0.0, radius=0.01)
    sim.run(8.0, dt=1 / 24)
    before = sim.vertex_positions()[:, 2].min()
    sim.run(82.0, dt=1 / 24)
    assert np.mean(sim.vertex_char() > 0.5) == 1.0  # all burnt
    assert before - sim.vertex_positions()[:, 2].min() > 0.006


def _mesh_edges(faces):
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    return np.unique(np.sort(e, 1), axis=0).astype(np.int32)


@pytest.mark.parametrize("name, seconds", [("silk", 60.0), ("letter", 30.0)])
def test_a_curling_sheet_never_passes_through_itself(name, seconds):
    """Issue #12: no mesh edge crosses a triangle of the same sheet, checked on every frame
    (ipctk.has_intersections). Silk burning on its table (the issue's case: 27 crossing edges at
    one frame) and the folded letter, whose halves lie close. Measured: no frame with a
    crossing in 240 s of every demo scene at 64 cells (paper, cloth, hard paper, silk,
    curtain, lantern, sphere, letter), before there was a self-collision response. With it on
    (the default, docs/dynamics.md §3.3) this checks the demo's own motion end to end;
    tests/test_self_contact.py checks a sheet thrown onto itself."""
    ipctk = pytest.importorskip("ipctk")
    from thinburn.demo import shell_scene
    scene = default_scene(name) if name == "silk" else shell_scene(name)
    sim = build(scene, "silk" if name == "silk" else "paper", cells=48)
    faces = np.asfortranarray(scene.faces.astype(np.int32))
    mesh = ipctk.CollisionMesh(np.asfortranarray(sim.vertex_positions()),
                               np.asfortranarray(_mesh_edges(scene.faces)), faces)
    crossed = []
    for frame in range(int(seconds * 24)):
        sim.step(1 / 24)
        if ipctk.has_intersections(mesh, np.asfortranarray(sim.vertex_positions())):
            crossed.append(frame)
    assert crossed == []
    assert np.abs(sim.vertex_positions() - scene.vertices).max() > 0.005  # it did move


@pytest.mark.parametrize("wind", [None, 3.0])
def test_implicit_and_symplectic_agree_on_paper_on_its_table(wind):
    """Issue #12: the two integrators agree at dt = 1/24 s on the A4 demo (cells 64, 20 s), with
    and without a 3 m/s wind: the RMS distance between their meshes over the implicit run's RMS
    motion, measured 3.0 % and 1.9 % (the issue allows 15 %). Before friction acted before each
    symplectic substep's move (and inside the implicit solve), the symplectic sheet crept 9 mm
    and the implicit one 0.39 m across the table in the wind."""
    from benchmarks.motion import motion_run, relative_error
    rest, implicit, _ = motion_run("paper", wind, "implicit", 1 / 24, 20.0)
    _, symplectic, _ = motion_run("paper", wind, "symplectic", 1 / 24, 20.0)
    assert relative_error(symplectic, implicit, rest) < 0.045


@pytest.mark.parametrize("wind", [None, 3.0])
def test_bdf2_holds_paper_on_its_table_as_backward_euler_does(wind):
    """BDF2 and backward Euler at dt = 1/24 s on the A4 demo (cells 64, 20 s): RMS distance
    between their meshes over backward Euler's RMS motion, measured 0.19 % still and 0.40 % in a
    3 m/s wind. While a contact's state was extrapolated from its history like any vertex's,
    BDF2 lifted landed contacts off the floor and the sheet slid 0.47 m in the wind (47 times
    the motion; 9.7 % without wind)."""
    from benchmarks.motion import motion_run, relative_error
    rest, implicit, _ = motion_run("paper", wind, "implicit", 1 / 24, 20.0)
    _, bdf2, _ = motion_run("paper", wind, "bdf2", 1 / 24, 20.0)
    assert relative_error(bdf2, implicit, rest) < 0.006


def _standing_paper(height, **params):
    """A square paper sheet standing in the xz-plane, pinned along its bottom edge (lattice 9);
    its top edge's vertices; Greenhill's l_c for it, (7.837 B / q)^(1/3) (B: its flexural
    rigidity per width, q: its weight per area); the bow it starts with (docs/dynamics.md §1.2).
    scripts/greenhill.py holds the same scene."""
    v, f = rect_sheet(height, height, nx=19, ny=19, vertical=True)
    bottom = np.flatnonzero(v[:, 2] == v[:, 2].min())
    top = np.flatnonzero(v[:, 2] == v[:, 2].max())
    sim = thinburn.Simulation(v, f, material="paper", cells=32, lattice=9, pinned=bottom, **params)
    q = sim.control_masses().sum() * 9.81 / height ** 2
    lc = (7.837 * sim.bending_share * sim.lattice_rigidity / q) ** (1.0 / 3.0)
    bow = sim.params.imperfection * np.sqrt(2.0) * height
    return sim, v[top], top, lc, bow


@pytest.mark.parametrize("over_lc, falls", [(0.95, False), (1.05, True)])
def test_a_sheet_pinned_along_its_bottom_falls_when_taller_than_greenhills_column(over_lc, falls):
    """Greenhill: a column clamped at its base buckles under its own weight beyond
    l_c = (7.837 B / q)^(1/3). The bisection in scripts/greenhill.py finds the sheet starting to
    fall at 0.997 l_c on this lattice (0.919, 1.033, 1.004 at lattices 5, 17, 33); here 5 % on
    either side. 'Fallen': the top edge 16 s later more than 10 bows from where it stood (a
    fallen sheet hangs from its pins, 2 heights away)."""
    lc = _standing_paper(1.0)[3]  # l_c does not depend on the height while the layer is 1 cm thick
    sim, start, top, lc_here, bow = _standing_paper(over_lc * lc)
    assert lc_here == pytest.approx(lc, rel=1e-9)
    sim.run(16.0, dt=1 / 24)
    moved = np.linalg.norm(sim.vertex_positions()[top] - start, axis=1).mean()
    assert (moved > 10.0 * bow) == falls, (moved, bow)


def test_a_perfectly_flat_sheet_stands_in_its_plane_and_a_lying_one_keeps_its_start():
    """imperfection=0 leaves the buckling nothing to grow from: a sheet twice Greenhill's height
    stays in its plane to rounding (issue #12 measured a 1.4 m sheet 4e-19 m out of it). A sheet
    whose weight lies across its plane starts exactly as given (the bow scales with the share of
    gravity in the plane: 0)."""
    lc = _standing_paper(1.0)[3]
    sim, start, top, _, _ = _standing_paper(2.0 * lc, imperfection=0.0)
    sim.run(4.0, dt=1 / 24)
    assert np.abs(sim.vertex_positions()[:, 1]).max() < 1e-12
    v, f = rect_sheet(0.3, 0.3, nx=9, ny=9)
    lying = thinburn.Simulation(v, f, material="paper", cells=16, imperfection=0.1)
    assert np.array_equal(lying.vertex_positions(), v)


def test_lattice_awake_shows_which_control_vertices_the_next_step_integrates(square):
    # A sheet left on a table settles and sleeps whole: lattice_awake goes from all True (every
    # vertex integrated) to all False, in the lattice's (M, M, 2) layout, and agrees with
    # step_stats' count.
    v, f = square
    sim = thinburn.Simulation(v, f, cells=32, floor=0.0)
    M = sim.lattice_size
    awake = sim.lattice_awake()
    assert awake.shape == (M, M, 2) and awake.dtype == bool and awake.all()
    for _ in range(48):
        sim.step(1 / 24)
        if not sim.lattice_awake().any():
            break
    assert not sim.lattice_awake().any()
    sim.step(1 / 24)
    assert sim.step_stats()["awake"] == 0


def test_particle_ids_follow_each_particle(a4):
    # Simulation.particle_ids(): a live particle's birth number, in particles()' order. Rows
    # shift as particles die (the pool compacts in order); the numbers stay with the particles:
    # unique and increasing, and those alive a step apart keep their number and stay near
    # where they were (measured: 212 of 239 survive the step, every one in a new row, the
    # farthest moved 24.7 mm; a row's particle after the step is another one).
    sim = thinburn.Simulation(*a4, cells=48, floor=0.0)
    sim.ignite((0.1, 0.15, 0.0), radius=0.02)
    sim.run(2.0, dt=1 / 24)
    ids0, (p0, _) = sim.particle_ids(), sim.particles()
    sim.step(1 / 24)
    ids1, (p1, _) = sim.particle_ids(), sim.particles()
    assert ids0.dtype == np.uint64 and len(ids0) == len(p0) > 50 and len(ids1) == len(p1)
    assert np.all(np.diff(ids0.astype(np.int64)) > 0) and np.all(np.diff(ids1.astype(np.int64)) > 0)
    both, i0, i1 = np.intersect1d(ids0, ids1, return_indices=True)
    assert len(both) > 0.5 * len(ids0) and (i0 != i1).any()  # survivors moved rows
    assert np.linalg.norm(p1[i1] - p0[i0], axis=1).max() < 0.03


@pytest.mark.parametrize("material", ["cloth", "silk"])
def test_a_large_fabric_pile_keeps_its_surface_and_creases_between_couples(material):
    """A 40 cm fabric dropped upright folds its 9 x 9 couples (5 cm apart) through up to 180
    degrees between neighbours: the lattice creases along a couple line. An edge of the mesh
    across a crease is a chord, shorter than the surface under it (a 108 degree crease takes
    41 % off an edge straddling it evenly), so the mesh's edges end up to 24 % short for cloth
    and 98-99 % for silk (p99, six drops), while the surface keeps its length: p99 of each
    edge's length along it (SurfaceStrain, 16 pieces) measured 0.69-0.79 %, median 0.70 %
    (cloth) and 0.36-2.47 %, median 0.74 % (silk; `python scripts/pile_ensemble.py --sizes 0.4`; docs/lattice.md,
    "Creases between couples"). Bounds: median 1 %, every drop 5 %; and every edge that is
    more than 1 % shorter than its surface crosses a couple line or ends on the floor, where
    the mesh is clamped."""
    from thinburn._mesh_measures import EdgeStrain, SurfaceStrain
    surface, chord = [], []
    for k in range(6):
        v, f = rect_sheet(0.4, 0.4, nx=61, ny=61, vertical=True, z=0.05 + 0.002 * k)
        sim = thinburn.Simulation(v, f, material=material, cells=128, floor=0.0)
        sim.run(4.0, dt=1 / 24)
        assert sim.vertex_positions()[:, 2].max() < 0.1  # it collapsed (from 45 cm)
        along = SurfaceStrain(v, f)
        s, c = along(sim), EdgeStrain(v, f)(sim.vertex_positions())
        surface.append(np.percentile(s, 99))
        chord.append(np.percentile(c, 99))
        # The edges' lattice coordinates at rest: a couple line is a whole number.
        rest = sim.lattice_rest_positions().mean(axis=2)
        axes = np.stack([rest[1, 0] - rest[0, 0], rest[0, 1] - rest[0, 0]], 1)
        st = np.linalg.lstsq(axes, (v - rest[0, 0]).T, rcond=None)[0].T
        a, b = st[along.edges[:, 0]], st[along.edges[:, 1]]
        crosses = np.any(np.floor(a + 1e-9) != np.floor(b + 1e-9), axis=1)
        # Or it ends on the floor, where the mesh is clamped (docs/lattice.md, folds' reason 2).
        floored = np.any(sim.vertex_positions()[along.edges, 2] <= 0.0, axis=1)
        shorter = c - s > 0.01  # strains are |l/L - 1|; both are short here
        assert np.all((crosses | floored)[shorter])
    assert np.median(surface) < 0.01
    assert max(surface) < 0.05
    assert np.median(chord) > 0.05  # the chords are what the mesh loses (measured 9.1 %, 99.4 %)


def test_mesh_points_map_points_of_the_mesh_as_its_vertices(a4):
    v, f = a4
    sim = thinburn.Simulation(v, f, cells=32)
    centroid = np.full((len(f), 3), 1 / 3)
    # At rest, a face's centroid is where it was (the map reproduces the rest mesh, above):
    # measured within 5.6e-17 m, rounding.
    np.testing.assert_allclose(sim.mesh_points(f, centroid), v[f].mean(axis=1), rtol=0, atol=2e-16)
    # A free fall (19 cm in 0.5 s) moves every point alike, the lattice's embedding summing to
    # one: vertices and centroids measured within 3.4e-14 m of the first vertex's move.
    sim.run(0.5, dt=1 / 24)
    moved = sim.vertex_positions() - v
    np.testing.assert_allclose(moved, np.broadcast_to(moved[0], moved.shape), rtol=0, atol=1e-13)
    np.testing.assert_allclose(sim.mesh_points(f, centroid) - v[f].mean(axis=1),
                               np.broadcast_to(moved[0], (len(f), 3)), rtol=0, atol=1e-13)


def test_mesh_points_at_the_vertices_are_the_vertices_where_the_lattice_folds():
    # A cloth folding past 40 degrees between couples (the fold blend whole), with no mesh
    # tolerance (vertex_positions then deforms exactly): a vertex's own weight gives its row.
    v, f = rect_sheet(0.2, 0.2, nx=41, ny=41, vertical=True, z=0.05)
    sim = thinburn.Simulation(v, f, material="cloth", cells=128, floor=0.0, mesh_tolerance=0.0)
    sim.run(3.0, dt=1 / 24)
    x = sim.vertex_positions()
    assert x[:, 2].max() < 0.1  # it folded down
    idx = np.stack([np.arange(len(v)), np.roll(np.arange(len(v)), 1)], 1)
    w = np.tile([1.0, 0.0], (len(v), 1))
    np.testing.assert_array_equal(sim.mesh_points(idx, w), x)


def test_mesh_points_name_what_is_wrong(a4):
    v, f = a4
    sim = thinburn.Simulation(v, f, cells=32)
    with pytest.raises(ValueError, match="weights"):
        sim.mesh_points(f, np.ones((len(f), 2)) / 2)
    with pytest.raises(ValueError, match="vertices"):
        sim.mesh_points([[0, len(v)]], [[0.5, 0.5]])
    with pytest.raises(ValueError, match="sum to 1"):
        sim.mesh_points([[0, 1]], [[0.5, 0.6]])
    with pytest.raises(ValueError, match=">= 0"):
        sim.mesh_points([[0, 1]], [[2.0, -1.0]])
    assert sim.mesh_points(np.zeros((0, 2), int), np.zeros((0, 2))).shape == (0, 3)
    # Without a shell the sheet keeps its rest shape: the weighted rest points.
    still = thinburn.Simulation(v, f, cells=32, shell=False)
    np.testing.assert_array_equal(still.mesh_points([[0, 1]], [[0.25, 0.75]]), [0.25 * v[0] + 0.75 * v[1]])


def test_mesh_points_on_a_curved_shell():
    # A lantern (a control surface): at rest an edge's pieces add up to its length (measured
    # 4.4e-16 relative); after 10 s of burning a vertex's own weight gives its row bit for bit,
    # and one piece is the chord.
    from thinburn._mesh_measures import mesh_edges
    from thinburn.scenes import lantern
    v, f = lantern()
    e = mesh_edges(f)
    rest = np.linalg.norm(v[e[:, 0]] - v[e[:, 1]], axis=1)
    sim = thinburn.Simulation(v, f, cells=64, floor=0.0)
    assert sim.geometry == "surface"
    np.testing.assert_allclose(sim.surface_lengths(e), rest, rtol=2e-15, atol=0)
    sim.ignite(v[0], radius=0.02)
    sim.run(10.0, dt=1 / 24)
    x = sim.vertex_positions()
    one_hot = np.stack([np.arange(len(v)), np.arange(len(v))], 1)
    np.testing.assert_array_equal(sim.mesh_points(one_hot, np.tile([1.0, 0.0], (len(v), 1))), x)
    np.testing.assert_array_equal(sim.surface_lengths(e, samples=1), np.linalg.norm(x[e[:, 0]] - x[e[:, 1]], axis=1))


def test_surface_lengths_are_chords_in_one_piece_and_rest_lengths_in_a_fall(a4):
    from thinburn._mesh_measures import mesh_edges
    v, f = a4
    e = mesh_edges(f)
    sim = thinburn.Simulation(v, f, cells=32)
    sim.run(0.5, dt=1 / 24)
    x = sim.vertex_positions()
    chords = np.linalg.norm(x[e[:, 0]] - x[e[:, 1]], axis=1)
    # One piece is the chord: the same map at the same points (measured 0 difference).
    np.testing.assert_array_equal(sim.surface_lengths(e, samples=1), chords)
    # A free fall does not bend the sheet: 16 pieces add up to the rest length (measured
    # within 5.6e-15 relative: 5.6e-17 m on a 1 cm edge, rounding).
    rest = np.linalg.norm(v[e[:, 0]] - v[e[:, 1]], axis=1)
    np.testing.assert_allclose(sim.surface_lengths(e), rest, rtol=1e-14, atol=0)
    with pytest.raises(ValueError, match="samples"):
        sim.surface_lengths(e, samples=0)
    with pytest.raises(ValueError, match="edges"):
        sim.surface_lengths(f)


def test_step_stats_say_what_set_the_substeps(a4):
    """Issue #12: substeps where accuracy needs them, and step_stats() says why."""
    def stats(sim, steps=1, dt=1 / 24):
        out = []
        for _ in range(steps):
            sim.step(dt)
            s = sim.step_stats()
            out.append((s["substeps_by"], s["substeps"]))
        return out

    v, f = a4
    # A sheet on its floor: one substep, then it sleeps and none.
    assert stats(thinburn.Simulation(v, f, cells=32, floor=0.0), 3) == [("one", 1), ("none", 0), ("none", 0)]
    assert stats(thinburn.Simulation(v, f, cells=32, substeps=3)) == [("set", 3)]
    by, n = stats(thinburn.Simulation(v, f, cells=32, integrator="symplectic"))[0]
    assert by == "stability" and n > 1  # measured 190
    # Repro r4's cloth pinned at a corner: from rest one substep; once it swings, a spring
    # would change by more than max_stretch in one (measured 71 substeps).
    cloth_v, cloth_f = rect_sheet(1.0, 2.0, nx=6, ny=11)
    pin = np.zeros(len(cloth_v), bool)
    pin[0] = True
    swing = thinburn.Simulation(cloth_v, cloth_f, material="cloth", cells=32, pinned=pin, max_stretch=1e-3)
    first, second = stats(swing, 2)
    assert first == ("one", 1) and second[0] == "accuracy" and second[1] > 1
    # One 2 s step from rest overstretches and is redone (measured 3198 substeps).
    big = thinburn.Simulation(cloth_v, cloth_f, material="cloth", cells=32, pinned=pin)
    by, n = stats(big, dt=2.0)[0]
    assert by == "stretch_redo" and n > 1 and big.step_stats()["stretch_redos"] > 0
    # A cloth falling onto a sphere: steps near it take the contacts' substeps.
    drop_v, drop_f = rect_sheet(0.4, 0.4, nx=21, ny=21, z=0.5)
    drop_v[:, :2] -= 0.2
    drop = thinburn.Simulation(drop_v, drop_f, material="cloth", cells=32)
    drop.set_colliders(spheres=[dict(centre=(0.0, 0.0, 0.2), radius=0.1)])
    assert any(by == "contact" and n > 1 for by, n in stats(drop, 24))


def test_contact_rounds_keep_a_silk_pile_within_its_strain_limit():
    # docs/dynamics.md §3.4, "Turns with self-contact": one 20 cm silk drop (the second of
    # pile_ensemble.py's six). Without the membrane's knee (k_limit=0), self-contact once and
    # last (contact_rounds=0, the build before) leaves its mesh edges 13.7 % short (p99); with
    # the default turns 2.79 %. With the knee the pile lands otherwise, and both orders hold it:
    # measured 0.88 % (no turns) and 1.58 % (default). (The test took the third drop until
    # sticking floor contacts held beyond friction slid, docs/dynamics.md §3: 14.5 and 3.34 %
    # then; that drop now lands with 0.61 and 0.72 %, the second and fifth 13.7 and 14.1 %.)
    from thinburn._mesh_measures import EdgeStrain
    v, f = rect_sheet(0.2, 0.2, nx=41, ny=41, vertical=True, z=0.052)
    p99 = {}
    for rounds, k_limit in ((0, 0.0), (3, 0.0), (0, None), (3, None)):
        kw = {} if k_limit is None else dict(k_limit=k_limit)
        sim = thinburn.Simulation(v, f, material="silk", cells=128, floor=0.0, contact_rounds=rounds, **kw)
        sim.run(4.0, dt=1 / 24)
        p99[rounds, k_limit] = np.percentile(EdgeStrain(v, f)(sim.vertex_positions()), 99)
    assert p99[0, 0.0] > 0.12
    assert p99[3, 0.0] < 0.035
    assert p99[0, None] < 0.011 and p99[3, None] < 0.02
