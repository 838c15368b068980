"""The implicit solve's preconditioners (cpp/implicit_solver.*, docs/dynamics.md §4): the block
LDLT factor and Jacobi solve the same system, the factor is kept over solves, and a fresh
factor is exact."""
import numpy as np

import thinburn

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




def _auto_against_forced(dt, frames=300, M=7, threads=(1,)):
    """The crumpling lattice with auto above its threshold (ldlt_max_vertices=1), at each
    thread count, and with each preconditioner forced, at steps of dt: positions and the
    solves the factor preconditioned (the forced factor's count is every solve, contact rounds
    included)."""
    runs = [(f"auto{t}", "auto", t, dict(ldlt_max_vertices=1)) for t in threads]
    runs += [("ldlt", "ldlt", 1, {}), ("jacobi", "jacobi", 1, {})]
    out, old = {}, thinburn.get_threads()
    try:
        for key, name, t, extra in runs:
            thinburn.set_threads(t)
            lat, dyn = make(M, has_floor=True, floor_z=-0.0015, preconditioner=name, **{**CHORD, **extra})
            D, heat = zeros(M)
            solves = 0
            for f in range(frames):
                D[:] = 0.001 * f * np.sin(np.arange(M * M))
                solves += dyn.step(dt, D, heat).ldlt_solves
            out[key] = (lat.positions.copy(), solves)
    finally:
        thinburn.set_threads(old)
    return out


def test_auto_above_its_threshold_keeps_the_factor_where_it_pays():
    # Above ldlt_max_vertices, "auto" counts the multiply-adds each preconditioner spends and
    # keeps the cheaper, trying the other now and then. At 1/240 s steps the kept factor needs
    # a fourteenth of Jacobi's iterations (2203 against 31315): auto used it for 1551 of 1562
    # solves and ends 9.9e-10 m from the forced factor (bound 1e-8; the CG tolerance alone
    # would allow 300^2 dt 1e-7 = 3.8e-5 m). It counts work, not seconds: the same on 2 threads.
    r = _auto_against_forced(1 / 240, threads=(1, 2))
    assert r["auto1"][1] > 0.97 * r["ldlt"][1]
    np.testing.assert_allclose(r["auto1"][0], r["ldlt"][0], rtol=0, atol=1e-8)
    assert r["auto2"][1] == r["auto1"][1]
    assert np.array_equal(r["auto2"][0], r["auto1"][0])


def test_auto_above_its_threshold_drops_the_factor_where_it_does_not():
    # At 1/24000 s steps the system is nearly the mass matrix: Jacobi converges in a couple of
    # iterations and the factor's fill costs more than it saves. Auto used the factor for 29
    # of 2416 solves (its first trial and retrials) and ends 1.2e-10 m from forced Jacobi
    # (bound 2e-10; the forced factor itself ends 1.6e-8 m from it, within the CG tolerance).
    r = _auto_against_forced(1 / 24000)
    assert r["auto1"][1] < 0.03 * r["ldlt"][1]
    np.testing.assert_allclose(r["auto1"][0], r["jacobi"][0], rtol=0, atol=2e-10)


def test_a_kept_factor_of_another_awake_set_costs_at_most_about_a_factorization(hanging_curtain):
    # Rent or buy within a solve: a factor of another awake set is off from the system by a term
    # of rank about 3 x the vertices that changed next to it, and CG pays about that many more
    # iterations. Once a solve's extra iterations cost a factorization, it refactors there. With
    # wake_hold=0 the curtain's awake set changes nearly every step: the most iterations of a
    # step (up to 4 passes) measured 134, and 5503 in all; without the rule 748 and 24744.
    _, counts = hanging_curtain(wake_hold=0)
    assert counts["most_cg"] <= 150
    assert counts["cg_iterations"] <= 6000
