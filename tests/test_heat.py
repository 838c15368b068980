"""Heat (eq 2) and pyrolysis (eq 3) kernel sums: closed forms, fast vs direct, the bound."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import thinburn
from thinburn import _core
from thinburn.heat import KernelSummer, kernel_sum, particle_heat, pyrolysis
from thinburn.particles import ParticleSystem

# The direct reference itself carries rounding of order n * eps; fast results are compared
# with it up to the stated tolerance plus this slack.
ROUND = 1e-11


def check_fast(src, w, tgt, power, tol, d_min=0.01):
    """Fast within tol of direct; the returned bound bounds the error and is <= tol * sum."""
    exact = kernel_sum(src, w, tgt, power=power, d_min=d_min, method="direct")
    fast, bound = kernel_sum(src, w, tgt, power=power, d_min=d_min, method="fast",
                             tolerance=tol, return_bound=True)
    err = np.abs(fast - exact)
    assert np.all(err <= bound + ROUND * exact)
    assert np.all(bound <= tol * exact * (1 + 1e-9))
    assert np.all(err <= (tol + ROUND) * exact)
    return err, bound, exact


def lattice(m, z):
    g = (np.arange(m) + 0.5) / m - 0.5
    x, y = np.meshgrid(g, g)
    return np.c_[x.ravel(), y.ravel(), np.full(m * m, z)]


# --- closed forms -------------------------------------------------------------------------

@pytest.mark.parametrize("method", ["direct", "fast"])
@pytest.mark.parametrize("d", [0.0, 1e-3, 0.05, 0.7, 12.0])
def test_single_particle_heat_matches_eq2(method, d):
    ct, temp, dt, d_min = 0.37, 640.0, 1.0 / 60.0, 0.01
    src = np.array([[0.1, -0.2, 0.3]])
    tgt = src + d * np.array([[0.6, 0.0, 0.8]])
    got = particle_heat(src, [temp], tgt, ct=ct, dt=dt, d_min=d_min, method=method)
    want = ct * temp * dt / (4 * math.pi * (d + d_min) ** 2)
    assert got[0] == pytest.approx(want, rel=1e-12)


@pytest.mark.parametrize("method", ["direct", "fast"])
def test_single_ignition_point_pyrolysis_matches_eq3(method):
    src = np.array([[0.0, 0.0, 0.0]])
    tgt = np.array([[0.3, 0.4, 0.0], [0.0, 0.0, 0.0]])
    got = pyrolysis(src, tgt, cp=0.8, d_min=0.02, method=method)
    np.testing.assert_allclose(got, [0.8 / 0.52, 0.8 / 0.02], rtol=1e-12)


def test_heat_is_linear_in_weights_and_additive():
    rng = np.random.default_rng(3)
    src, tgt = rng.random((50, 3)), rng.random((7, 3))
    w = rng.random(50)
    both = kernel_sum(src, w, tgt, method="direct")
    parts = kernel_sum(src[:20], w[:20], tgt, method="direct") + \
        kernel_sum(src[20:], w[20:], tgt, method="direct")
    np.testing.assert_allclose(both, parts, rtol=1e-13)
    np.testing.assert_allclose(kernel_sum(src, 3 * w, tgt, method="direct"), 3 * both, rtol=1e-13)


# --- fast vs direct ------------------------------------------------------------------------

def cloud(kind, n, rng):
    if kind == "uniform":
        return rng.random((n, 3))
    if kind == "clustered":
        centres = rng.random((5, 3))
        return centres[rng.integers(0, 5, n)] + 0.01 * rng.normal(size=(n, 3))
    if kind == "coincident":
        base = rng.random((max(1, n // 10), 3))
        pts = base[rng.integers(0, len(base), n)]
        pts[: n // 2] += 1e-12 * rng.normal(size=(n // 2, 3))  # half exactly coincident
        return pts
    if kind == "flat":
        p = rng.random((n, 3))
        p[:, 2] = 0.0
        return p
    raise ValueError(kind)


@pytest.mark.parametrize("power", [1, 2])
@pytest.mark.parametrize("kind", ["uniform", "clustered", "coincident", "flat"])
@pytest.mark.parametrize("n", [1, 2, 33, 500, 5000])
def test_fast_within_tolerance_random_clouds(kind, n, power):
    rng = np.random.default_rng(n * 10 + power)
    src = cloud(kind, n, rng)
    w = rng.random(n) * (rng.random(n) < 0.9)  # some zero weights
    tgt = np.r_[rng.random((150, 3)) * 1.4 - 0.2, src[:20]]  # inside, outside, on a source
    check_fast(src, w, tgt, power, tol=0.01)


@pytest.mark.parametrize("power", [1, 2])
def test_fast_within_tolerance_20000_sources(power):
    rng = np.random.default_rng(power)
    src = np.r_[cloud("uniform", 10000, rng), cloud("clustered", 10000, rng)]
    w = rng.random(20000)
    tgt = rng.random((200, 3))
    err, bound, exact = check_fast(src, w, tgt, power, tol=0.01)
    assert bound.max() > 0.0  # the tree did approximate


@pytest.mark.parametrize("tol", [0.3, 1e-3, 1e-6])
@pytest.mark.parametrize("d_min", [1e-6, 0.01, 1.0])
def test_fast_honours_every_tolerance_and_d_min(tol, d_min):
    rng = np.random.default_rng(7)
    src = cloud("clustered", 3000, rng)
    check_fast(src, rng.random(3000), rng.random((100, 3)), 2, tol=tol, d_min=d_min)
    check_fast(src, rng.random(3000), rng.random((100, 3)), 1, tol=tol, d_min=d_min)


def fire_front(shape, n_steps=25, seed=0):
    """Particles from a burning ring or line on the sheet z = 0, in a light wind."""
    ps = ParticleSystem(seed=seed, birth_rate=20000.0)
    k = 200
    if shape == "ring":
        a = np.linspace(0, 2 * np.pi, k, endpoint=False)
        pos = np.c_[0.3 * np.cos(a), 0.3 * np.sin(a), np.zeros(k)]
        length = np.full(k, 2 * np.pi * 0.3 / k)
    else:
        pos = np.c_[np.linspace(-0.4, 0.4, k), np.full(k, -0.1), np.zeros(k)]
        length = np.full(k, 0.8 / k)
    normal = np.tile([0.0, 0.0, 1.0], (k, 1))
    for _ in range(n_steps):
        ps.emit(pos, normal, length, 1 / 60)
        ps.step(1 / 60, (0.3, 0.0, 0.0))
    return ps.positions(), ps.temperatures()


@pytest.mark.parametrize("power", [1, 2])
@pytest.mark.parametrize("shape", ["ring", "line"])
def test_fast_within_tolerance_fire_front(shape, power):
    x, t = fire_front(shape)
    assert len(x) > 2000
    tgt = np.r_[lattice(32, 0.002), lattice(32, -0.002)]
    err, bound, exact = check_fast(x, t, tgt, power, tol=0.01)
    assert bound.max() > 0.0


def test_taylor_remainder_bound_on_single_cells():
    """One leaf accepted as a whole at ratios rho/D up to 0.9, in many directions, for the
    worst-shaped cells (poles, shells, lines): the error must stay within the bound."""
    rng = np.random.default_rng(11)
    shapes = {
        "poles": np.array([[0, 0, 1.0], [0, 0, -1.0]] * 8),
        "shell": (lambda v: v / np.linalg.norm(v, axis=1, keepdims=True))(rng.normal(size=(30, 3))),
        "line": np.c_[np.zeros(30), np.zeros(30), np.linspace(-1, 1, 30)],
        "lopsided": np.r_[np.zeros((20, 3)), [[0, 0, 1.0]]],
    }
    for name, cell in shapes.items():
        w = rng.random(len(cell)) + 0.1
        for ratio in (0.9, 0.6, 0.3, 0.1):
            dirs = rng.normal(size=(40, 3))
            dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
            tgt = np.r_[dirs / ratio, [[0, 0, 1 / ratio], [0, 0, -1 / ratio]]]
            for power in (1, 2):
                for d_min in (1e-4, 0.3):
                    check_fast(cell, w, tgt, power, tol=0.99, d_min=d_min)


def fourth_derivative_bound(r, p, d_min):
    """M4(r) of docs/heat.md, as the C++ core computes it."""
    v, ir = 1.0 / (r + d_min), 1.0 / r
    g1 = p * v ** (p + 1)
    g2 = (p + 1) * g1 * v
    g3 = (p + 2) * g2 * v
    g4 = (p + 3) * g3 * v
    a, b, d = g4, 6 * g3 * ir, 3 * ir * ir * (g2 + g1 * ir)
    return max(a, d, 0.25 * b + 0.8 * d)


def test_fourth_derivative_bound_against_high_precision_derivatives():
    """|d^4/dt^4 K(|x + t e|)| <= M4(|x|) for unit e, and M4 is nearly attained."""
    mp = pytest.importorskip("mpmath")
    mp.mp.dps = 40
    rng = np.random.default_rng(0)
    worst = 0.0
    for _ in range(200):
        p, d_min = int(rng.integers(1, 3)), 10 ** rng.uniform(-4, 0)
        x = rng.normal(size=3)
        x *= 10 ** rng.uniform(-2, 1) / np.linalg.norm(x)
        e = rng.normal(size=3)
        e /= np.linalg.norm(e)
        if rng.random() < 0.2:  # near-perpendicular directions, where the bound is tight
            e -= (e @ x) / (x @ x) * x * (1 - 1e-3)
            e /= np.linalg.norm(e)
        xm, em = [mp.mpf(float(c)) for c in x], [mp.mpf(float(c)) for c in e]

        def k(t):
            r = mp.sqrt(sum((xm[i] + t * em[i]) ** 2 for i in range(3)))
            return (r + mp.mpf(d_min)) ** (-p)

        d4 = abs(float(mp.diff(k, 0, 4)))
        ratio = d4 / fourth_derivative_bound(float(np.linalg.norm(x)), p, d_min)
        assert ratio <= 1 + 1e-9
        worst = max(worst, ratio)
    assert worst > 0.99


@settings(max_examples=40, deadline=None)
@given(n=st.integers(1, 300), seed=st.integers(0, 2**31), power=st.sampled_from([1, 2]),
       scale=st.sampled_from([1e-3, 1.0, 1e3]), tol=st.sampled_from([0.5, 0.01, 1e-4]))
def test_fast_bound_property(n, seed, power, scale, tol):
    rng = np.random.default_rng(seed)
    src = cloud("clustered", n, rng) * scale
    tgt = rng.random((20, 3)) * scale
    check_fast(src, rng.random(n), tgt, power, tol=tol, d_min=0.01 * scale)


# --- structure, reuse, determinism --------------------------------------------------------

def test_degenerate_inputs():
    rng = np.random.default_rng(0)
    tgt = rng.random((5, 3))
    for method in ("direct", "fast"):
        np.testing.assert_array_equal(kernel_sum(np.zeros((0, 3)), [], tgt, method=method), 0.0)
        np.testing.assert_array_equal(kernel_sum(rng.random((9, 3)), np.zeros(9), tgt,
                                                 method=method), 0.0)
        assert kernel_sum(rng.random((9, 3)), np.ones(9), np.zeros((0, 3)),
                          method=method).shape == (0,)
    # 1000 copies of one point equal one point of 1000 times the weight
    one = kernel_sum([[0.2, 0.2, 0.2]], [1000.0], tgt, method="direct")
    many = kernel_sum(np.tile([0.2, 0.2, 0.2], (1000, 1)), np.ones(1000), tgt, tolerance=1e-3)
    np.testing.assert_allclose(many, one, rtol=1e-12)


def test_summer_reuse_matches_free_function():
    rng = np.random.default_rng(5)
    ks = KernelSummer()
    tgt = rng.random((60, 3))
    for n in (4000, 300, 2500):  # grow, shrink, grow: buffers reused
        src, w = cloud("clustered", n, rng), rng.random(n)
        ks.build(src, w)
        assert ks.size == n and ks.node_count >= 1
        for power in (1, 2):
            a, ba = ks.evaluate(tgt, power=power, return_bound=True)
            b, bb = kernel_sum(src, w, tgt, power=power, return_bound=True)
            np.testing.assert_array_equal(a, b)
            np.testing.assert_array_equal(ba, bb)
            np.testing.assert_array_equal(ks.evaluate(tgt, power=power, method="direct"),
                                          kernel_sum(src, w, tgt, power=power, method="direct"))


def test_bit_identical_for_any_thread_count():
    x, t = fire_front("ring", n_steps=10)
    tgt = np.r_[lattice(24, 0.002), lattice(24, -0.002)]
    old = _core.num_threads()
    try:
        res = {}
        for n in (1, 2):
            _core.set_num_threads(n)
            res[n] = [kernel_sum(x, t, tgt, power=p, method=m, return_bound=True)
                      for p in (1, 2) for m in ("direct", "fast")]
    finally:
        _core.set_num_threads(old)
    for (a, ba), (b, bb) in zip(res[1], res[2]):
        assert a.tobytes() == b.tobytes() and ba.tobytes() == bb.tobytes()


# --- validation ---------------------------------------------------------------------------

GOOD = dict(sources=np.zeros((2, 3)), weights=np.ones(2), targets=np.ones((3, 3)))


@pytest.mark.parametrize("change, exc, name", [
    (dict(sources=np.zeros((2, 2))), ValueError, "sources"),
    (dict(sources=np.zeros(6)), ValueError, "sources"),
    (dict(sources=[["a", "b", "c"]] * 2), TypeError, "sources"),
    (dict(sources=[[0, 0, np.nan], [0, 0, 0]]), ValueError, "sources"),
    (dict(weights=[1.0, -1.0]), ValueError, "weights"),
    (dict(weights=[1.0]), ValueError, "weights"),
    (dict(weights=[1.0, np.inf]), ValueError, "weights"),
    (dict(targets=np.zeros((3, 4))), ValueError, "targets"),
    (dict(targets=[[np.inf, 0, 0]]), ValueError, "targets"),
    (dict(power=3), ValueError, "power"),
    (dict(power=2.0), TypeError, "power"),
    (dict(power=True), TypeError, "power"),
    (dict(d_min=0.0), ValueError, "d_min"),
    (dict(d_min=np.nan), ValueError, "d_min"),
    (dict(d_min="1"), TypeError, "d_min"),
    (dict(tolerance=0.0), ValueError, "tolerance"),
    (dict(tolerance=1.0), ValueError, "tolerance"),
    (dict(method="slow"), ValueError, "method"),
    (dict(method=1), TypeError, "method"),
    (dict(return_bound="yes"), TypeError, "return_bound"),
    (dict(cutoff=-0.1), ValueError, "cutoff"),
    (dict(cutoff=np.inf), ValueError, "cutoff"),
])
def test_bad_input_names_the_argument(change, exc, name):
    with pytest.raises(exc, match=name):
        kernel_sum(**{**GOOD, **change})


@pytest.mark.parametrize("power", [1, 2])
def test_cutoff_sums_the_truncated_kernel_exactly(power):
    # docs/dynamics.md §2, "Pyrolysis reaches as far as": K(d) - K(cutoff) over the sources
    # closer than the cutoff, against numpy over every pair (clouds spanning many grid cells,
    # sources on cell boundaries included); within rounding (measured 1e-15 relative).
    rng = np.random.default_rng(7)
    src = rng.uniform(-0.3, 0.3, (4000, 3))
    src[:50] = np.round(src[:50] / 0.05) * 0.05  # exactly on the grid's cell walls
    w = rng.uniform(0.0, 2.0, len(src))
    tgt = np.vstack([rng.uniform(-0.35, 0.35, (300, 3)), src[:20]])
    cutoff, d_min = 0.05, 0.005
    d = np.linalg.norm(tgt[:, None, :] - src[None, :, :], axis=2)
    K = lambda x: (x + d_min) ** -power  # noqa: E731
    want = np.where(d < cutoff, w * (K(d) - K(cutoff)), 0.0).sum(axis=1)
    got = kernel_sum(src, w, tgt, power=power, d_min=d_min, cutoff=cutoff)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
    # Two targets 1 cm apart (a couple's top and bottom) with every source within the cutoff of
    # both: their difference is the untruncated kernel's.
    near = np.array([[0.0, 0.0, 0.005], [0.0, 0.0, -0.005]])
    cloud = rng.uniform(-0.015, 0.015, (500, 3))
    full = pyrolysis(cloud, near, cp=1.0, d_min=d_min, method="direct")
    cut = pyrolysis(cloud, near, cp=1.0, d_min=d_min, cutoff=cutoff)
    assert abs((cut[0] - cut[1]) - (full[0] - full[1])) < 1e-9 * abs(full[0])


def test_core_validates_too():
    with pytest.raises(ValueError, match="weights"):
        _core.kernel_sum(np.zeros((2, 3)), np.array([1.0, -1.0]), np.ones((1, 3)))
    with pytest.raises(ValueError, match="d_min"):
        _core.kernel_sum(np.zeros((2, 3)), np.ones(2), np.ones((1, 3)), d_min=-1.0)
    with pytest.raises(ValueError, match="method"):
        _core.kernel_sum(np.zeros((2, 3)), np.ones(2), np.ones((1, 3)), method="slow")
    with pytest.raises(ValueError, match="temperatures|weights"):
        particle_heat(np.zeros((2, 3)), [1.0, -1.0], np.ones((1, 3)), ct=1.0, dt=0.1)
    with pytest.raises(ValueError, match="ct"):
        particle_heat(np.zeros((2, 3)), [1.0, 1.0], np.ones((1, 3)), ct=-1.0, dt=0.1)
    with pytest.raises(ValueError, match="dt"):
        particle_heat(np.zeros((2, 3)), [1.0, 1.0], np.ones((1, 3)), ct=1.0, dt=-0.1)
    with pytest.raises(ValueError, match="cp"):
        pyrolysis(np.zeros((2, 3)), np.ones((1, 3)), cp=np.inf)
    with pytest.raises(ValueError, match="vertices"):
        pyrolysis(np.zeros((2, 3)), np.ones((1, 2)), cp=1.0)
