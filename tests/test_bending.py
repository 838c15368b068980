"""Bending (eqs 2-6) on its own, against the closed forms of docs/bending.md."""
import numpy as np
import pytest

from thinburn.bending import DEFAULTS, Bending


def _couples(n=2, spacing=0.1, thickness=0.01):
    """n couples on the x axis: bottom at z = -t/2, top at z = +t/2 (index 2 c + k)."""
    pts = []
    for c in range(n):
        pts += [(c * spacing, 0.0, -thickness / 2), (c * spacing, 0.0, thickness / 2)]
    return np.array(pts)


def test_heat_is_eq_2_summed_over_particles_and_steps():
    ct, d_min, dt = 2e-6, 0.005, 0.04
    b = Bending(2, ct=ct, d_min=d_min, heat_fast=False)
    control = _couples()
    particles = np.array([[0.0, 0.0, 0.05], [0.3, 0.2, 0.1]])
    temps = np.array([900.0, 400.0])
    d = np.linalg.norm(control[:, None, :] - particles[None, :, :], axis=2)
    step = ct * dt / (4 * np.pi) * (temps / (d + d_min) ** 2).sum(axis=1)
    b.add_particle_heat(control, particles, temps, dt)
    np.testing.assert_allclose(b.heat, step, rtol=1e-13)
    np.testing.assert_allclose(b.heat_rate, step / dt, rtol=1e-13)
    b.add_particle_heat(control, particles, temps, dt)  # heat accumulates over steps
    np.testing.assert_allclose(b.heat, 2 * step, rtol=1e-13)
    b.add_particle_heat(control, np.zeros((0, 3)), np.zeros(0), dt)  # no particles: no rate
    np.testing.assert_allclose(b.heat, 2 * step, rtol=1e-13)
    assert not b.heat_rate.any()


def test_pyrolysis_is_eq_3_and_is_recomputed():
    # pyrolysis_range=0: every ignition point counts, as in the paper.
    cp, d_min = 0.8, 0.005
    b = Bending(2, cp=cp, d_min=d_min, heat_fast=False, pyrolysis_range=0.0)
    control = _couples()
    pts = np.array([[0.0, 0.0, 0.02], [0.1, 0.05, 0.0]])
    d = np.linalg.norm(control[:, None, :] - pts[None, :, :], axis=2)
    b.set_pyrolysis(control, pts)
    np.testing.assert_allclose(b.pyrolysis, cp * (1 / (d + d_min)).sum(axis=1), rtol=1e-13)
    b.set_pyrolysis(control, pts[:1])  # recomputed, not accumulated
    np.testing.assert_allclose(b.pyrolysis, cp / (d[:, 0] + d_min), rtol=1e-13)


def test_pyrolysis_counts_the_ignition_points_within_its_range():
    # The default pyrolysis_range (3 cm): each point closer than it adds 1/(d + d_min) less its
    # value at the range; a point 10 cm away adds nothing (docs/dynamics.md §2, "Pyrolysis
    # reaches as far as"). Each couple has one point within the range and one beyond it.
    cp, d_min, reach = 0.8, 0.005, 0.03
    b = Bending(2, cp=cp, d_min=d_min)
    control = _couples()
    pts = np.array([[0.0, 0.0, 0.02], [0.1, 0.015, 0.0]])
    d = np.linalg.norm(control[:, None, :] - pts[None, :, :], axis=2)
    b.set_pyrolysis(control, pts)
    want = cp * np.where(d < reach, 1 / (d + d_min) - 1 / (reach + d_min), 0.0).sum(axis=1)
    assert want.min() > 0 and ((d < reach).sum(axis=1) == 1).all()
    np.testing.assert_allclose(b.pyrolysis, want, rtol=1e-13)


@pytest.mark.parametrize("max_rotation", [0.0, 1.2, 0.05])
def test_rotation_is_eqs_4_to_6_saturated(max_rotation):
    alpha, beta = 3.0, 2e-3
    b = Bending(2, alpha=alpha, beta=beta, max_rotation=max_rotation, heat_fast=False, ct=1e-5)
    control = _couples()
    above = np.array([[0.0, 0.0, 0.03]])  # over couple 0: its top face is nearer, hotter
    b.add_particle_heat(control, above, np.array([1000.0]), 0.1)
    b.set_pyrolysis(control, above)
    T, P = b.heat.reshape(2, 2), b.pyrolysis.reshape(2, 2)
    raw = alpha * (T[:, 1] - T[:, 0]) + beta * (P[:, 1] - P[:, 0])
    want = raw if max_rotation == 0 else max_rotation * np.tanh(raw / max_rotation)
    D = b.rotation()
    np.testing.assert_allclose(D, want, rtol=1e-12)
    assert D[0] > 0  # the heated top face: positive D
    assert np.all(np.abs(D) <= (max_rotation or np.inf))


def test_the_fast_sums_stay_within_their_tolerance():
    rng = np.random.default_rng(1)
    control = np.c_[rng.uniform(0, 1, (400, 2)), np.tile([-0.005, 0.005], 200)]
    particles = rng.uniform([0, 0, 0.01], [1, 1, 0.2], (3000, 3))
    temps = rng.uniform(100, 1000, 3000)
    # The octree's tolerance is eq 3's over every point (pyrolysis_range=0; within a range the
    # sum is exact either way).
    exact = Bending(200, heat_fast=False, pyrolysis_range=0.0)
    fast = Bending(200, heat_fast=True, heat_tolerance=0.01, pyrolysis_range=0.0)
    for b in (exact, fast):
        b.add_particle_heat(control, particles, temps, 0.04)
        b.set_pyrolysis(control, particles[:500])
    assert np.max(np.abs(fast.heat / exact.heat - 1)) <= 0.01
    assert np.max(np.abs(fast.pyrolysis / exact.pyrolysis - 1)) <= 0.01


@pytest.mark.parametrize("kw, exc, name", [
    (dict(d_min=0.0), ValueError, "d_min"), (dict(heat_tolerance=1.0), ValueError, "heat_tolerance"),
    (dict(ct=-1.0), ValueError, "ct"), (dict(alpha=float("nan")), ValueError, "alpha"),
    (dict(heat_fast=1), TypeError, "heat_fast"), (dict(beta="x"), TypeError, "beta"),
    (dict(gamma=1.0), TypeError, "gamma"),
])
def test_bad_parameters_name_themselves(kw, exc, name):
    with pytest.raises(exc, match=name):
        Bending(2, **kw)


def test_bad_arrays_name_themselves():
    b = Bending(2)
    with pytest.raises(ValueError, match="control"):
        b.add_particle_heat(np.zeros((3, 3)), np.zeros((1, 3)), np.ones(1), 0.1)
    with pytest.raises(ValueError, match="temperatures"):
        b.add_particle_heat(_couples(), np.zeros((2, 3)), np.ones(3), 0.1)
    with pytest.raises(ValueError, match="dt"):
        b.add_particle_heat(_couples(), np.zeros((1, 3)), np.ones(1), 0.0)
    with pytest.raises(ValueError, match="couples"):
        Bending(0)


def test_defaults_are_the_documented_ones():
    assert DEFAULTS == dict(ct=1e-7, cp=1.0, alpha=1.0, beta=1e-3, d_min=0.005, max_rotation=0.4,
                            heat_tolerance=0.01, heat_fast=True, pyrolysis_range=0.03)
