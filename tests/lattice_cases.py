"""The flat lattices and parameter sets the dynamics tests build (test_dynamics, test_crumple,
test_contact, test_sleeping, test_implicit_solver, test_block_ldlt, test_membrane,
test_strain_limit, test_params), in one place so that each of them builds the same numbers.
Imported as `from lattice_cases import ...`: pytest puts tests/ on the path (rootdir-based
import, tests/ has no __init__.py), as tests/blender's modules import blender_helpers."""
import numpy as np

from thinburn import _core
from thinburn.dynamics import vertex_masses
from thinburn.lattice import vertex_index

INTEGRATORS = ["explicit", "symplectic", "implicit"]
SPRINGS_OFF = dict(k_structure=0.0, k_shear=0.0, k_flex=0.0, k_thickness=0.0, k_transverse=0.0)
# Fig. 5's prescribed chord motion, as the paper reads it; the core's default is the bimetal
# curl (docs/dynamics.md §2), so the tests of the chord ask for it.
CHORD = dict(bimetal=False, crumple_momentum=False)


def grid_rest(M, L, thickness, centred=True):
    """Flat M x M lattice of spacing L, layers at z = -+thickness / 2, couple (i, j) at x = j L,
    y = i L; centred: symmetric about x = 0 and y = 0 (exactly: coordinates are (j - (M-1)/2) L)."""
    idx = np.arange(2 * M * M)
    k, c = idx % 2, idx // 2
    i, j = c // M, c % M
    if centred:
        return np.column_stack([(j - (M - 1) / 2) * L, (i - (M - 1) / 2) * L, (k - 0.5) * thickness])
    return np.column_stack([j * L, i * L, (k - 0.5) * thickness])


def make(M=6, L=0.03, thickness=0.003, density=0.08, centred=True, **params):
    """grid_rest's lattice and its LatticeDynamics(**params), masses of a sheet of `density`
    kg/m^2 over the lattice's (M-1) L square."""
    lat = _core.FfdLattice(M, grid_rest(M, L, thickness, centred))
    dyn = _core.LatticeDynamics(lat, **params)
    dyn.set_masses(vertex_masses(M, ((M - 1) * L) ** 2, density))
    return lat, dyn


def zeros(M):
    """Zero D (per couple) and heat (per vertex): a step with no fire."""
    return np.zeros(M * M), np.zeros(2 * M * M)


def rotate(p, centre, axis, angle):
    axis = axis / np.linalg.norm(axis)
    q = p - centre
    par = q @ axis * axis
    perp = q - par
    return centre + par + np.cos(angle) * perp + np.sin(angle) * np.cross(axis, perp)


def expected_crumple(lat, M, oi, oj, delta):
    """Neighbours of couple (oi, oj) turned about the lines through its centre, toward +z."""
    rest = lat.rest
    out = rest.copy()
    centre = 0.5 * (rest[vertex_index(M, oi, oj, 0)] + rest[vertex_index(M, oi, oj, 1)])
    for di, dj in [(-1, 0), (1, 0), (0, -1), (0, 1)]:
        axis = np.array([1.0, 0, 0]) if di else np.array([0, 1.0, 0])
        ni, nj = oi + di, oj + dj
        nc = 0.5 * (rest[vertex_index(M, ni, nj, 0)] + rest[vertex_index(M, ni, nj, 1)])
        angle = abs(delta)
        if (rotate(nc, centre, axis, angle)[2] - nc[2]) * delta < 0:
            angle = -angle
        for k in (0, 1):
            v = vertex_index(M, ni, nj, k)
            out[v] = rotate(rest[v], centre, axis, angle)
    return out
