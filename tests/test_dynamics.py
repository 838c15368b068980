"""Lattice dynamics (paper §4.3): derivatives, integrators against closed forms and stability
theory, invariants, parameters and the closed forms of thin-sheet statics. The parts the
dynamics owns have their own files: test_crumple, test_contact, test_sleeping,
test_implicit_solver, test_block_ldlt (and test_membrane, test_strain_limit, test_self_contact)."""
import numpy as np
import pytest

import thinburn
from thinburn import _core
from thinburn.dynamics import preset, vertex_masses
from thinburn.lattice import vertex_index
from lattice_cases import CHORD, INTEGRATORS, SPRINGS_OFF, expected_crumple, grid_rest, make, zeros


def exact_omega(dyn, masses):
    K = dyn.stiffness_matrix()
    s = np.repeat(1.0 / np.sqrt(masses), 3)
    return float(np.sqrt(np.linalg.eigvalsh(-(s[:, None] * K * s[None, :])).max()))


# --- derivatives ---------------------------------------------------------------------------------

# With flexural_rigidity below the lattice's own (0.045 N m here), membrane springs join the
# layers (cpp/membrane.*, tests/test_membrane.py): the same derivatives hold.
# The third: the membrane's knee (docs/dynamics.md §3.4), beyond 0.8 * 5 % where perturbed()'s
# 1 cm noise on 5 cm spacings stretches a pair of couples.
SOFT = [{}, dict(flexural_rigidity=2e-6), dict(flexural_rigidity=2e-6, strain_limit=0.05, k_limit=2.0)]


def perturbed(seed=0, M=3, **params):
    lat, dyn = make(M, 0.05, 0.01, gravity=[0, 0, 0], k_structure=0.3, k_shear=0.2, k_flex=0.1,
                    k_thickness=0.7, k_transverse=0.4, **params)
    rng = np.random.default_rng(seed)
    x = lat.rest + rng.normal(scale=0.01, size=lat.rest.shape)
    dyn.set_state(x, np.zeros_like(x))
    return lat, dyn, x


@pytest.mark.parametrize("soft", SOFT)
def test_spring_forces_are_minus_the_energy_gradient(soft):
    lat, dyn, x = perturbed(**soft)
    assert (dyn.membrane_springs > 0) == bool(soft)
    f = dyn.forces()
    assert np.abs(f).max() > 1.0
    eps = 1e-7
    grad = np.zeros_like(x)
    for v in range(x.shape[0]):
        for d in range(3):
            xp, xm = x.copy(), x.copy()
            xp[v, d] += eps
            xm[v, d] -= eps
            dyn.set_state(xp, np.zeros_like(x))
            ep = dyn.energy()
            dyn.set_state(xm, np.zeros_like(x))
            grad[v, d] = (ep - dyn.energy()) / (2 * eps)
    np.testing.assert_allclose(f, -grad, rtol=0, atol=1e-6 * np.abs(f).max())
    kinds = dyn.spring_kinds
    lengths = np.linalg.norm(x[dyn.spring_pairs[:, 1]] - x[dyn.spring_pairs[:, 0]], axis=1)
    stretch = lengths - np.asarray(dyn.rest_lengths)
    assert (stretch > 0).any() and (stretch < 0).any()  # both regimes are exercised
    assert set(np.unique(kinds)) == {0, 1, 2, 3, 4} - ({2} if lat.M < 3 else set()) | ({5} if soft else set())
    if soft.get("k_limit"):  # pairs beyond the knee: 2.66 J against 2.40 J without it
        _, kneeless, _ = perturbed(**{**soft, "k_limit": 0.0})
        assert dyn.energy() > 1.05 * kneeless.energy()


def test_the_knee_stores_its_closed_form_energy_on_pairs_and_corners():
    # Beyond (1 + 0.8 strain_limit) of its rest length a pair of neighbouring couples' centres
    # stores k_limit * stiffness_unit / 2 * (l - end)^2 on top of its springs, and so does each
    # corner's diagonal g = c_b + c_c - 2 c_a (cpp/membrane.hpp, add_corners).
    soft = SOFT[2]
    lat, dyn, x = perturbed(**soft)
    _, kneeless, _ = perturbed(**{**soft, "k_limit": 0.0})
    assert dyn.membrane_corners == 4
    M, k, knee = 3, soft["k_limit"] * 1000.0, 1 + 0.8 * soft["strain_limit"]
    c = x.reshape(M, M, 2, 3).mean(axis=2)
    r = lat.rest.reshape(M, M, 2, 3).mean(axis=2)
    pairs = [((i, j), (i + di, j + dj)) for i in range(M) for j in range(M)
             for di, dj in ((1, 0), (0, 1), (1, 1)) if i + di < M and j + dj < M]
    pairs += [((i + 1, j), (i, j + 1)) for i in range(M - 1) for j in range(M - 1)]
    beyond = [np.linalg.norm(c[b] - c[a]) - knee * np.linalg.norm(r[b] - r[a]) for a, b in pairs]
    corners = []
    for i, j in ((0, 0), (0, M - 1), (M - 1, 0), (M - 1, M - 1)):
        di, dj = (1 if i == 0 else -1), (1 if j == 0 else -1)
        g = lambda p: p[i + di, j] + p[i, j + dj] - 2 * p[i, j]
        corners.append(np.linalg.norm(g(c)) - knee * np.linalg.norm(g(r)))
    over = np.maximum(beyond + corners, 0.0)
    assert np.sum(np.array(corners) > 0) >= 2  # perturbed() takes corners past their knee
    assert dyn.energy() - kneeless.energy() == pytest.approx(0.5 * k * np.sum(over ** 2), rel=1e-10)


@pytest.mark.parametrize("soft", SOFT)
def test_stiffness_matrix_is_the_jacobian_of_the_forces(soft):
    lat, dyn, x = perturbed(1, **soft)
    K = dyn.stiffness_matrix()
    assert np.abs(K).max() > 1.0
    np.testing.assert_allclose(K, K.T, rtol=0, atol=1e-9)
    eps = 1e-7
    Kfd = np.zeros_like(K)
    for v in range(x.shape[0]):
        for d in range(3):
            xp, xm = x.copy(), x.copy()
            xp[v, d] += eps
            xm[v, d] -= eps
            dyn.set_state(xp, np.zeros_like(x))
            fp = dyn.forces().ravel()
            dyn.set_state(xm, np.zeros_like(x))
            Kfd[:, 3 * v + d] = (fp - dyn.forces().ravel()) / (2 * eps)
    np.testing.assert_allclose(K, Kfd, rtol=0, atol=1e-6 * np.abs(K).max())


def test_forces_of_gravity_buoyancy_damping_and_wind():
    M = 2
    lat, dyn = make(M, 0.05, 0.004, gravity=[0.5, 0, -9.81], buoyancy=3.0, c_damping=1.7,
                    wind_drag=0.8)
    rng = np.random.default_rng(2)
    m = rng.uniform(0.5, 2.0, 2 * M * M)
    a = rng.uniform(0.1, 0.2, 2 * M * M)
    v = rng.normal(size=(2 * M * M, 3))
    heat = rng.uniform(0, 5, 2 * M * M)
    dyn.set_masses(m)
    dyn.set_areas(a)
    wind = np.array([1.0, -2.0, 3.0])
    dyn.set_wind(wind)
    dyn.set_state(lat.rest, v)
    n = np.array([0, 0, 1.0])  # couples point up at rest
    want = (m[:, None] * np.array([0.5, 0, -9.81]) - 1.7 * m[:, None] * v
            + 0.8 * a[:, None] * ((wind - v) @ n)[:, None] * n)
    np.testing.assert_allclose(dyn.forces(), want, rtol=1e-12, atol=1e-12)
    # Buoyancy acts through the heat of a step: one symplectic substep from rest, springs off.
    dyn.set_params(gravity=[0, 0, 0], c_damping=0.0, wind_drag=0.0, substeps=1,
                   integrator="symplectic", **SPRINGS_OFF)
    dyn.set_state(lat.rest, np.zeros_like(v))
    dt = 1e-3
    dyn.step(dt, np.zeros(M * M), heat)
    np.testing.assert_allclose(dyn.forces()[:, 2], m * 3.0 * heat, rtol=1e-12)
    np.testing.assert_allclose(dyn.velocities[:, 2], 3.0 * heat * dt, rtol=1e-12)


# --- integrators against closed forms ------------------------------------------------------------

def slope(hs, errs):
    return np.polyfit(np.log(hs), np.log(errs), 1)[0]


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_free_fall_converges_at_first_order(integrator):
    g, T = 9.81, 0.5
    errs, hs = [], []
    for N in (10, 20, 40, 80):
        lat, dyn = make(2, integrator=integrator, substeps=1, sleeping=False, c_damping=0.0,
                        gravity=[0, 0, -g], **SPRINGS_OFF)
        D, heat = zeros(2)
        for _ in range(N):
            dyn.step(T / N, D, heat)
        z = lat.positions[:, 2] - lat.rest[:, 2]
        errs.append(np.abs(z + 0.5 * g * T * T).max())
        hs.append(T / N)
        np.testing.assert_allclose(dyn.velocities[:, 2], -g * T, rtol=1e-12)
    assert abs(slope(hs, errs) - 1.0) < 0.3
    # The closed forms of the errors: symplectic and backward Euler g T h / 2, the paper's g T h.
    factor = 1.0 if integrator == "explicit" else 0.5
    np.testing.assert_allclose(errs, factor * g * T * np.array(hs), rtol=1e-9)


def oscillator(integrator, N, T, c):
    """One free vertex tied to pinned ones by springs: x'' = -K/m x - c x' (small amplitude)."""
    M, L = 2, 1.0
    lat = _core.FfdLattice(M, grid_rest(M, L, 0.3))
    # Amplitudes of a micrometre: the CG converges relatively only (no absolute floor).
    dyn = _core.LatticeDynamics(lat, integrator=integrator, substeps=1, sleeping=False,
                                cg_velocity_tolerance=0.0,
                                c_damping=c, gravity=[0, 0, 0], k_structure=0.3, k_shear=0.2,
                                k_thickness=1.0, k_transverse=0.1)
    m = np.full(2 * M * M, 10.0)
    dyn.set_masses(m)
    pinned = np.ones(2 * M * M, dtype=np.uint8)
    pinned[1] = 0
    dyn.set_pinned(pinned)
    K = -dyn.stiffness_matrix()[3:6, 3:6] / m[1]
    u0 = 1e-6 * np.array([1.0, 2.0, -3.0])
    x = lat.rest.copy()
    x[1] += u0
    dyn.set_state(x, np.zeros_like(x))
    D, heat = zeros(M)
    for _ in range(N):
        dyn.step(T / N, D, heat)
    # Closed form per mode: q(t) = exp(-c t / 2) (q0 cos wd t + c q0 / (2 wd) sin wd t).
    w2, V = np.linalg.eigh(K)
    q0 = V.T @ u0
    wd = np.sqrt(w2 - c * c / 4)
    q = np.exp(-c * T / 2) * (q0 * np.cos(wd * T) + c * q0 / (2 * wd) * np.sin(wd * T))
    return lat.positions[1] - lat.rest[1], V @ q, np.sqrt(w2.max())


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_damped_oscillator_converges_at_first_order(integrator):
    T, c = 1.0, 3.0
    errs, hs = [], []
    for N in (200, 400, 800, 1600):
        got, want, w = oscillator(integrator, N, T, c)
        errs.append(np.linalg.norm(got - want) / 1e-6)
        hs.append(T / N)
    assert w * hs[0] < 0.2  # well inside every explicit stability limit
    assert errs[-1] < 0.05
    assert abs(slope(hs, errs) - 1.0) < 0.3


# --- stability --------------------------------------------------------------------------------

def grows(integrator, dt, steps=200):
    M = 8
    lat, dyn = make(M, integrator=integrator, substeps=1, sleeping=False, c_damping=0.0,
                    gravity=[0, 0, 0])
    rng = np.random.default_rng(7)
    x0 = lat.rest + rng.normal(scale=1e-8, size=lat.rest.shape)
    dyn.set_state(x0, np.zeros_like(x0))
    D, heat = zeros(M)
    for _ in range(steps):
        dyn.step(dt, D, heat)
        if not np.all(np.abs(lat.positions - lat.rest) < 1e-4):
            return True
    return False


def test_theoretical_limits():
    w = 123.0
    assert _core.explicit_stability_limit("symplectic", w) == pytest.approx(2 / w, rel=1e-9)
    assert _core.explicit_stability_limit("explicit", w) == pytest.approx(np.sqrt(2) / w, rel=1e-9)
    # Damping per kg shrinks the symplectic limit to the root of w^2 h^2 + 2 c h = 4.
    c = 40.0
    want = (-c + np.sqrt(c * c + 4 * w * w)) / (w * w)
    assert _core.explicit_stability_limit("symplectic", w, c) == pytest.approx(want, rel=1e-9)


@pytest.mark.parametrize("integrator, limit", [("symplectic", 2.0), ("explicit", np.sqrt(2.0))])
def test_explicit_methods_fail_where_theory_says(integrator, limit):
    M = 8
    lat, dyn = make(M)
    w = exact_omega(dyn, vertex_masses(M, (7 * 0.03) ** 2, 0.08))
    bound = dyn.max_frequency()
    assert w <= bound <= 2.0 * w
    lo, hi = 0.5, 3.0  # in units of 1 / w
    assert not grows(integrator, lo / w) and grows(integrator, hi / w)
    for _ in range(12):
        mid = 0.5 * (lo + hi)
        if grows(integrator, mid / w):
            hi = mid
        else:
            lo = mid
    assert abs(0.5 * (lo + hi) / limit - 1.0) < 0.1


@pytest.mark.parametrize("dt", [1 / 24, 1.0])
def test_implicit_stays_bounded_at_large_steps(dt):
    M = 8
    lat, dyn = make(M, substeps=1, sleeping=False, c_damping=0.0, gravity=[0, 0, 0])
    rng = np.random.default_rng(8)
    x0 = lat.rest + rng.normal(scale=1e-3, size=lat.rest.shape)
    dyn.set_state(x0, np.zeros_like(x0))
    e0 = dyn.energy()
    D, heat = zeros(M)
    w = dyn.max_frequency()
    assert w * dt > 100  # far past every explicit limit
    for _ in range(20):
        dyn.step(dt, D, heat)
    assert np.all(np.isfinite(lat.positions))
    assert dyn.energy() < e0
    assert np.abs(lat.positions - lat.rest).max() < 0.05


@pytest.mark.parametrize("integrator, limit", [("symplectic", 2.0), ("explicit", np.sqrt(2.0))])
def test_explicit_step_substeps_to_stay_stable(integrator, limit):
    M = 6
    lat, dyn = make(M, integrator=integrator, gravity=[0, 0, 0])
    w = exact_omega(dyn, vertex_masses(M, (5 * 0.03) ** 2, 0.08))
    D, heat = zeros(M)
    dt = 1 / 24
    for f in range(12):
        D[2 * M + 3] = 0.05 * f
        st = dyn.step(dt, D, heat)
        assert st.substeps >= dt * w / limit
    assert np.all(np.isfinite(lat.positions))
    assert np.abs(lat.positions - lat.rest).max() < 0.1


def test_explicit_step_refuses_beyond_max_substeps():
    M = 6
    lat, dyn = make(M, integrator="explicit", max_substeps=10, **CHORD)
    D, heat = zeros(M)
    D[2 * M + 3] = 0.2
    with pytest.raises(RuntimeError, match="max_substeps = 10.*Implicit"):
        dyn.step(1 / 24, D, heat)
    assert np.array_equal(lat.positions, lat.rest)
    # Nothing was consumed: with room, the same call applies the whole increment.
    dyn.set_params(max_substeps=100000, **SPRINGS_OFF, gravity=[0, 0, 0], c_damping=0.0)
    dyn.step(1 / 24, D, heat)
    np.testing.assert_allclose(lat.positions, expected_crumple(lat, M, 2, 3, 0.2), atol=1e-12)


# --- invariants ---------------------------------------------------------------------------------

def mirror_map(M, kind):
    idx = np.arange(2 * M * M)
    k, c = idx % 2, idx // 2
    i, j = c // M, c % M
    if kind == "mirror":
        return vertex_index(M, i, M - 1 - j, k), np.diag([-1.0, 1, 1])
    return vertex_index(M, j, i, k), np.array([[0, 1.0, 0], [1, 0, 0], [0, 0, 1]])


@pytest.mark.parametrize("kind", ["mirror", "transpose"])
@pytest.mark.parametrize("integrator", ["implicit", "symplectic"])
def test_symmetric_input_gives_symmetric_output(kind, integrator):
    # The explicit run has no floor: a contact decided by the last bit of a coordinate (the
    # sheet starts on the floor) turns rounding-level asymmetry into a different friction
    # impulse, which hundreds of substeps then amplify.
    M = 8
    # Symmetry to 1e-12 needs the CG converged to its relative tolerance (no absolute floor).
    lat, dyn = make(M, integrator=integrator, cg_tolerance=1e-14, cg_velocity_tolerance=0.0,
                    has_floor=integrator == "implicit", floor_z=-0.0015, plasticity=0.5)
    perm, R = mirror_map(M, kind)
    rng = np.random.default_rng(9)
    base = rng.uniform(0, 0.05, (M, M))
    base = base + (base[:, ::-1] if kind == "mirror" else base.T)
    heat = rng.uniform(0, 0.1, 2 * M * M)
    heat = heat + heat[perm]
    for f in range(1, 5):
        dyn.step(1 / 24, base.ravel() * f, heat)
    x = lat.positions
    assert np.abs(x - lat.rest).max() > 1e-3
    np.testing.assert_allclose(x[perm] @ R.T, x, rtol=0, atol=1e-12)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_no_forcing_no_motion(integrator):
    M = 5
    lat, dyn = make(M, integrator=integrator, gravity=[0, 0, 0], sleeping=False)
    D, heat = zeros(M)
    for _ in range(5):
        dyn.step(1 / 24, D, heat)
    assert np.array_equal(lat.positions, lat.rest)
    assert not np.any(dyn.velocities)


def run_scene(threads, integrator="implicit", M=28):
    old = thinburn.get_threads()
    try:
        thinburn.set_threads(threads)
        # The chord crumple drives the scene: it moves the sheet more than the bimetal curl.
        lat, dyn = make(M, integrator=integrator, sleeping=False, has_floor=True,
                        floor_z=-0.0015, **CHORD, **({} if integrator == "implicit" else
                                            dict(substeps=3, stiffness_unit=1.0)))
        D, heat = zeros(M)
        c = (M // 2) * M + M // 3
        for f in range(3):
            D[c] = 0.1 * (f + 1)
            D[c + 5] = 0.07 * (f + 1)
            heat[2 * c:2 * c + 40] = 0.3 * f
            dyn.step(1 / 24, D, heat)
        return lat.positions.copy(), dyn.velocities.copy()
    finally:
        thinburn.set_threads(old)


@pytest.mark.parametrize("integrator", ["implicit", "symplectic"])
def test_bit_identical_across_runs_and_threads(integrator):
    a = run_scene(1, integrator)
    b = run_scene(1, integrator)
    c = run_scene(2, integrator)
    assert np.abs(a[0] - grid_rest(28, 0.03, 0.003)).max() > 1e-4
    for u, v, w in zip(a, b, c):
        assert np.array_equal(u, v)
        assert np.array_equal(u, w)


# --- spring strength --------------------------------------------------------------------------

def test_strength_scales_each_spring_by_the_mean_of_its_ends():
    # K is linear in the spring constants: a uniform strength s scales it by s exactly, and
    # strengths s_a, s_b scale the spring between them by (s_a + s_b) / 2.
    M = 4
    lat, dyn = make(M)
    lat.positions = lat.rest + np.random.default_rng(3).normal(scale=1e-3, size=lat.rest.shape)
    K1 = dyn.stiffness_matrix()  # dense
    dyn.set_strength(np.full(2 * M * M, 0.3))
    K = dyn.stiffness_matrix()
    np.testing.assert_allclose(K, 0.3 * K1, rtol=1e-12, atol=1e-12 * np.abs(K1).max())
    s = np.ones(2 * M * M)
    s[0] = 0.0  # vertex 0's springs keep half their stiffness
    dyn.set_strength(s)
    K = dyn.stiffness_matrix()
    # The off-diagonal block between vertex 0 and a neighbour is that spring's -J: halved.
    j = 2  # vertex 2 = couple (0, 1) bottom, a structure neighbour of vertex 0
    np.testing.assert_allclose(K[0:3, 3 * j:3 * j + 3], 0.5 * K1[0:3, 3 * j:3 * j + 3], rtol=1e-12)
    assert np.array_equal(dyn.strength, s)
    with pytest.raises(ValueError, match="strength"):
        dyn.set_strength(np.full(2 * M * M, 1.5))
    with pytest.raises(ValueError, match="strength"):
        dyn.set_strength(np.ones(3))


# --- parameters and validation --------------------------------------------------------------------

def test_params_round_trip_and_presets():
    M = 3
    lat, dyn = make(M, **preset("cloth", integrator="symplectic"))
    p = dyn.params
    assert p["k_structure"] == 0.3 and p["k_transverse"] == 0.3 and p["c_damping"] == 2.5
    assert p["crumple_gain"] == 0.05 / 0.3  # the core's set_material, as a cloth Simulation's
    assert p["integrator"] == "symplectic"
    dyn.set_params(wind_drag=2.0)
    assert dyn.params["wind_drag"] == 2.0 and dyn.params["k_structure"] == 0.3
    m = vertex_masses(5, 0.3, 0.08)
    assert m.sum() == pytest.approx(0.3 * 0.08, rel=1e-12)


def test_bad_input_names_the_argument():
    M = 3
    lat = _core.FfdLattice(M, grid_rest(M, 0.03, 0.003))
    with pytest.raises(TypeError, match="unexpected keyword argument 'k_bogus'"):
        _core.LatticeDynamics(lat, k_bogus=1.0)
    with pytest.raises(ValueError, match="k_shear"):
        _core.LatticeDynamics(lat, k_shear=-1.0)
    with pytest.raises(ValueError, match="integrator"):
        _core.LatticeDynamics(lat, integrator="rk4")
    with pytest.raises(TypeError, match="sleeping"):
        _core.LatticeDynamics(lat, sleeping=1)
    with pytest.raises(TypeError, match="c_damping"):
        _core.LatticeDynamics(lat, c_damping=True)
    with pytest.raises(ValueError, match="preconditioner"):
        _core.LatticeDynamics(lat, preconditioner="lu")
    with pytest.raises(ValueError, match="wake_hold"):
        _core.LatticeDynamics(lat, wake_hold=-1)
    with pytest.raises(ValueError, match="refactor_iterations"):
        _core.LatticeDynamics(lat, refactor_iterations=-2)
    dyn = _core.LatticeDynamics(lat)
    D, heat = zeros(M)
    with pytest.raises(ValueError, match="D must have"):
        dyn.step(0.1, np.zeros(3), heat)
    with pytest.raises(ValueError, match="heat must have"):
        dyn.step(0.1, D, np.zeros(3))
    with pytest.raises(ValueError, match="dt"):
        dyn.step(0.0, D, heat)
    with pytest.raises(ValueError, match="heat must be finite"):
        dyn.step(0.1, D, np.full(2 * M * M, np.nan))
    with pytest.raises(ValueError, match="masses"):
        dyn.set_masses(np.zeros(2 * M * M))
    with pytest.raises(ValueError, match="areas"):
        dyn.set_areas(np.ones(3))
    with pytest.raises(ValueError, match="pinned"):
        dyn.set_pinned(np.ones(3, dtype=np.uint8))
    with pytest.raises(ValueError, match="wind"):
        dyn.set_wind([1.0, 2.0])


def cantilever_tip(M, side=0.2, thickness=0.005):
    lat = _core.FfdLattice(M, grid_rest(M, side / (M - 1), thickness))
    dyn = _core.LatticeDynamics(lat, c_damping=20.0)
    dyn.set_masses(vertex_masses(M, side * side, 0.08))
    pinned = np.zeros(2 * M * M, dtype=np.uint8)
    pinned[:2 * M] = 1  # the first row of couples, both layers: a clamped edge
    dyn.set_pinned(pinned)
    D, heat = zeros(M)
    for _ in range(120):
        if dyn.step(1 / 24, D, heat).awake == 0:
            break
    assert not dyn.awake.any()
    return lat.positions.reshape(M, M, 2, 3)[-1, :, :, 2].mean()


def test_stiffness_scale_makes_the_static_shape_converge_in_M():
    # A 0.2 m paper sheet clamped along one edge droops under gravity: the tip deflection
    # changes less and less as the lattice is refined (same sheet, same coefficients).
    tips = [cantilever_tip(M) for M in (5, 9, 17)]
    assert all(-0.1 < t < -0.02 for t in tips)
    d1, d2 = abs(tips[1] - tips[0]), abs(tips[2] - tips[1])
    assert d2 < 0.7 * d1
    assert d2 < 0.15 * abs(tips[2])


def test_python_helpers_validate_their_arguments():
    with pytest.raises(ValueError, match="name"):
        preset("papyrus")
    with pytest.raises(ValueError, match="M must be"):
        vertex_masses(1, 1.0, 0.08)
    with pytest.raises(ValueError, match="areal_density"):
        vertex_masses(4, 1.0, -0.08)
    m = vertex_masses(4, 0.09, 0.08)
    assert m.shape == (32,) and m[0] == m[1] == pytest.approx(0.25 * m[2 * 5])


def test_keyword_values_of_the_wrong_type_name_the_key():
    """Repro r6: pybind's RuntimeError 'Unable to cast' reached the user; now every keyword of
    LatticeDynamics (and set_params) gives a TypeError or ValueError naming it."""
    M = 3
    lat = _core.FfdLattice(M, grid_rest(M, 0.03, 0.003))
    cases = [(dict(gravity=9.81), TypeError, "gravity"), (dict(gravity="down"), TypeError, "gravity"),
             (dict(gravity=(0, 0)), ValueError, "gravity"), (dict(gravity=(0, 0, np.nan)), ValueError, "gravity"),
             (dict(substeps=1.5), TypeError, "substeps"), (dict(substeps=2**40), ValueError, "substeps"),
             (dict(max_substeps=2**31), ValueError, "max_substeps"), (dict(wake_hold=np.float64(2)), TypeError, "wake_hold"),
             (dict(k_structure="1"), TypeError, "k_structure"), (dict(k_structure=None), TypeError, "k_structure"),
             (dict(k_structure=10**400), ValueError, "k_structure"), (dict(buoyancy=np.inf), ValueError, "buoyancy"),
             (dict(floor_z=[0.0]), TypeError, "floor_z"), (dict(has_floor=np.int64(1)), TypeError, "has_floor"),
             (dict(cg_max_iterations=-2**63), ValueError, "cg_max_iterations"),
             (dict(integrator=None), TypeError, "integrator"), (dict(preconditioner=1.0), TypeError, "preconditioner")]
    for kw, exc, name in cases:
        with pytest.raises(exc, match=name):
            _core.LatticeDynamics(lat, **kw)
    dyn = _core.LatticeDynamics(lat, substeps=np.int64(3), k_structure=np.float32(2.0), sleeping=np.bool_(False),
                                gravity=np.array([0.0, 0.0, -1.0]))
    assert dyn.params["substeps"] == 3 and dyn.params["k_structure"] == 2.0 and dyn.params["sleeping"] is False
    before = dyn.params
    for kw, exc, name in cases:
        with pytest.raises(exc, match=name):
            dyn.set_params(**kw)
    assert dyn.params == before


def test_substep_ceilings():
    M = 3
    lat = _core.FfdLattice(M, grid_rest(M, 0.03, 0.003))
    dyn = _core.LatticeDynamics(lat, substeps=10000, max_substeps=1000000)
    assert dyn.params["substeps"] == 10000
    with pytest.raises(ValueError, match=r"substeps must be in \[0, 10000\]"):
        dyn.set_params(substeps=10001)
    with pytest.raises(ValueError, match=r"max_substeps must be in \[1, 1000000\]"):
        dyn.set_params(max_substeps=1000001)


def test_stability_limit_checks_its_numbers():
    for bad, exc in ((np.nan, ValueError), (-1.0, ValueError), ("1", TypeError), (True, TypeError)):
        with pytest.raises(exc, match="omega"):
            _core.explicit_stability_limit("explicit", bad)
        with pytest.raises(exc, match="c"):
            _core.explicit_stability_limit("explicit", 1.0, bad)
    assert _core.explicit_stability_limit("explicit", np.float32(2.0), np.int64(0)) == pytest.approx(np.sqrt(2) / 2)
    with pytest.raises(TypeError, match="area"):
        vertex_masses(4, "1", 0.08)
    for bad in ([1, 2], None, 3):
        with pytest.raises(TypeError, match="name"):
            preset(bad)


def test_parameter_dicts_name_their_keys():
    p = _core.SimulationParams()
    with pytest.raises(TypeError, match="parameter names must be str"):
        p.set_dynamics({1: 2.0})
    with pytest.raises(TypeError, match="capacity"):
        p.set_particles({"capacity": 1.5})
    with pytest.raises(ValueError, match="capacity"):
        p.set_particles({"capacity": 10**12})
    with pytest.raises(TypeError, match="birth_rate"):
        p.set_particles({"birth_rate": "many"})
    with pytest.raises(TypeError, match="heat_fast"):
        p.set_bending({"heat_fast": "x"})
    with pytest.raises(ValueError, match="alpha"):
        p.set_bending({"alpha": np.nan})


# --- closed forms of thin-sheet statics ------------------------------------------------------

def _settled(M, L, thickness, density, material, pinned_of, start, steps, **params):
    """A flat L x L lattice (thinburn.lattice.flat_rest) released from `start(rest)` with the
    vertices pinned_of(column j, layer k) held, stepped (1/24 s, implicit) to rest: its
    mid-surface (M*M x 3) and the dynamics."""
    from thinburn.lattice import flat_rest
    rest = np.asarray(flat_rest(M, L, L, thickness)).reshape(-1, 3)
    lat = _core.FfdLattice(M, rest)
    dyn = _core.LatticeDynamics(lat, **preset(material, sleeping=False, **params))
    dyn.set_masses(vertex_masses(M, L * L, density))
    idx = np.arange(2 * M * M)
    dyn.set_state(start(rest), np.zeros_like(rest))
    dyn.set_pinned(list(pinned_of(idx // 2 % M, idx % 2).astype(np.uint8)))
    D, heat = zeros(M)
    for _ in range(steps):
        dyn.step(1 / 24, D, heat)
    assert np.abs(dyn.velocities).max() < 1e-8  # at rest
    x = lat.positions
    return 0.5 * (x[0::2] + x[1::2]), dyn, rest


def _cylindrical_bending_stiffness(dyn, rest, L, kappa=0.05):
    """N m: 2 (E(kappa) - E(0)) / (kappa^2 area), the rest lattice bent about the y axis with
    curvature kappa (each vertex kept at its distance from the mid-surface)."""
    dyn.set_state(rest, np.zeros_like(rest))
    e0 = dyn.energy()
    R = 1.0 / kappa
    bent = rest.copy()
    bent[:, 0] = (R + rest[:, 2]) * np.sin(rest[:, 0] / R)
    bent[:, 2] = (R + rest[:, 2]) * np.cos(rest[:, 0] / R) - R
    dyn.set_state(bent, np.zeros_like(bent))
    return 2.0 * (dyn.energy() - e0) / (kappa**2 * L * L)


def test_a_cantilevered_paper_plate_deflects_as_euler_bernoulli_says():
    """A 0.2 m square of paper lattice (4 mm thick, 8 g/m^2: small deflection) clamped along one
    edge sags under its weight q per area by q L^4 / (8 D) at its free edge, D its cylindrical
    bending stiffness per width, measured on the lattice itself from the energy of an imposed
    bend. The lattice's clamp and its finite shear make the error first order in the spacing:
    measured tip / theory 1.273 (M = 9) and 1.131 (17): the error halves as the spacing does
    (2.08x) and the Richardson extrapolation 2 r17 - r9 = 0.988."""
    L, th, rho = 0.2, 0.004, 0.008
    ratios = []
    for M in (9, 17):
        mid, dyn, rest = _settled(M, L, th, rho, "paper", lambda j, k: j == 0, lambda r: r, 2400)
        D = _cylindrical_bending_stiffness(dyn, rest, L)
        tip = -mid[np.arange(M * M) % M == M - 1, 2].mean()
        ratios.append(tip / (rho * 9.81 * L**4 / (8 * D)))
    r9, r17 = ratios
    assert 1.7 < (r9 - 1) / (r17 - 1) < 2.4  # first order
    assert abs(2 * r17 - r9 - 1) < 0.02


def test_a_cloth_hung_by_two_edges_takes_a_catenary():
    """A 0.4 m square of cloth lattice hinged (bottom layer pinned) along two opposite edges
    brought 0.32 m apart hangs as the catenary of its length: z = a cosh(x/a) + c with
    2 a sinh(S / 2a) = L. Membrane 10x the preset's (its stretch under the weight would add
    3 % of sag) and a 2 mm lattice (its bending stiffens the ends). Measured at M = 17: sag
    1.4 % above the catenary's, profile within 1.6 % of the sag."""
    L, S, M = 0.4, 0.32, 17

    def start(rest):  # the pinned edges moved in, the rest of the sheet hanging below them
        x = rest.copy()
        x[:, 0] *= S / L
        x[:, 2] -= 0.3 * L * np.sin(np.pi * rest[:, 0] / L)
        return x

    mid, _, _ = _settled(M, L, 0.002, 0.1, "cloth", lambda j, k: ((j == 0) | (j == M - 1)) & (k == 0),
                         start, 2400, stiffness_unit=1e4)
    lo, hi = 1e-3, 100.0  # 2 a sinh(S / 2a) = L by bisection (decreasing in a)
    for _ in range(200):
        a = 0.5 * (lo + hi)
        lo, hi = (a, hi) if 2 * a * np.sinh(S / (2 * a)) > L else (lo, a)
    row = mid[np.arange(M * M) // M == M // 2]
    xs = row[:, 0] - S / 2
    z = a * np.cosh(xs / a) - a * np.cosh(S / (2 * a))
    sag = -z.min()
    assert abs(-row[:, 2].min() / sag - 1) < 0.02
    assert np.abs(row[:, 2] - z).max() < 0.025 * sag
