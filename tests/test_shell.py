"""The shell's motion as a whole: a burning sheet bends in place; the crumple cannot move it.

Regression for the drift of a burning A4 sheet across the table (docs/dynamics.md §2, the
bimetal crumple): with the paper's prescribed chord motion (bimetal=False) the same scene's
vertex centroid moved 30 cm in 40 s at cells=48.
"""
import numpy as np
import pytest

import thinburn
from thinburn._mesh_measures import EdgeStrain
from thinburn.demo import build, default_scene
from thinburn.scenes import A4, folded_sheet, rect_sheet


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
    # Measured (cells=48, M=4, 40 s): centroid of the vertices moved 0.74 mm horizontally
    # (0.54, 0.51 mm); max z 48 mm. Issue
    # #12 asks for at most 5 mm; the bound is 1.5 mm. It was 20.2 mm before static friction
    # acted inside the implicit solve (docs/dynamics.md §3), and 300 mm with the paper's chord
    # crumple (bimetal=False).
    sim, x, x0, _ = _burn(40.0)
    drift = np.linalg.norm((x - x0)[:, :2].mean(0))
    assert drift < 0.0015
    assert x[:, 2].max() > 0.01
    assert np.all(np.isfinite(x))


def test_a4_on_the_table_without_air_drag_stays_put_too():
    # Measured (40 s): centroid 0.73 mm (0.54, 0.49 mm), max z 48 mm (6.1 mm before static
    # friction inside the solve).
    sim, x, x0, _ = _burn(40.0, wind_drag=0.0)
    drift = np.linalg.norm((x - x0)[:, :2].mean(0))
    assert drift < 0.0015
    assert x[:, 2].max() > 0.01


def test_free_sheet_centre_of_mass_stays_put():
    # No floor, no gravity, and no other external force (buoyancy, air drag): only the springs
    # act, so the centre of mass cannot move. Measured (40 s): 0.12 mm (-0.06, -0.10, 0.03 mm) with cg_tolerance=1e-10
    # (the Simulation's 1e-4 leaves ~2 mm of solver error), while the sheet curls 0.12 m.
    sim, x, x0, com = _burn(40.0, gravity=(0.0, 0.0, 0.0), buoyancy=0.0, wind_drag=0.0,
                            cg_tolerance=1e-10)
    assert np.linalg.norm(com) < 1e-3
    assert x[:, 2].max() - x[:, 2].min() > 0.01


# --- shells (issue #11) and the default curl (issue #12) -------------------------------------

def _layer_position(sim, V, F, M):
    """Per vertex, where it sits across the layer of its couples now: 0 bottom, 1 top."""
    from thinburn.control_surface import ControlSurface

    cs = ControlSurface(V, F, np.sqrt(sim._sim.area) / (M - 1), sim.lattice_thickness)
    assert np.array_equal(cs.rest, sim.lattice_rest_positions())  # the Simulation's own lattice
    e = cs.embed(V)
    L = sim.lattice_positions()
    bottom = (e.weight[..., None] * L[e.couple, 0]).sum(1)
    top = (e.weight[..., None] * L[e.couple, 1]).sum(1)
    d = top - bottom
    return ((sim.vertex_positions() - bottom) * d).sum(1) / (d * d).sum(1)


def _burn_shell(V, F, src, seconds=40, **kw):
    sim = thinburn.Simulation(V, F, cells=48, **kw)
    sim.ignite(src)
    measure = EdgeStrain(V, F)
    strain, layer, rise = 0.0, [1.0, 0.0], 0.0
    for k in range(24 * seconds):
        sim.step(1 / 24)
        if k % 24 == 23:  # once a second
            P = sim.vertex_positions()
            ch = sim.vertex_char()
            strain = max(strain, np.percentile(measure.unburnt(sim), 99))
            rise = max(rise, (P[ch == 0, 2] - V[ch == 0, 2]).max())
            if sim.geometry == "surface":
                lam = _layer_position(sim, V, F, kw["lattice"])
                layer = [min(layer[0], lam.min()), max(layer[1], lam.max())]
    return sim, strain, layer, rise


@pytest.mark.parametrize("shape", ["lantern", "sphere"])
def test_a_burning_shell_crumples_without_leaving_its_layer_or_stretching(shape):
    # 40 s of burning (a quarter to a third of the shell burnt). Every vertex stays between its
    # couples' bottom and top (measured 0.509-0.531 across the layer on the lantern, 0.510-0.557
    # on the sphere), and unburnt edges keep their length: p99 of |l/L - 1| at most 0.42 % on the
    # lantern and 0.13 % on the sphere, issue #12's 1 % for paper (the sphere 0.095 % while its
    # lower half's flames and pyrolysis sat on its inside, docs/particles.md "Closed shells";
    # 0.46 % and 0.15 % before pyrolysis had a 3 cm range, docs/dynamics.md §2; 13 % and 9.3 % before the curl
    # rolled across the front; 1.63 % and 0.46 % before it kept the shell's Gaussian curvature,
    # docs/dynamics.md §2 "Curved shells": the far side's faint curl barrelled the lantern and
    # squeezed its rims; the lantern 0.63 % before its rims had couples, docs/lattice.md).
    from thinburn import _surface_shapes as S

    if shape == "lantern":
        V, F = S.cylinder(0.1, 0.3, 96, 36)
        sim, strain, layer, _ = _burn_shell(V, F, [0.1, 0.0, 0.15], floor=0.0, lattice=12)
        assert strain < 0.005
    else:
        V, F = S.icosphere(4, 0.1)
        sim, strain, layer, _ = _burn_shell(V, F, [0.1, 0.0, 0.0], pinned=np.flatnonzero(V[:, 2] > 0.098),
                                            lattice=12)
        assert strain < 0.0015
    assert sim.geometry == "surface"
    assert 0.45 < layer[0] and layer[1] < 0.6
    assert (sim.cell_states() == 2).mean() > 0.2


@pytest.mark.parametrize("turn, bound, near_bound", [(30.0, 0.002, 0.036), (150.0, 0.0065, 0.003)])
def test_a_folded_letter_burning_on_its_table_keeps_its_fold(turn, bound, near_bound):
    # The demo's letter (A4 folded across its middle by 30 degrees) and one folded back over
    # itself (150), lit at a corner of the lying half, 40 s at cells=48. Its fold is a crease
    # (docs/lattice.md, "Creases"): p99 of |l/L - 1| over unburnt edges, the most over the run,
    # measured 0.18 % and 0.57 % (within 1 cm of the fold 3.39 % and 0.27 %); with one MLS window
    # across the fold 5.39 % and 1.86 % (37.6 % and 2.99 % near it). Before the rim's corners had
    # couples (docs/lattice.md, "Rim couples") and pyrolysis a 3 cm range (docs/dynamics.md §2):
    # 0.33 % and 0.65 % (1.43 % and 0.49 %); with the corners alone 0.26 % and 0.78 % (3.15 % and
    # 0.26 %). The 30 degree letter has 10 couples at cells=48, 4 of them at its corners, and its
    # fold's 3.15 % (corners alone) was one second (at 25 s; 0.65 % at 20 s, 0.50 % at 30 s); at
    # cells=64 it was 0.46 % against 1.23 % before.
    V, F = folded_sheet(A4[0], A4[1], angle=turn, nx=43, ny=61)
    measure = EdgeStrain(V, F)
    E = measure.edges
    mid = 0.5 * (V[E[:, 0]] + V[E[:, 1]])
    near = np.hypot(mid[:, 1] - A4[1] / 2, mid[:, 2]) < 0.01
    sim = thinburn.Simulation(V, F, cells=48, floor=0.0)
    sim.ignite((0.004, 0.004, 0.0))
    strain = near_strain = 0.0
    for k in range(24 * 40):
        sim.step(1 / 24)
        if k % 24 == 23:
            strain = max(strain, np.percentile(measure.unburnt(sim), 99))
            near_strain = max(near_strain, np.percentile(measure.unburnt(sim, near), 99))
    assert sim.geometry == "surface"
    assert (sim.cell_states() == 2).mean() > 0.15
    assert strain < bound
    assert near_strain < near_bound


def test_crease_angle_chooses_which_edges_are_hinges():
    # The letter folded back over itself: its fold (150 degrees) is a crease at the default 25,
    # and the lattice fits the mesh exactly (measured 1.7e-14), as at 140; at 160 or 180 no edge is a
    # crease and brings back the one smooth window across the fold, bit for bit the build before
    # creases (fit 0.054, 52 couples against 48). Out of range names the keyword.
    V, F = folded_sheet(A4[0], A4[1], angle=150.0, nx=43, ny=61)
    creased = thinburn.Simulation(V, F, cells=48, floor=0.0)
    smooth = thinburn.Simulation(V, F, cells=48, floor=0.0, crease_angle=180.0)
    assert creased.lattice_fit < 1e-12
    assert smooth.lattice_fit > 0.01
    assert thinburn.Simulation(V, F, cells=48, floor=0.0, crease_angle=140.0).lattice_fit < 1e-12
    assert thinburn.Simulation(V, F, cells=48, floor=0.0, crease_angle=160.0).lattice_fit > 0.01
    with pytest.raises(ValueError, match="crease_angle"):
        thinburn.Simulation(V, F, cells=48, crease_angle=200.0)


def test_paper_lit_at_a_corner_curls_at_the_edge_and_stays_flat_elsewhere():
    # Issue #12's default: over 40 s the unburnt paper rises at most 1 cm above the table
    # (measured 0.88 cm; 1.08 cm before pyrolysis had a 3 cm range, docs/dynamics.md §2) and its
    # edges keep their length within 0.55 % (p99, measured 0.46 %; 0.57 % before the range;
    # 0.42 % with the trilinear embedding that kinked at control cells; 6.9 % at the old
    # defaults, which rolled the sheet into a tube). Issue #12 asks for 1 %. (How far from the
    # fire the sheet lifts: `python scripts/curl_reach.py`.)
    V, F = rect_sheet()
    sim, strain, _, rise = _burn_shell(V, F, [0.0, 0.0, 0.0], floor=0.0)
    assert sim.geometry == "plane"
    assert strain < 0.0055
    assert rise < 0.010


@pytest.mark.parametrize("reach, lit_bound, far_bound", [(0.03, (0.040, 0.055), (0.0, 0.0005)),
                                                        (0.0, (0.050, 0.065), (0.030, 0.040))])
def test_a_sheet_lit_at_a_corner_keeps_its_far_end_on_the_table(reach, lit_bound, far_bound):
    # The artists' trial: A4 paper of 61 x 61 vertices 0.5 mm above its table, lit at a corner,
    # spreading at 25 mm/s for 5 s (cells=64): "the unburnt far end curls up" 34 mm, the sheet a
    # U touching its table nowhere. Eq 3 summed every burning cell, and the curled corner's
    # cells, lifted above the sheet's plane, sat nearer every couple's top than its bottom.
    # With pyrolysis counting the cells within 3 cm (the default, docs/dynamics.md §2): the far
    # corner stays on the table (measured 0.0 mm) while the lit corner curls up 47.2 mm; counting
    # all of them (pyrolysis_range=0, the paper's reading) 34.4 mm and 57.0 mm
    # (`python scripts/curl_reach.py`).
    V, F = rect_sheet(0.21, 0.297, nx=61, ny=61, z=0.0005)
    mat = thinburn.MATERIALS["paper"].with_(V0=25.0)
    sim = thinburn.Simulation(V, F, material=mat, cells=64, floor=0.0, pyrolysis_range=reach)
    sim.ignite((0.0, 0.0, 0.0005), radius=0.02)
    sim.run(5.0, dt=1 / 24)
    X = sim.vertex_positions()
    assert lit_bound[0] < X[0, 2] < lit_bound[1]
    assert far_bound[0] <= X[-1, 2] < far_bound[1]


def test_a_closed_shell_burns_on_its_outside():
    # docs/particles.md, "Closed shells": a 10 cm paper sphere on its table lit at its bottom.
    # Its flames are born on its outside and stay there, sliding along it (measured: the nearest
    # live particle 104.3 mm from its centre at 1, 2 and 3 s; bound 100 mm, its radius). With the
    # up rule they were born on the lower half's inside, or rose up through it: 89-91 % within
    # 95 mm of its centre.
    from thinburn import _surface_shapes as S

    V, F = S.icosphere(4, 0.1)
    V = V + [0.0, 0.0, 0.1]
    sim = thinburn.Simulation(V, F, cells=64, floor=0.0)
    sim.ignite((0.0, 0.0, 0.0), radius=0.02)
    for second in range(3):
        sim.run(1.0, dt=1 / 24)
        P, _ = sim.particles()
        r = np.linalg.norm(P - sim.vertex_positions().mean(axis=0), axis=1)
        assert len(P) > 100
        assert r.min() > 0.1


def test_a_stack_of_sheets_closer_than_its_couples_keeps_each_sheet_in_its_own_lattice():
    # Three 20 cm sheets 4 mm apart in one mesh, couples about 2 cm apart: a point's nearest
    # couple may lie on the sheet above, and embedding it there tore the stack into shards
    # (edges 3.04x at 128 cells, scripts/repro_shell_motion.py). Each point now starts from a
    # couple of its own sheet: measured max edge strain 0.0031 over 3 s of a fast (40 mm/s) fire.
    from thinburn import _surface_shapes as S

    n, gap = 33, 0.004
    v0, f0 = S.sheet(n - 1, 0.2)
    V = np.vstack([v0 + [0.01 * k, 0.01 * k, 0.0005 + gap * k] for k in range(3)])
    F = np.vstack([f0 + len(v0) * k for k in range(3)])
    mat = thinburn.MATERIALS["paper"].with_(V0=40.0)
    sim = thinburn.Simulation(V, F, material=mat, cells=64, lattice=9, floor=0.0005, crumple_gain=0.3)
    sim.ignite((0.0, 0.0, 0.0045), radius=0.01)
    measure = EdgeStrain(V, F)
    worst = 0.0
    for _ in range(72):
        sim.step(1 / 24)
        worst = max(worst, measure(sim.vertex_positions()).max())
    assert sim.geometry == "surface"
    assert worst < 0.006


@pytest.mark.parametrize("material, bound", [("paper", 2.0), ("silk", 4.5)])
def test_no_lattice_facets_away_from_the_fire(material, bound):
    """Issue #12 item 2: adjacent faces of a fine mesh (edges well under a quarter of a control
    cell) away from the fire (unburnt, 3 cm from any char) meet at small angles. The demo
    scenes at 64 cells (5 x 5 couples), every 10 s for 40 s. Measured max: paper 1.35 degrees,
    silk held at its corners 3.4 (with the trilinear embedding, which kinks at the control
    cells: 10.5 and 28.6; the issue's limit is 15)."""
    from thinburn._mesh_measures import dihedral_angles, face_adjacency, far_from_fire
    scene = default_scene(material)
    sim = build(scene, material, cells=64)
    pairs = face_adjacency(scene.faces)
    worst = 0.0
    for _ in range(4):
        sim.run(10.0, dt=1 / 24)
        keep = far_from_fire(scene.vertices, scene.faces, sim.vertex_char(), 0.03)
        sel = keep[pairs[:, 0]] & keep[pairs[:, 1]]
        assert sel.sum() > 3000
        worst = max(worst, dihedral_angles(sim.vertex_positions(), scene.faces, pairs[sel]).max())
    assert np.abs(sim.vertex_positions() - scene.vertices).max() > 0.005  # it did move
    assert worst < bound


def _pleated_curtain(lattice=None, wind=0.0):
    # A half-size curtain (0.5 m x 0.7 m) with 1 cm pleats 10 cm apart, pinned along its top,
    # hanging for 2 s at 64 cells (in still air or a wind across it): the worst p99 of
    # |l/L - 1| over its mesh edges.

    v, f = rect_sheet(0.5, 0.7, nx=51, ny=71, vertical=True, z=0.05)
    v[:, 1] = 0.01 * np.sin(2 * np.pi * v[:, 0] / 0.1)
    top = np.flatnonzero(np.isclose(v[:, 2], v[:, 2].max()))
    sim = thinburn.Simulation(v, f, material="curtain", cells=64, pinned=top, lattice=lattice)
    sim.wind = (0.0, wind, 0.0)
    measure = EdgeStrain(v, f)
    worst = 0.0
    for _ in range(48):
        sim.step(1 / 24)
        worst = max(worst, np.percentile(measure(sim.vertex_positions()), 99))
    return sim, worst


def test_a_lattice_is_made_fine_enough_to_carry_the_meshs_pleats():
    """docs/lattice.md, "Detail finer than the lattice": pleats the couples cannot follow ride at
    their offset from the layer, and bending stretches them by curvature times offset. The
    chosen lattice is made finer until the mesh lies in its layer, then finer again where the
    layer, now following the pleats, turns faster than the couples can: measured 1024 couples
    (lattice_fit 0.094) and 0.15 % strain, where the grid's rule alone gave 16 couples and
    7.17 %. An explicit lattice=5 (18 couples, fit 2.56) hangs in still air within 0.80 % since
    its corners have couples (8.13 % before, fit 2.31), but in a 1.5 m/s wind across it its
    pleats stretch by 26.6 % (231 % before). (Without the second curvature pass: 284 couples,
    fit 0.19, 0.16 %; before the rim had couples: 284 couples, fit 0.45, 0.53 %; lattice=5 fit
    3.61, 5.99 %.)"""
    sim, strain = _pleated_curtain()
    assert sim.geometry == "surface"
    assert sim.lattice_couples > 900 and sim.lattice_fit <= 0.15
    assert strain < 0.002
    coarse, coarse_strain = _pleated_curtain(lattice=5, wind=1.5)
    assert coarse.lattice_couples < 30 and coarse.lattice_fit > 2.0
    assert coarse_strain > 0.2


def test_pleats_hold_their_length_in_a_wind():
    """The same curtain in a 1.5 m/s wind across it: the pleats bend with the layer where the
    couples resolve them, and stay within the curtain's 5 % (issue 12). Measured 3.10 % (p99,
    worst over 2 s); with the couples of the first curvature pass alone (284) 6.35 %."""
    _, strain = _pleated_curtain(wind=1.5)
    assert strain < 0.035


def test_a_rolling_sphere_stays_on_its_table():
    """A curved shell's floor follows its pose (FloorSupport, docs/lattice.md "Floor"): which
    mesh points are lowest changes as a sphere rolls. The demo's paper sphere in a 3 m/s wind
    rolls 4.30 m in 2 s; over the frames from 0.5 s to 2 s its lowest mesh point is 0.00 mm
    above the table at the median and 0.099 mm on average (it hops now and then, up to 0.97 mm,
    as a ball of 110 couples rolls over their corners); bound 0.13 mm. (0.195 mm on average,
    hops up to 2.8 mm, before sticking contacts held beyond friction slid: docs/dynamics.md §3.)
    With the rest pose's offsets it floated 27.6 mm on average, up to 38.8 mm
    (`python scripts/rolling_sphere.py`). Over 4 s the rolling is chaotic, so the test stops at
    2 s (docs/dynamics.md §3, "A hold beyond friction slides")."""
    from thinburn.demo import shell_scene

    sc = shell_scene("sphere")
    sim = thinburn.Simulation(sc.vertices, sc.faces, material="paper", cells=32, floor=0.0)
    sim.wind = (3.0, 0.0, 0.0)
    low = []
    for _ in range(48):
        sim.step(1 / 24)
        low.append(sim.vertex_positions()[:, 2].min())
    low = np.array(low[12:])
    assert sim.vertex_positions()[:, 0].mean() > 3.0  # it rolled
    assert low.min() >= 0.0
    assert np.median(low) < 0.00005 and low.mean() < 0.00013


def test_a_sphere_at_rest_on_its_table_stays_there_under_the_symplectic_integrator():
    """The floor lifts a couple by the mesh points it moves most (docs/lattice.md "Floor"). On
    points it merely shared (MLS weight small or negative) the explicit integrator's floor
    projection kept lifting couples that hardly moved them: the paper sphere at rest hopped,
    its lowest point 11-34 mm above the table after 1.5-2 s. Measured now: at most 0.004 mm over
    2 s, the mean height within 1.11 mm of its start (the sphere settles under its weight)."""
    from thinburn.demo import shell_scene

    sc = shell_scene("sphere")
    sim = thinburn.Simulation(sc.vertices, sc.faces, material="paper", cells=32, floor=0.0,
                              integrator="symplectic")
    z0 = sc.vertices[:, 2].mean()
    for _ in range(48):
        sim.step(1 / 24)
        p = sim.vertex_positions()
        assert p[:, 2].min() < 1e-4
        assert abs(p[:, 2].mean() - z0) < 0.0012
