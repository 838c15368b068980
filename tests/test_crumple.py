"""The crumple (cpp/crumple.*, docs/dynamics.md §2, paper eqs 7, 8, Fig. 5): with the springs
off, a couple's rotation turns its axis neighbours along the chord, increments compose, the
sign and crumple_gain act as the paper says."""
import numpy as np
import pytest

from lattice_cases import CHORD, INTEGRATORS, SPRINGS_OFF, expected_crumple, make, zeros


@pytest.mark.parametrize("integrator", INTEGRATORS)
@pytest.mark.parametrize("substeps", [0, 7])
def test_crumple_moves_neighbours_along_the_chord(integrator, substeps):
    M, L, th = 5, 0.05, 0.004
    lat, dyn = make(M, L, th, integrator=integrator, substeps=substeps, gravity=[0, 0, 0],
                    c_damping=0.0, **SPRINGS_OFF, **CHORD)
    D, heat = zeros(M)
    delta = 0.3
    D[2 * M + 2] = delta
    dyn.step(1 / 24, D, heat)
    want = expected_crumple(lat, M, 2, 2, delta)
    np.testing.assert_allclose(lat.positions, want, rtol=0, atol=1e-12)
    # |AB| = 2 r sin(delta / 2), r the distance from the axis.
    moved = np.linalg.norm(lat.positions - lat.rest, axis=1)
    r = np.hypot(L, th / 2)
    assert np.count_nonzero(moved) == 8
    np.testing.assert_allclose(moved[moved > 0], 2 * r * np.sin(delta / 2), rtol=1e-12)
    assert np.all(lat.positions[moved > 0, 2] > lat.rest[moved > 0, 2])  # toward the top face
    # No velocity is left: the crumple is a prescribed motion over the frame.
    assert np.abs(dyn.velocities).max() < 1e-12


def test_crumple_increments_compose_to_the_total_rotation():
    M = 5
    lat, dyn = make(M, 0.05, 0.004, gravity=[0, 0, 0], c_damping=0.0, **SPRINGS_OFF, **CHORD)
    D, heat = zeros(M)
    for f in range(1, 11):
        D[2 * M + 2] = 0.04 * f
        dyn.step(1 / 24, D, heat)
    np.testing.assert_allclose(lat.positions, expected_crumple(lat, M, 2, 2, 0.4), rtol=0,
                               atol=1e-12)


def test_negative_rotation_turns_toward_the_bottom_and_gain_scales():
    M = 5
    lat, dyn = make(M, 0.05, 0.004, gravity=[0, 0, 0], c_damping=0.0, crumple_gain=2.0,
                    **SPRINGS_OFF, **CHORD)
    D, heat = zeros(M)
    D[2 * M + 2] = -0.1
    dyn.step(1 / 24, D, heat)
    np.testing.assert_allclose(lat.positions, expected_crumple(lat, M, 2, 2, -0.2), rtol=0,
                               atol=1e-12)
    assert lat.positions[:, 2].min() < lat.rest[:, 2].min()
