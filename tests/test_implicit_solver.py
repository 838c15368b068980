"""The implicit solve's preconditioners (cpp/implicit_solver.*, docs/dynamics.md §4): the block
LDLT factor and Jacobi solve the same system, the factor is kept over solves, and a fresh
factor is exact."""
import numpy as np

from lattice_cases import CHORD, make, zeros


def crumpling_on_floor(preconditioner, frames=24, M=7, **params):
    """A lattice resting on a floor while a growing D crumples it: moving vertices, contacts,
    sleepers waking and falling asleep (the chord crumple: it moves the lattice more than the
    bimetal curl)."""
    lat, dyn = make(M, has_floor=True, floor_z=-0.0015, preconditioner=preconditioner,
                    **{**CHORD, **params})
    D, heat = zeros(M)
    stats = []
    for f in range(frames):
        D[:] = 0.01 * f * np.sin(np.arange(M * M))
        stats.append(dyn.step(1 / 24, D, heat))
    return lat, dyn, stats


def test_ldlt_and_jacobi_solve_the_same_system():
    # Both stop the conjugate gradients at the same residual test on the same system. Each solve
    # may leave a velocity error up to about cg_velocity_tolerance (1e-7 m/s); kept over the
    # following frames it moves a vertex by at most frames^2 * dt * 1e-7 = 2.4e-6 m.
    frames, dt = 24, 1 / 24
    lat_l, _, st_l = crumpling_on_floor("ldlt", frames)
    lat_j, _, st_j = crumpling_on_floor("jacobi", frames)
    moved = np.abs(lat_j.positions - lat_j.rest).max()
    assert moved > 1e-2
    np.testing.assert_allclose(lat_l.positions, lat_j.positions, rtol=0, atol=frames**2 * dt * 1e-7)
    factorizations = sum(s.factorizations for s in st_l)
    assert factorizations > 0 and sum(s.factorizations for s in st_j) == 0
    # The factor is kept over some solves, and it saves most of the iterations.
    assert factorizations < sum(s.substeps * s.passes for s in st_l)
    assert sum(s.cg_iterations for s in st_l) < 0.2 * sum(s.cg_iterations for s in st_j)


def test_a_fresh_factorization_is_exact():
    # refactor_iterations=0 refactors before every solve but the first's follow-ups; a solve
    # that starts from a fresh factor of its own matrix is P = A^-1: one iteration suffices.
    M = 5
    lat, dyn = make(M, preconditioner="ldlt", refactor_iterations=0, sleeping=False, gravity=[0, 0, -9.81])
    D, heat = zeros(M)
    for f in range(6):
        D[:] = 0.02 * f * np.cos(np.arange(M * M))
        st = dyn.step(1 / 24, D, heat)
        assert st.factorizations == st.substeps  # one per solve: no contacts, no passes
        assert st.cg_iterations <= st.substeps
