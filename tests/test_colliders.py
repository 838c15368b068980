"""Collision objects: distances against closed forms, and a sheet resting, draping and sliding."""
import numpy as np
import pytest

import thinburn
from thinburn.colliders import Colliders
from thinburn.scenes import rect_sheet, sphere

QUIET = dict(speed_noise=0.0, duration_noise=0.0)


def test_sphere_and_box_distances_are_the_closed_forms():
    c = Colliders(spheres=[dict(centre=(1, 0, 0), radius=0.5)])
    d, n, i = c.query([(3, 0, 0), (1, 0, 0.2)])
    np.testing.assert_allclose(d, [1.5, -0.3], atol=1e-12)
    np.testing.assert_allclose(n, [(1, 0, 0), (0, 0, 1)], atol=1e-12)
    a = np.radians(30)
    R = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    b = Colliders(boxes=[dict(centre=(0, 0, 0), half_extents=(1, 2, 3), rotation=R, thickness=0.1)])
    # Local (2, 0, 0) is 1 past the x face; local (2, 3, 0) 1 past x and y: sqrt(2). Minus thickness.
    d, n, _ = b.query([R @ (2, 0, 0), R @ (2, 3, 0), R @ (0.5, 0, 0)])
    np.testing.assert_allclose(d, [0.9, 2 ** 0.5 - 0.1, -0.6], atol=1e-12)
    np.testing.assert_allclose(n[0], R @ (1, 0, 0), atol=1e-12)
    np.testing.assert_allclose(n[1], R @ (2 ** -0.5, 2 ** -0.5, 0), atol=1e-12)
    # The nearest of several wins; moving one moves its field.
    both = Colliders(spheres=[dict(centre=(0, 0, 0), radius=1), dict(centre=(5, 0, 0), radius=1)])
    assert both.query([(4.5, 0, 0)])[2][0] == 1
    both.set_transform(1, (10, 0, 0))
    assert both.query([(4.5, 0, 0)])[2][0] == 0


def test_closed_mesh_agrees_with_the_analytic_sphere_within_the_grid():
    R = 0.2
    v, f = sphere(R, level=3)  # 1280 faces: the facets lie within R (1 - cos(3.0 deg)) = 0.28 mm of the sphere
    mesh = Colliders(meshes=[dict(vertices=v, faces=f, resolution=48)])
    dx = mesh.grid_spacing(0)
    rng = np.random.default_rng(0)
    dirs = rng.normal(size=(400, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    radii = rng.uniform(0.5 * R, 1.5 * R, size=400)
    p = dirs * radii[:, None] + (0.01, -0.02, 0.03)
    mesh.set_transform(0, (0.01, -0.02, 0.03))  # the field moves with its pose
    d, n, _ = mesh.query(p)
    exact = radii - R
    near = np.abs(exact) < 2 * dx  # where contacts happen; farther out the grid's padding ends
    err = np.abs(d - exact)[near]
    angle = np.degrees(np.arccos(np.clip(np.sum(n * dirs, axis=1), -1, 1)))[near]
    # Measured (dx 8.3 mm): max |error| 0.89 mm = 0.107 dx, normals within 5.1 deg.
    assert err.max() < 0.13 * dx
    assert angle.max() < 6.0
    assert np.all(np.sign(d[np.abs(exact) > dx]) == np.sign(exact[np.abs(exact) > dx]))


def test_bad_inputs_name_the_argument():
    v, f = sphere(1.0, level=1)
    with pytest.raises(ValueError, match=r"meshes\[0\].*not closed"):
        Colliders(meshes=[dict(vertices=v, faces=f[:-1])])
    bad = v.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match=r"meshes\[0\]\.vertices.*NaN"):
        Colliders(meshes=[dict(vertices=bad, faces=f)])
    with pytest.raises(ValueError, match=r"spheres\[1\]\.radius"):
        Colliders(spheres=[dict(centre=(0, 0, 0), radius=1), dict(centre=(0, 0, 0), radius=-1)])
    with pytest.raises(ValueError, match=r"boxes\[0\].*rotation"):
        Colliders(boxes=[dict(centre=(0, 0, 0), half_extents=(1, 1, 1), rotation=2 * np.eye(3))])
    with pytest.raises(ValueError, match=r"spheres\[0\].*friction"):
        Colliders(spheres=[dict(centre=(0, 0, 0), radius=1, friction=-0.1)])
    sim = thinburn.Simulation(*rect_sheet(0.1, 0.1, nx=5, ny=5), cells=16, lattice=4)
    with pytest.raises(TypeError, match="colliders"):
        sim.set_colliders("table")
    with pytest.raises(ValueError, match="margin"):
        sim.set_colliders(spheres=[dict(centre=(0, 0, -1), radius=0.5)], margin=-1.0)


def run_lattice(sim, seconds):
    for _ in range(int(round(seconds * 24))):
        sim.step(1 / 24)
    return sim.lattice_positions().reshape(-1, 3)


def test_cloth_dropped_on_a_sphere_rests_on_it():
    R = 0.25
    c = np.array([0.15, 0.15, -R - 0.02])
    sim = thinburn.Simulation(*rect_sheet(0.3, 0.3, nx=31, ny=31), cells=32, lattice=12, material="cloth", **QUIET)
    sim.set_colliders(spheres=[dict(centre=c, radius=R, friction=0.5)])
    margin = 0.5 * sim.lattice_thickness
    before = run_lattice(sim, 4.0)
    after = run_lattice(sim, 1.0)
    d = np.linalg.norm(after - c, axis=1) - R
    assert d.min() > margin - 1e-9  # no control vertex inside the margin
    mesh = sim.vertex_positions()
    apex = mesh[np.argmin(np.linalg.norm(mesh[:, :2] - c[:2], axis=1)), 2] - (c[2] + R)
    # The mid-surface above the top: margin (3.4 mm) + about half a thickness; measured 6.07 mm.
    assert abs(apex - 6.07e-3) < 0.3e-3
    assert (np.linalg.norm(mesh - c, axis=1) - R).min() > 0.0  # measured 6.1 mm clear
    assert mesh[:, 2].min() < c[2] + R - 0.006  # it drapes: the hem 9.0 mm below the top (measured)
    assert np.abs(after - before).max() < 1e-6  # at rest: measured 3e-11 m in the 5th second


def test_cloth_draped_over_a_box_edge_hangs_down_the_side():
    # 0.35 m of the strip on the box's top (z = -0.01, edge at x = 0.35), 0.25 m over the edge.
    sim = thinburn.Simulation(*rect_sheet(0.6, 0.1, nx=61, ny=11), cells=32, lattice=16, material="cloth", **QUIET)
    sim.set_colliders(boxes=[dict(centre=(-0.15, 0.05, -0.51), half_extents=(0.5, 0.5, 0.5), friction=1.0)])
    margin = 0.5 * sim.lattice_thickness
    L = run_lattice(sim, 2.0)
    d, _, _ = Colliders(boxes=[dict(centre=(-0.15, 0.05, -0.51), half_extents=(0.5, 0.5, 0.5))]).query(L)
    assert d.min() > margin - 1e-9
    mesh = sim.vertex_positions()
    assert mesh[:, 2].min() < -0.01 - 0.19  # the hem hangs 0.2035 m below the top (measured)
    # The part on top stays: its end moved 10.7 mm by 2 s, settling (0.2 mm between 2.5 and 3 s).
    # Control vertices alone it moved 0.8 mm: the box's edge, 8.8 mm into the mesh between two
    # couples, held the strip like a hook (tests/test_shell_contact.py).
    assert mesh[:, 0].min() < 0.013


@pytest.mark.parametrize("degrees, slides", [(20, False), (35, True)])
def test_coulomb_friction_on_an_inclined_box(degrees, slides):
    mu, a = 0.5, np.radians(degrees)
    Ry = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    n = Ry @ (0, 0, 1)
    v, f = rect_sheet(0.1, 0.1, nx=11, ny=11)
    thickness = 0.005  # this sheet's lattice_thickness (asserted below)
    v = (v - (0.05, 0.05, 0)) @ Ry.T + n * (thickness + 1e-4)  # bottom layer 0.1 mm above the margin
    # wind_drag 0: the air's drag on each substep's fall into the face would take from the normal
    # force, hence the friction (docs/dynamics.md §3.2).
    sim = thinburn.Simulation(v, f, cells=16, lattice=6, material="paper", wind_drag=0.0, **QUIET)
    assert sim.lattice_thickness == pytest.approx(thickness)
    sim.set_colliders(boxes=[dict(centre=-0.5 * n, half_extents=(5, 5, 0.5), rotation=Ry, friction=mu)])
    x0 = sim.vertex_positions().mean(0)
    T = 1.5
    run_lattice(sim, T)
    slid = (sim.vertex_positions().mean(0) - x0) @ (Ry @ (1, 0, 0))
    c = sim.params.dynamics["c_damping"]
    accel = 9.81 * (np.sin(a) - mu * np.cos(a))
    # x'' = accel - c x' from rest: x = accel / c (T - (1 - exp(-c T)) / c); 0 when tan(angle) < mu.
    expected = max(0.0, accel / c * (T - (1 - np.exp(-c * T)) / c))
    if slides:
        assert slid == pytest.approx(expected, rel=0.01)  # measured 0.9077 vs 0.9063 m
    else:
        assert abs(slid) < 1e-4  # measured 0



@pytest.mark.parametrize("degrees, slides", [(10, False), (20, False), (30, True)])
def test_coulomb_friction_on_a_sphere(degrees, slides):
    # A 0.3 m cloth laid on a 1 m sphere, tilted by `degrees` from its top (a curved shell's
    # lattice: its couples touch alone), friction 0.5: the cone holds it while tan < 0.5 over the
    # sheet (it spans +-8.6 deg, so 20 deg reaches 28.6) and lets it go beyond. Measured
    # (scripts/collider_friction.py, seconds 1 to 4): 0.00 mm/s at 10 and 20 deg (10 deg: 0.10
    # before the contacts' positional friction), 627 mm/s at 30.
    R, c, a = 1.0, np.array([0.0, 0.0, 1.2]), np.radians(degrees)
    v, f = rect_sheet(0.3, 0.3, nx=31, ny=31)
    v = v - v.mean(0) + (0.0, 0.0, R + 0.006)
    Ry = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    sim = thinburn.Simulation(v @ Ry.T + c, f, cells=16, lattice=6, material="cloth", **QUIET)
    sim.set_colliders(spheres=[dict(centre=tuple(c), radius=R, friction=0.5)])

    def along():  # m along the sphere's surface
        p = sim.vertex_positions().mean(0) - c
        return R * np.arctan2(p[0], p[2])

    run_lattice(sim, 1.0)
    start = along()
    run_lattice(sim, 3.0)
    speed = abs(along() - start) / 3.0
    if slides:
        assert speed > 0.3
    else:
        assert speed < 1e-5


def test_a_moving_collider_wakes_and_lifts_a_resting_sheet():
    sim = thinburn.Simulation(*rect_sheet(0.2, 0.2, nx=11, ny=11), cells=16, lattice=6, material="cloth", **QUIET)
    col = sim.set_colliders(boxes=[dict(centre=(0.1, 0.1, -0.52), half_extents=(0.5, 0.5, 0.5))])
    margin = 0.5 * sim.lattice_thickness
    run_lattice(sim, 0.5)
    assert sim.step_stats()["awake"] == 0  # asleep on the box
    col.set_transform(0, (0.1, 0.1, -0.51))  # 1 cm up
    L = run_lattice(sim, 1 / 24)
    # The move is the box's velocity over the step (0.24 m/s up): the sheet, lifted to the margin
    # and given that speed, rises on 0.73 mm above it by the step's end (measured).
    assert L[0::2, 2].min() == pytest.approx(-0.01 + margin + 0.73e-3, abs=0.05e-3)


def test_a_moving_box_carries_the_sheet_resting_on_it():
    # The box's pose changes once a frame (as Blender's animation sets it); each move is the
    # box's velocity over the next step, and the contact's friction (mu = 1) acts on the sheet's
    # speed relative to it.
    sim = thinburn.Simulation(*rect_sheet(0.2, 0.2, nx=21, ny=21), cells=16, lattice=6, material="cloth", **QUIET)
    col = sim.set_colliders(boxes=[dict(centre=(0.1, 0.1, -0.26), half_extents=(0.25, 0.25, 0.25), friction=1.0)])
    run_lattice(sim, 0.5)
    x0 = sim.vertex_positions().mean(0)
    for k in range(24):  # 0.2 m/s along x for 1 s
        col.set_transform(0, (0.1 + 0.2 * (k + 1) / 24, 0.1, -0.26))
        sim.step(1 / 24)
    moved = sim.vertex_positions().mean(0) - x0
    # Measured: 0.1989 m of the box's 0.2 m (it starts from rest, so lags the first frames).
    assert moved[0] == pytest.approx(0.1989, abs=0.002)
    assert abs(moved[1]) < 1e-9 and abs(moved[2]) < 1e-5


def test_a_turning_box_turns_the_sheet_resting_on_it():
    # A turntable: the box turns 30 degrees about z in 1 s, its pose set once a frame; each
    # point of its top moves with the rotation's velocity at that point.
    sim = thinburn.Simulation(*rect_sheet(0.2, 0.2, nx=21, ny=21), cells=16, lattice=6, material="cloth", **QUIET)
    col = sim.set_colliders(boxes=[dict(centre=(0.1, 0.1, -0.26), half_extents=(0.25, 0.25, 0.25), friction=1.0)])
    run_lattice(sim, 0.5)
    x0 = sim.vertex_positions()
    for k in range(24):
        a = np.radians(30) * (k + 1) / 24
        R = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
        col.set_transform(0, (0.1, 0.1, -0.26), R)
        sim.step(1 / 24)
    x1 = sim.vertex_positions()
    d0, d1 = x0[:, :2] - x0[:, :2].mean(0), x1[:, :2] - x1[:, :2].mean(0)
    turned = np.degrees(np.arctan2((d0[:, 0] * d1[:, 1] - d0[:, 1] * d1[:, 0]).sum(), (d0 * d1).sum()))
    # Measured: 29.91 degrees (before the colliders' velocity was passed: 0), the centre still.
    assert turned == pytest.approx(29.91, abs=0.1)
    assert np.abs(x1.mean(0) - x0.mean(0)).max() < 1e-5


def _carried_sheet(integrator):
    # The carry scene above, small, on an explicit integrator (its steps can refuse).
    sim = thinburn.Simulation(*rect_sheet(0.2, 0.2, nx=11, ny=11), cells=16, lattice=6, material="cloth",
                              integrator=integrator, **QUIET)
    col = sim.set_colliders(boxes=[dict(centre=(0.1, 0.1, -0.26), half_extents=(0.25, 0.25, 0.25), friction=1.0)])
    return sim, col


def test_a_refused_step_leaves_the_colliders_motion_as_it_was():
    # A step that throws (an explicit integrator needing more than max_substeps) is rolled back
    # whole: the retried step must see the box's move since the last step, as a run that never
    # tried the big step does. Before the rollback kept ColliderMotion, the refused step had
    # already taken the box's pose as "last", so the retry saw the box still (velocity 0) and
    # the sheet lagged it (measured: 1.74 mm apart after 24 steps of 1/240 s with four refusals).
    dt = 1 / 240
    runs = []
    for refuse in (False, True):
        sim, col = _carried_sheet("symplectic")
        sim.set_dynamics(max_substeps=400)
        for k in range(24):
            col.set_transform(0, (0.1 + 0.2 * (k + 1) * dt, 0.1, -0.26))
            if refuse and k % 6 == 3:
                with pytest.raises(RuntimeError, match="max_substeps"):
                    sim.step(2.0)
            sim.step(dt)
        runs.append(sim.lattice_positions())
    assert np.array_equal(runs[0], runs[1])


@pytest.mark.xfail(strict=True, reason="docs/dynamics.md §9: a sheet at rest on a collider never rests")
def test_a_cloth_at_rest_on_a_ball_is_not_redone_every_step():
    # The Blender drape in small (scripts/collider_rest.py): a 40 cm cloth settled on a 10 cm ball.
    # Collision objects are projections after the solve, so in each substep the cloth falls
    # g h^2 into the ball and its lattice strains with the substep (the full drape: 19.8 % at
    # the contacts' 3 substeps), so every step is redone, here with 27 (measured: frames 25-30,
    # each redone, the strain after the redo 2.98-3.00 %). A contact held in the solve, as the
    # floor's are, would take the step at once.
    v, f = rect_sheet(0.4, 0.4, nx=21, ny=21, z=0.22)
    v[:, :2] -= v[:, :2].mean(0)
    sim = thinburn.Simulation(v, f, material="cloth", cells=16, floor=0.0, lattice=12, **QUIET)
    sim.set_colliders(spheres=[dict(centre=(0, 0, 0.1), radius=0.1, friction=0.5, thickness=0.001)])
    run_lattice(sim, 1.0)
    redone = 0
    for _ in range(6):
        sim.step(1 / 24)
        redone += sim.step_stats()["stretch_redos"] > 0
    assert redone == 0
