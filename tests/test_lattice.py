"""FFD lattice (paper §4.1): exact rest, affine precision, partition of unity, adjointness."""
import numpy as np
import pytest

import thinburn
from thinburn import _core
from thinburn.lattice import drape, flat_rest, vertex_index

INTERPS = ["trilinear", "bspline"]


def wavy_lattice(M, rng):
    t = np.linspace(0.0, 1.0, M)
    mid = np.zeros((M, M, 3))
    mid[:, :, 0] = 0.3 * t[None, :]
    mid[:, :, 1] = 0.2 * t[:, None]
    mid[:, :, 2] = 0.02 * np.sin(7 * mid[:, :, 0]) * np.cos(5 * mid[:, :, 1])
    normals = np.zeros_like(mid)
    normals[:, :, 2] = 1.0
    normals[:, :, :2] = rng.normal(scale=0.1, size=(M, M, 2))
    return drape(mid, normals, 0.004)


def random_params(M, n, rng):
    p = rng.uniform(0, 1, size=(n, 3))
    p[:, :2] *= M - 1
    p[:3, :2] = [[0, 0], [M - 1, M - 1], [0, M - 1]]  # corners and borders exactly
    return p


@pytest.mark.parametrize("interp", INTERPS)
def test_rest_reproduces_exactly(interp):
    rng = np.random.default_rng(1)
    M = 6
    lat = _core.FfdLattice(M, wavy_lattice(M, rng))
    params = random_params(M, 500, rng)
    pts = rng.normal(size=(500, 3))  # any rest points, even off the lattice
    e = lat.embed(params, pts, interp)
    assert np.array_equal(lat.deform(e), pts)


@pytest.mark.parametrize("interp", INTERPS)
def test_partition_of_unity_and_nonnegative(interp):
    rng = np.random.default_rng(2)
    M = 7
    lat = _core.FfdLattice(M, wavy_lattice(M, rng))
    e = lat.embed(random_params(M, 400, rng), np.zeros((400, 3)), interp)
    w = e.weights
    assert w.shape == (400, 4 if interp == "trilinear" else 9)
    np.testing.assert_allclose(w.sum(axis=1), 1.0, rtol=0, atol=1e-14)
    assert w.min() >= -1e-15
    # A translation of every control vertex moves every point by it (to rounding).
    shift = np.array([0.3, -1.2, 2.5])
    lat.positions = lat.rest + shift
    np.testing.assert_allclose(lat.deform(e) - e.rest, np.broadcast_to(shift, (400, 3)),
                               rtol=0, atol=1e-14)


@pytest.mark.parametrize("interp", INTERPS)
def test_affine_motion_is_reproduced(interp):
    # On a lattice that is an affine image of its parameter grid, embedded points whose rest
    # positions match their parameters follow any affine motion of the control vertices exactly.
    rng = np.random.default_rng(3)
    M = 5
    O = np.array([0.1, -0.2, 0.3])
    U, V, N = rng.normal(size=(3, 3))
    idx = np.arange(2 * M * M)
    k, c = idx % 2, idx // 2
    i, j = c // M, c % M
    rest = O + np.outer(j, U) + np.outer(i, V) + np.outer(k, N)
    lat = _core.FfdLattice(M, rest)
    params = random_params(M, 300, rng)
    pts = O + np.outer(params[:, 1], U) + np.outer(params[:, 0], V) + np.outer(params[:, 2], N)
    e = lat.embed(params, pts, interp)
    A = np.eye(3) + rng.normal(scale=0.5, size=(3, 3))
    b = rng.normal(size=3)
    lat.positions = rest @ A.T + b
    np.testing.assert_allclose(lat.deform(e), pts @ A.T + b, rtol=0, atol=1e-12)


@pytest.mark.parametrize("interp", INTERPS)
def test_scatter_is_the_transpose_of_deform(interp):
    rng = np.random.default_rng(4)
    M = 6
    lat = _core.FfdLattice(M, wavy_lattice(M, rng))
    e = lat.embed(random_params(M, 200, rng), np.zeros((200, 3)), interp)
    values = rng.normal(size=200)
    g = rng.normal(size=(2 * M * M, 3))
    lat.positions = lat.rest + g
    lhs = lat.scatter(e, values) @ g
    rhs = values @ lat.deform(e)
    assert np.abs(rhs).max() > 1e-3
    np.testing.assert_allclose(lhs, rhs, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(lat.scatter(e, np.ones(200)).sum(), 200.0, rtol=1e-13)


def test_bspline_is_c1_across_couples_and_trilinear_is_not():
    # Deform a flat lattice by a bump on one control vertex and compare one-sided slopes at an
    # interior lattice line.
    M = 6
    rest = flat_rest(M, 1.0, 1.0, 0.01)
    lat = _core.FfdLattice(M, rest)
    pos = rest.copy()
    pos[vertex_index(M, 2, 3, np.array([0, 1])), 2] += 0.1
    lat.positions = pos
    eps = 1e-6
    t = np.array([3 - 2 * eps, 3 - eps, 3.0, 3 + eps, 3 + 2 * eps])
    params = np.column_stack([np.full(5, 2.2), t, np.full(5, 0.5)])
    jumps = {}
    for interp in INTERPS:
        z = lat.deform(lat.embed(params, np.zeros((5, 3)), interp))[:, 2]
        left, right = (z[2] - z[0]) / (2 * eps), (z[4] - z[2]) / (2 * eps)
        jumps[interp] = abs(right - left)
    assert jumps["trilinear"] > 1e-2
    assert jumps["bspline"] < 1e-6


def test_deform_is_thread_independent_and_writes_in_place():
    rng = np.random.default_rng(5)
    M = 12
    lat = _core.FfdLattice(M, wavy_lattice(M, rng))
    e = lat.embed(random_params(M, 20000, rng), rng.normal(size=(20000, 3)), "bspline")
    lat.positions = lat.rest + rng.normal(scale=0.01, size=(2 * M * M, 3))
    old = thinburn.get_threads()
    try:
        thinburn.set_threads(1)
        a = lat.deform(e)
        thinburn.set_threads(2)
        out = np.empty((20000, 3))
        lat.deform_into(e, out)
    finally:
        thinburn.set_threads(old)
    assert np.array_equal(a, out)


@pytest.mark.parametrize("interp", INTERPS)
def test_deform_matches_the_stencil_sum(interp):
    """deform against the formula in numpy: rest + sum_q w_q ((1 - r) d_bottom + r d_top)."""
    rng = np.random.default_rng(8)
    M = 6
    lat = _core.FfdLattice(M, wavy_lattice(M, rng))
    lat.positions = lat.rest + rng.normal(scale=0.01, size=(2 * M * M, 3))
    e = lat.embed(random_params(M, 500, rng), rng.normal(size=(500, 3)), interp)
    d = lat.positions - lat.rest
    bottom, top = d[2 * e.couples], d[2 * e.couples + 1]
    r = e.r[:, None, None]
    ref = e.rest + np.sum(e.weights[:, :, None] * ((1 - r) * bottom + r * top), axis=1)
    assert np.allclose(lat.deform(e), ref, rtol=0, atol=1e-15)


def test_deform_refuses_an_embedding_of_a_larger_lattice():
    big = _core.FfdLattice(5, flat_rest(5, 1.0, 1.0, 0.01))
    small = _core.FfdLattice(3, flat_rest(3, 1.0, 1.0, 0.01))
    e = big.embed(np.array([[0.5, 0.5, 0.5], [3.5, 3.5, 0.5]]), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="does not fit"):
        small.deform(e)
    with pytest.raises(ValueError, match="out must have"):
        big.deform_into(e, np.empty((3, 3)))


def test_concurrent_deforms_keep_their_own_tables():
    """deform releases the GIL and keeps its displacement table per calling thread: two Python
    threads deforming different lattices at once get exactly the serial results."""
    from concurrent.futures import ThreadPoolExecutor
    rng = np.random.default_rng(9)
    jobs = []
    for M in (4, 9):
        lat = _core.FfdLattice(M, wavy_lattice(M, rng))
        lat.positions = lat.rest + rng.normal(scale=0.01, size=(2 * M * M, 3))
        jobs.append((lat, lat.embed(random_params(M, 20000, rng), rng.normal(size=(20000, 3)), "bspline")))
    serial = [lat.deform(e) for lat, e in jobs]
    with ThreadPoolExecutor(2) as pool:
        results = list(pool.map(lambda k: [jobs[k % 2][0].deform(jobs[k % 2][1]) for _ in range(20)], range(4)))
    for k, res in enumerate(results):
        for out in res:
            assert np.array_equal(out, serial[k % 2])


def test_bad_input_names_the_argument():
    rest = flat_rest(3, 1.0, 1.0, 0.01)
    with pytest.raises(ValueError, match="M must be"):
        _core.FfdLattice(1, rest[:2])
    with pytest.raises(ValueError, match="rest must have"):
        _core.FfdLattice(4, rest)
    lat = _core.FfdLattice(3, rest)
    with pytest.raises(ValueError, match="params"):
        lat.embed(np.array([[0.0, 2.5, 0.5]]), np.zeros((1, 3)))
    with pytest.raises(ValueError, match="params"):
        lat.embed(np.array([[0.0, 0.5, np.nan]]), np.zeros((1, 3)))
    with pytest.raises(ValueError, match="rest_points"):
        lat.embed(np.zeros((2, 3)), np.zeros((1, 3)))
    with pytest.raises(ValueError, match="interp"):
        lat.embed(np.zeros((1, 3)), np.zeros((1, 3)), "cubic")
    with pytest.raises(ValueError, match="positions"):
        lat.positions = np.zeros((5, 3))
    with pytest.raises(ValueError, match="thickness"):
        flat_rest(3, 1.0, 1.0, 0.0)


def test_drape_places_couples_across_the_surface():
    M = 3
    mid = np.random.default_rng(6).normal(size=(M, M, 3))
    normals = np.zeros((M, M, 3))
    normals[..., 1] = 2.0
    rest = drape(mid, normals, 0.01)
    np.testing.assert_allclose(rest[1::2] - rest[0::2], np.tile([0, 0.01, 0], (M * M, 1)),
                               atol=1e-15)
    np.testing.assert_allclose(0.5 * (rest[1::2] + rest[0::2]), mid.reshape(-1, 3), atol=1e-15)
    with pytest.raises(ValueError, match="mid"):
        drape(mid[:2], normals, 0.01)
    with pytest.raises(ValueError, match="normals"):
        drape(mid, normals[:, :2], 0.01)
    with pytest.raises(ValueError, match="normals must be non-zero"):
        drape(mid, np.zeros_like(mid), 0.01)
    with pytest.raises(ValueError, match="M must be"):
        flat_rest(1, 1.0, 1.0, 0.01)


def test_index_and_builders_name_their_arguments():
    lat = _core.FfdLattice(3, flat_rest(3, 1.0, 1.0, 0.1))
    assert lat.index(2, 1, 1) == ((2 * 3) + 1) * 2 + 1
    for args, name in (((3, 0, 0), "i"), ((-1, 0, 0), "i"), ((0, 3, 0), "j"), ((0, 0, 2), "k")):
        with pytest.raises(ValueError, match=f"^{name} must"):
            lat.index(*args)
    with pytest.raises(TypeError, match="width"):
        flat_rest(3, "1", 1.0, 0.1)
    with pytest.raises(ValueError, match="height"):
        flat_rest(3, 1.0, np.nan, 0.1)
    with pytest.raises(ValueError, match="origin"):
        flat_rest(3, 1.0, 1.0, 0.1, origin=(0.0, 0.0))
    with pytest.raises(TypeError, match="thickness"):
        drape(np.zeros((2, 2, 3)), np.ones((2, 2, 3)), "x")
    for bad in ("x", {"a": 1}, np.full((2, 2, 3), 1 + 2j)):
        with pytest.raises(TypeError, match="mid"):
            drape(bad, np.ones((2, 2, 3)), 0.1)
    with pytest.raises(ValueError, match="normals"):
        drape(np.zeros((2, 2, 3)), np.ones((2, 2)), 0.1)
    assert flat_rest(np.int64(3), np.float32(1.0), 1, 0.1).shape == (18, 3)


def test_assigning_positions_names_them():
    lat = _core.FfdLattice(3, flat_rest(3, 1.0, 1.0, 0.1))
    for bad in ("x", None, {"a": 1}, np.zeros((18, 3)) + 1j, np.zeros((18, 3), bool)):
        with pytest.raises(TypeError, match="positions"):
            lat.positions = bad  # was pybind's 'incompatible function arguments' naming no one
    for bad in (np.nan, np.zeros((18, 2)), np.full((18, 3), np.inf)):
        with pytest.raises(ValueError, match="positions"):
            lat.positions = bad
    lat.positions = np.asfortranarray(lat.rest + 1.0)
    np.testing.assert_array_equal(lat.positions, lat.rest + 1.0)
    lat.positions = np.zeros((18, 3), dtype=np.int32)
    assert np.all(lat.positions == 0.0)
