"""The Simulation's fire on the sheet: bookkeeping, the spread law, bad input (paper §3)."""
import numpy as np
import pytest

import thinburn
from thinburn.scenes import rect_sheet

QUIET = dict(speed_noise=0.0, duration_noise=0.0)
# The fire alone on a fixed shape (paper §3), for comparisons with closed forms.
FIRE_ONLY = dict(shell=False, **QUIET)


def burning_sim(mesh, cells=48, **kw):
    sim = thinburn.Simulation(*mesh, cells=cells, **{**QUIET, **kw})
    sim.ignite((0.1, 0.1, 0.0), time=0.0)
    return sim


def test_cell_burns_for_its_duration_then_is_burnt(square):
    sim = burning_sim(square)
    for _ in range(40):
        sim.step(0.5)
        t_ig, dur, st = sim.ignition_times(), sim.burn_durations(), sim.cell_states()
        lit = np.isfinite(t_ig)
        expect = np.zeros_like(st)
        expect[lit & (sim.time < t_ig + dur)] = 1
        expect[lit & (sim.time >= t_ig + dur)] = 2
        assert np.array_equal(st, expect)
        assert np.all(t_ig[lit] <= sim.time)
    assert (sim.cell_states() == 2).any() and (sim.cell_states() == 1).any()


def test_fringe_is_burning_cells_next_to_unburnt_ones(square):
    sim = burning_sim(square, shell=False)
    sim.run(20.0, dt=0.5)
    st = sim.cell_states()
    unburnt = np.pad(st == 0, 1)
    near_unburnt = np.zeros_like(st, dtype=bool)
    n = st.shape[0]
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            if dr or dc:
                near_unburnt |= unburnt[1 + dr:1 + dr + n, 1 + dc:1 + dc + n]
    expect = (st == 1) & near_unburnt
    assert expect.sum() > 10
    assert np.array_equal(sim.fringe(), expect)
    # The fringe is a thin ring: far fewer cells than all that burn.
    assert sim.fringe().sum() < (st == 1).sum()


def test_vertex_char_is_monotone_in_time_and_bounded(square):
    sim = thinburn.Simulation(*square, cells=40)  # with the preset's noise on
    sim.ignite((0.0, 0.0, 0.0))
    prev = sim.vertex_char()
    for _ in range(60):
        sim.step(1.0)
        ch = sim.vertex_char()
        assert np.all(ch >= prev - 1e-15)
        assert np.all((ch >= 0) & (ch <= 1))
        prev = ch
    assert prev.max() == 1.0


def test_a_future_ignition_waits_for_its_time(square):
    sim = thinburn.Simulation(*square, cells=32, **QUIET)
    sim.ignite((0.1, 0.1, 0.0), time=5.0)
    sim.run(4.9, dt=0.1)
    assert not np.isfinite(sim.ignition_times()).any()
    sim.run(0.3, dt=0.1)
    t = sim.ignition_times()
    assert np.nanmin(np.where(np.isfinite(t), t, np.nan)) == pytest.approx(5.0)


def test_spread_speed_on_flat_paper_is_realistic(a4):
    # Paper preset: V0 = 3.5 mm/s (Table 1 in mm/s). Horizontal spread of 80 g/m^2 paper is
    # about 4 mm/s (MODEL.md §1); we ask for the factor-of-two band and the preset value.
    sim = thinburn.Simulation(*a4, cells=64, material="paper", shell=False)
    sim.ignite((0.105, 0.1485, 0.0))
    sim.run(30.0, dt=0.25)
    t = sim.ignition_times()
    p = sim.cell_positions()
    d = np.hypot(p[..., 0] - 0.105, p[..., 1] - 0.1485)
    ok = np.isfinite(t) & (d > 0.02)
    speed = np.polyfit(t[ok], d[ok], 1)[0]
    assert 2e-3 <= speed <= 8e-3
    assert speed == pytest.approx(3.5e-3, rel=0.05)


def tent(slope, width=0.3, height=0.1, nx=61, ny=21):
    v, f = rect_sheet(width, height, nx=nx, ny=ny)
    v[:, 2] = slope * np.abs(v[:, 0] - width / 2)
    return v, f


def test_grad_term_slows_the_fire_on_a_steep_rest_shape():
    # A tent z = s|x - w/2| has slope s along x on both halves and its best-fit plane is
    # horizontal, so eq 1 gives V = V0 (1 - Cv s^2) along x: dT/dx = 1 / (V0 (1 - Cv s^2)).
    s, cv = 0.6, 0.5
    sim = thinburn.Simulation(*tent(s), cells=120, cv=cv, **FIRE_ONLY)
    p = sim.cell_positions()
    for r in range(sim.cells):
        sim.ignite(p[r, 0], time=0.0)
    sim.run(120.0, dt=1.0)
    t = sim.ignition_times()
    x = p[..., 0]
    mid = sim.cells // 2
    v0 = sim.material.v0
    # Fit each flank away from the edge and the ridge (where the central difference sees
    # both slopes).
    for cols in (slice(5, mid - 3), slice(mid + 3, sim.cells - 5)):
        slope = np.polyfit(x[:, cols].ravel(), t[:, cols].ravel(), 1)[0]
        assert slope == pytest.approx(1.0 / (v0 * (1 - cv * s * s)), rel=0.01)
    flat = thinburn.Simulation(*tent(0.0), cells=120, cv=cv, **FIRE_ONLY)
    assert flat.local_speed(10, 10)[0] == pytest.approx(v0, rel=1e-12)
    assert sim.local_speed(10, 10)[0] == pytest.approx(v0 * (1 - cv * s * s), rel=1e-9)


def test_speed_never_falls_below_its_floor():
    # Slope 1.5 with Cv = 1 would give V = -1.25 V0; the floor holds it at 0.1 V0. (A tall
    # enough sheet keeps the best-fit plane horizontal.)
    sim = thinburn.Simulation(*tent(1.5, height=0.3, ny=31), cells=40, cv=1.0, v_floor=0.1, **FIRE_ONLY)
    assert sim.local_speed(5, 5)[0] == pytest.approx(0.1 * sim.material.v0, rel=1e-12)


def test_flames_climb_a_hanging_sheet_faster_than_they_descend():
    # Beyond the paper: with climb = e the front is an ellipse with the source at a focus:
    # upward speed V (1 + e), downward V (1 - e).
    e = 0.4
    v, f = rect_sheet(0.3, 0.3, nx=31, ny=31, vertical=True)
    sim = thinburn.Simulation(v, f, cells=101, climb=e, **FIRE_ONLY)
    sim.ignite((0.15, 0.0, 0.15))
    sim.run(50.0, dt=0.5)
    t = sim.ignition_times()
    z = sim.cell_positions()[:, 50, 2]
    col = t[:, 50]
    src = int(np.argmin(col))
    up, down = slice(src + 5, src + 40), slice(src - 25, src - 5)
    v0 = sim.material.v0
    up_speed = np.polyfit(col[up], z[up], 1)[0]
    down_speed = -np.polyfit(col[down], z[down], 1)[0]
    assert up_speed == pytest.approx(v0 * (1 + e), rel=0.03)
    assert down_speed == pytest.approx(v0 * (1 - e), rel=0.03)


def test_wind_pushes_the_front_downwind(square):
    sim = thinburn.Simulation(*square, cells=60, wind_spread=0.2, **FIRE_ONLY)
    sim.wind = (2.0, 0.0, 0.0)  # e = 0.4 along +x
    sim.ignite((0.1, 0.1, 0.0))
    sim.run(15.0, dt=0.5)
    t = sim.ignition_times()
    row = t[30]
    assert np.isfinite(row[45]) and (not np.isfinite(row[15]) or row[15] > row[45])


def test_symmetric_law_is_the_default():
    sim = thinburn.Simulation(*rect_sheet(0.2, 0.2, 5, 5, vertical=True), cells=16)
    sim.wind = (3.0, 0.0, 0.0)
    assert sim.local_speed(8, 8)[1:] == (0.0, 0.0)


def test_same_seed_same_result(square):
    runs = []
    for _ in range(2):
        sim = thinburn.Simulation(*square, cells=40, seed=7)
        sim.ignite((0.05, 0.05, 0.0))
        sim.run(10.0, dt=0.5)
        runs.append(sim.ignition_times())
    assert np.array_equal(runs[0], runs[1])
    other = thinburn.Simulation(*square, cells=40, seed=8)
    other.ignite((0.05, 0.05, 0.0))
    other.run(10.0, dt=0.5)
    assert not np.array_equal(runs[0], other.ignition_times())


# --- bad input: a clear error naming the argument, nothing crashes -----------------------

def test_bad_vertices(square):
    v, f = square
    bad = v.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match="vertices.*NaN"):
        thinburn.Simulation(bad, f)
    bad[3, 1] = np.inf
    with pytest.raises(ValueError, match="vertices"):
        thinburn.Simulation(bad, f)
    with pytest.raises(ValueError, match="vertices.*shape"):
        thinburn.Simulation(v[:, :2], f)
    with pytest.raises(TypeError, match="vertices"):
        thinburn.Simulation(v.astype(str), f)
    with pytest.raises(TypeError, match="vertices"):
        thinburn.Simulation(None, f)


def test_bad_faces(square):
    v, f = square
    with pytest.raises(ValueError, match="faces.*out of range"):
        thinburn.Simulation(v, f + len(v))
    with pytest.raises(ValueError, match="faces.*out of range"):
        thinburn.Simulation(v, f - 1000)
    with pytest.raises(ValueError, match="faces.*shape"):
        thinburn.Simulation(v, f[:, :2])
    with pytest.raises(TypeError, match="faces"):
        thinburn.Simulation(v, f + 0.5)


def test_empty_mesh(square):
    v, f = square
    with pytest.raises(ValueError, match="faces.*empty"):
        thinburn.Simulation(v, np.zeros((0, 3), int))
    with pytest.raises(ValueError, match="vertices.*empty"):
        thinburn.Simulation(np.zeros((0, 3)), np.zeros((0, 3), int))
    with pytest.raises(ValueError, match="zero area|degenerate"):
        thinburn.Simulation(np.zeros((3, 3)), np.array([[0, 1, 2]]))


def test_bad_material_and_params(square):
    with pytest.raises(ValueError, match="material"):
        thinburn.Simulation(*square, material="balsa")
    with pytest.raises(TypeError, match="material"):
        thinburn.Simulation(*square, material=3)
    with pytest.raises(ValueError, match="material.V0"):
        thinburn.Simulation(*square, material=thinburn.MATERIALS["paper"].with_(V0=-1.0))
    with pytest.raises(ValueError, match="material.K_structure"):
        thinburn.Simulation(*square, material=thinburn.MATERIALS["paper"].with_(K_structure=0.0))
    with pytest.raises(TypeError, match="unexpected keyword.*bogus"):
        thinburn.Simulation(*square, bogus=1.0)
    with pytest.raises(ValueError, match="climb"):
        thinburn.Simulation(*square, climb=2.0)
    with pytest.raises(ValueError, match="cells"):
        thinburn.Simulation(*square, cells=1)
    with pytest.raises(ValueError, match="front"):
        thinburn.Simulation(*square, front="magic")
    with pytest.raises(ValueError, match="uv.*shape"):
        thinburn.Simulation(*square, uv=np.zeros((3, 2)))


def test_bad_step_and_ignite(square):
    sim = thinburn.Simulation(*square, cells=16)
    for dt in (0.0, -1.0, np.nan, np.inf):
        with pytest.raises(ValueError, match="dt"):
            sim.step(dt)
    with pytest.raises(TypeError, match="dt"):
        sim.step("1")
    with pytest.raises(ValueError, match="point.*no cell"):
        sim.ignite((5.0, 5.0, 0.0))
    with pytest.raises(ValueError, match="point"):
        sim.ignite((0.1, np.nan, 0.0))
    with pytest.raises(ValueError, match="point.*shape"):
        sim.ignite((0.1, 0.1))
    with pytest.raises(ValueError, match="radius"):
        sim.ignite((0.1, 0.1, 0.0), radius=-1)
    with pytest.raises(ValueError, match="wind"):
        sim.wind = (0, 0)
    # Nothing was lost: the simulation still runs.
    sim.ignite((0.1, 0.1, 0.0))
    sim.step(1.0)
    assert sim.time == 1.0


def _brute_cells_near(sim, point, radius):
    """What ignite lit before the locator: a scan of every inside cell."""
    pos = sim.cell_positions().reshape(-1, 3)
    inside = sim.inside().ravel().astype(bool)
    d2 = np.sum((pos - np.asarray(point)) ** 2, axis=1)
    d2[~inside] = np.inf
    if radius > 0 and np.any(d2 <= radius * radius):
        idx = np.flatnonzero(d2 <= radius * radius)
    else:
        idx = np.array([int(np.argmin(d2))])
    return np.stack([idx // sim.cells, idx % sim.cells], axis=1)


@pytest.mark.parametrize("shell", [True, False])
def test_cells_near_finds_what_a_scan_of_every_cell_finds(shell):
    # ignite looks cells up through the lattice's control cells (cpp/cell_locator.hpp) instead
    # of scanning all N² cells; on a crumpled, moving sheet it must find the same cells.
    v, f = rect_sheet(0.21, 0.297, nx=15, ny=21)
    sim = thinburn.Simulation(v, f, cells=48, floor=0.0, shell=shell, seed=2)
    sim.ignite((0.0, 0.0, 0.0), time=0.0, radius=0.03)
    sim.ignite((0.21, 0.297, 0.0), time=0.0)
    for _ in range(24 * 25):
        sim.step(1 / 24)
    pos = sim.cell_positions().reshape(-1, 3)[sim.inside().ravel().astype(bool)]
    if shell:
        assert np.ptp(pos[:, 2]) > 0.01  # the sheet has curled up: positions are not the rest plane
    rng = np.random.default_rng(0)
    for k in range(60):
        point = pos[rng.integers(len(pos))] + rng.normal(0.0, 0.004, 3)
        radius = [0.0, 0.004, 0.02][k % 3]
        np.testing.assert_array_equal(sim.cells_near(point, radius), _brute_cells_near(sim, point, radius))


def test_cells_near_refuses_a_point_off_the_sheet(square):
    sim = thinburn.Simulation(*square, cells=16, shell=False)
    with pytest.raises(ValueError, match="point"):
        sim.cells_near((5.0, 5.0, 5.0))
