"""The block LDLT factorization (cpp/block_ldlt.*, `_core.block_ldlt_solve`): random SPD block
systems and a lattice's implicit system against numpy, and the errors it names."""
import numpy as np
import pytest

from thinburn import _core
from thinburn.dynamics import vertex_masses
from lattice_cases import make


def block_pattern(A, n):
    """The lower block triangle of a dense (3n, 3n) matrix, as block_ldlt_solve takes it."""
    col_start, rows, blocks = [0], [], []
    for j in range(n):
        for i in range(j, n):
            b = A[3 * i:3 * i + 3, 3 * j:3 * j + 3]
            if i == j or np.any(b):
                rows.append(i)
                blocks.append(b)
        col_start.append(len(rows))
    return col_start, rows, np.array(blocks).reshape(-1, 3, 3)


def random_spd_blocks(n, density, seed):
    rng = np.random.default_rng(seed)
    A = np.zeros((3 * n, 3 * n))
    for i in range(n):
        for j in range(i + 1, n):
            if rng.random() < density:
                B = rng.normal(size=(3, 3))
                A[3 * i:3 * i + 3, 3 * j:3 * j + 3] = B
                A[3 * j:3 * j + 3, 3 * i:3 * i + 3] = B.T
    G = rng.normal(size=(3 * n, 3 * n))
    for i in range(n):  # dense SPD diagonal blocks; diagonal dominance makes A SPD
        A[3 * i:3 * i + 3, 3 * i:3 * i + 3] = G[3 * i:3 * i + 3, :3] @ G[3 * i:3 * i + 3, :3].T
    return A + np.eye(3 * n) * (np.abs(A).sum(axis=1).max() + 1.0)


def test_block_ldlt_of_an_empty_system_is_empty():
    x, fill = _core.block_ldlt_solve(0, [0], [], np.zeros((0, 3, 3)), np.zeros(0))
    assert x.shape == (0,) and fill == 0


@pytest.mark.parametrize("n, density", [(1, 0.0), (2, 1.0), (12, 0.0), (40, 0.1), (60, 1.0)])
def test_block_ldlt_solves_spd_block_systems(n, density):
    A = random_spd_blocks(n, density, seed=n)
    b = np.random.default_rng(0).normal(size=3 * n)
    x, fill = _core.block_ldlt_solve(n, *block_pattern(A, n), b)
    # Backward stable: the residual is at rounding level relative to |A| |x|.
    assert np.abs(A @ x - b).max() <= 1e-13 * np.abs(A).max() * np.abs(x).max() * 3 * n
    assert fill <= n * (n - 1) // 2


def test_block_ldlt_solves_the_lattice_system():
    # The implicit system M + h^2 K (K = -dF/dx) of a stretched, jittered lattice: every spring
    # in tension keeps K positive semidefinite, as the solver's clamped Jacobian is. The same
    # kind of solve the preconditioner does, against numpy's dense solve.
    M, h = 7, 1 / 24
    lat, dyn = make(M)
    rng = np.random.default_rng(5)
    lat.positions = 1.05 * lat.rest + rng.normal(scale=1e-5, size=lat.rest.shape)
    m = vertex_masses(M, ((M - 1) * 0.03) ** 2, 0.08)
    A = np.diag(np.repeat(m, 3)) - h * h * dyn.stiffness_matrix()
    A = 0.5 * (A + A.T)
    n = 2 * M * M
    b = rng.normal(size=3 * n)
    col_start, rows, blocks = block_pattern(A, n)
    x, fill = _core.block_ldlt_solve(n, col_start, rows, blocks, b)
    np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=0, atol=1e-10 * np.abs(x).max())
    # The fill-reducing order keeps L well short of dense.
    assert len(rows) - n < fill < 0.5 * n * (n - 1) / 2


def test_block_ldlt_rejects_what_it_cannot_factor():
    A = random_spd_blocks(5, 0.5, seed=1)
    with pytest.raises(ValueError, match="not positive definite"):
        _core.block_ldlt_solve(5, *block_pattern(-A, 5), np.ones(15))
    col_start, rows, blocks = block_pattern(A, 5)
    with pytest.raises(ValueError, match="rhs must have"):
        _core.block_ldlt_solve(5, col_start, rows, blocks, np.ones(14))
    with pytest.raises(ValueError, match="blocks must have shape"):
        _core.block_ldlt_solve(5, col_start, rows, blocks[:-1], np.ones(15))
    with pytest.raises(ValueError, match="blocks must be finite"):
        _core.block_ldlt_solve(5, col_start, rows, np.where(blocks == blocks.max(), np.nan, blocks), np.ones(15))
    with pytest.raises(ValueError, match="rhs must be finite"):
        _core.block_ldlt_solve(5, col_start, rows, blocks, np.full(15, np.inf))
    with pytest.raises(ValueError, match="must start at 0"):
        _core.block_ldlt_solve(5, [1] + col_start[1:], rows, blocks, np.ones(15))
    with pytest.raises(ValueError, match="must not decrease"):
        _core.block_ldlt_solve(5, [0, 3, 1] + col_start[3:], rows, blocks, np.ones(15))
    with pytest.raises(ValueError, match=r"n \+ 1 entries"):
        _core.block_ldlt_solve(5, col_start[:-1], rows, blocks, np.ones(15))
    bad_rows = list(rows)
    bad_rows[-1] = 0  # a row above the diagonal of the last column
    with pytest.raises(ValueError, match="a row outside"):
        _core.block_ldlt_solve(5, col_start, bad_rows, blocks, np.ones(15))
