"""Self-collision (cpp/self_contact.cpp, docs/dynamics.md §3.3): a sheet folded over onto
itself stops a separation above itself instead of passing through, momentum is kept and no
energy is made, and where nothing is near contact it changes nothing (bit for bit)."""
import numpy as np
import pytest

import thinburn
from thinburn import _core
from thinburn.demo import build, default_scene
from thinburn.dynamics import preset, vertex_masses
from thinburn.lattice import drape

ipctk = pytest.importorskip("ipctk")

# A 22 cm cloth lattice (M = 12, 2 cm spacing, 5 mm thick) folded across x into a U: flat up to
# x = FOLD, round a half circle of radius BEND, then back over itself 2 BEND above.
M, SPACING, THICKNESS = 12, 0.02, 0.005
WIDTH = (M - 1) * SPACING
FOLD, BEND = 0.09, 0.01
DT = 1 / 240
STEPS = 96  # 0.4 s


def folded(s):
    """The U's mid-surface (x, z) and unit normal at arc length s along x."""
    th = np.clip((s - FOLD) / BEND, 0.0, np.pi)
    back = FOLD - (s - FOLD - np.pi * BEND)
    x = np.where(s <= FOLD, s, np.where(s <= FOLD + np.pi * BEND, FOLD + BEND * np.sin(th), back))
    n = np.stack([-np.sin(th), np.zeros_like(s), np.cos(th)], -1)
    return x, BEND * (1 - np.cos(th)), n


def folded_sheet(self_collision, speed, **params):
    """The U, at rest in that shape, its upper part thrown down at `speed` (m/s); soft springs
    (stiffness_unit 50) let the fold close. Returns the lattice, its dynamics, the vertex masses
    and, per couple, its arc length."""
    s, y = np.meshgrid(np.linspace(0, WIDTH, M), np.linspace(0, WIDTH, M))  # rows i along y
    x, z, n = folded(s)
    pos = drape(np.stack([x, y, z], -1), n, THICKNESS)
    lat = _core.FfdLattice(M, pos)
    kw = preset("cloth", stiffness_unit=50.0, has_floor=True, floor_z=-THICKNESS / 2,
                self_collision=self_collision)
    kw.update(params)
    dyn = _core.LatticeDynamics(lat, **kw)
    mass = vertex_masses(M, WIDTH ** 2, 0.1)
    dyn.set_masses(mass)
    vel = np.zeros_like(pos)
    vel[np.repeat(s.ravel() > FOLD + np.pi * BEND, 2), 2] = -speed
    dyn.set_state(pos, vel)
    return lat, dyn, mass, s.ravel()


def embedded_mesh(lat, n=34):
    """A fine mesh (n x n vertices) in the lattice's mid-layer, quadratic B-spline FFD as a flat
    sheet's: its embedding, faces and edges."""
    s, y = np.meshgrid(np.linspace(0, WIDTH, n), np.linspace(0, WIDTH, n))
    x, z, _ = folded(s)
    rest = np.stack([x.ravel(), y.ravel(), z.ravel()], 1)
    coords = np.stack([y.ravel() / SPACING, s.ravel() / SPACING, np.full(s.size, 0.5)], 1)
    emb = lat.embed(coords, rest, "bspline")
    a = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)[None, :]).ravel()
    faces = np.concatenate([np.stack([a, a + 1, a + n + 1], 1), np.stack([a, a + n + 1, a + n], 1)]).astype(np.int32)
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    return emb, faces, np.unique(np.sort(e, 1), axis=0).astype(np.int32)


def crossing_steps(lat, dyn, after_step=lambda: None):
    """Steps after which a mesh edge crosses a triangle of the same mesh (ipctk)."""
    emb, faces, edges = embedded_mesh(lat)
    mesh = ipctk.CollisionMesh(np.asfortranarray(lat.deform(emb)), np.asfortranarray(edges), np.asfortranarray(faces))
    assert not ipctk.has_intersections(mesh, np.asfortranarray(lat.deform(emb)))
    crossed = []
    for k in range(STEPS):
        dyn.step(DT, np.zeros(M * M), np.zeros(2 * M * M))
        if ipctk.has_intersections(mesh, np.asfortranarray(lat.deform(emb))):
            crossed.append(k)
        after_step()
    return crossed


def mids(lat):
    p = lat.positions
    return 0.5 * (p[0::2] + p[1::2])


def upper_gap(lat, s):
    """Smallest distance from the upper part's couples (two spacings past the bend: not the
    lower part's neighbours) to the lower part's mid-surface triangles."""
    m = mids(lat)
    upper = np.flatnonzero(s > FOLD + np.pi * BEND + 2 * SPACING)
    tris = []
    for i in range(M - 1):
        for j in range(M - 1):
            if s[i * M + j + 1] <= FOLD:
                c = i * M + j
                tris += [(c, c + M, c + M + 1), (c, c + M + 1, c + 1)]
    return min(np.sqrt(ipctk.point_triangle_distance(m[p], m[a], m[b], m[c])) for p in upper for a, b, c in tris)


def test_a_sheet_thrown_onto_itself_does_not_pass_through():
    """Without self-collision the upper part of the U, thrown down at 1 m/s, passes through the
    lower part to the floor (the embedded mesh crosses itself at steps 4-7 of 96, measured);
    with it, no step crosses and the upper part's couples stay the separation (one lattice
    thickness, 5 mm) from the lower part's mid-surface: measured at least 5.000 mm."""
    lat, dyn, _, _ = folded_sheet(False, 1.0)
    assert len(crossing_steps(lat, dyn)) >= 2
    lat, dyn, _, s = folded_sheet(True, 1.0)
    gaps = []
    assert crossing_steps(lat, dyn, lambda: gaps.append(upper_gap(lat, s))) == []
    assert min(gaps) > (1 - 1e-6) * THICKNESS


def test_plates_meeting_in_free_space_keep_momentum_and_make_no_energy():
    """No gravity, floor or damping, symplectic Euler (which keeps this lattice's energy within
    0.32 % when the parts pass through each other, measured): the upper part of the U meets the
    lower one at 1 m/s.
    Contact pushes are equal and opposite, so the momentum stays the initial 1.98e-3 kg m/s
    (measured to 6e-18); the response is inelastic, so kinetic plus spring energy never rises
    above the integrator's own wobble (measured at most 0.9923 mJ of 0.9900) and the meeting
    takes a third of it (0.642 mJ left at 0.4 s)."""
    def run(self_collision):
        lat, dyn, mass, _ = folded_sheet(self_collision, 1.0, has_floor=False, gravity=(0.0, 0.0, 0.0),
                                         c_damping=0.0, integrator="symplectic")

        def momentum():
            return (mass[:, None] * dyn.velocities).sum(0)

        def energy():
            return 0.5 * (mass * (dyn.velocities ** 2).sum(1)).sum() + dyn.energy()

        p0, e0 = momentum(), energy()
        energies = []
        for _ in range(STEPS):
            dyn.step(DT, np.zeros(M * M), np.zeros(2 * M * M))
            energies.append(energy())
            np.testing.assert_allclose(momentum(), p0, rtol=0, atol=1e-12 * np.abs(p0).max())
        return np.array(energies) / e0

    free = run(False)  # the parts pass through each other: the integrator's own wobble
    assert np.abs(free - 1).max() < 0.004
    met = run(True)
    assert met.max() < 1.004
    assert met[-1] < 0.7


def test_nothing_near_contact_changes_nothing():
    """The A4 paper demo burning on its table for 3 s (64 cells), whose curl stays clear of
    itself: self-collision on and off give bit-identical meshes (the hash finds no pair, so no
    couple is touched)."""
    scene = default_scene("paper")
    runs = []
    for on in (True, False):
        sim = build(scene, "paper", cells=64)
        sim.set_dynamics(self_collision=on)
        assert sim.params.dynamics["self_collision"] is on
        sim.run(3.0)
        runs.append(sim.vertex_positions())
    assert np.abs(runs[0] - scene.vertices).max() > 1e-4  # it moved
    assert np.array_equal(runs[0], runs[1])


def test_self_distance_must_be_positive():
    sim = thinburn.Simulation(*thinburn.scenes.rect_sheet(0.1, 0.1, nx=5, ny=5), cells=16, lattice=4)
    with pytest.raises(ValueError, match="self_distance"):
        sim.set_dynamics(self_distance=0.0)


@pytest.mark.parametrize("turn", [160.0, 170.0, 175.0])
def test_a_letter_folded_nearly_shut_does_not_cross_itself(turn):
    """The demo's letter folded nearly shut (halves 20, 10 and 5 degrees apart; 13 mm apart at
    the open edge at 175, under a 9.5 mm lattice), burning on its table for 40 s from a corner
    of the lying half (cells=64; `python scripts/folded_letter.py --crossings`). Checked on every
    frame with ipctk: no mesh edge crosses a triangle of the faces a render keeps (the add-on
    removes a face once all its vertices burnt out). Measured: at 160 and 170 no frame crosses at
    all; at 175, 392 of the 960 frames cross only within burnt-out faces (ash, in the add-on's
    Char (Ash) mode). Before the rim's corners had couples the lying half's corner was
    extrapolated 1.2 cm beyond its control triangles, and curled through the upper half:
    19, 367 and 533 frames crossed, 450 of them (at 175) within the faces a render keeps."""
    from thinburn._mesh_measures import mesh_edges
    from thinburn.scenes import A4, folded_sheet

    def collision_mesh(V, F):
        E = mesh_edges(F).astype(np.int32)
        return ipctk.CollisionMesh(np.asfortranarray(V), np.asfortranarray(E), np.asfortranarray(F.astype(np.int32)))

    V, F = folded_sheet(A4[0], A4[1], angle=turn, nx=43, ny=61)
    whole = collision_mesh(V, F)
    sim = thinburn.Simulation(V, F, cells=64, floor=0.0)
    sim.ignite((0.004, 0.004, 0.0))
    crossed = kept_crossed = 0
    for _ in range(24 * 40):
        sim.step(1 / 24)
        X = np.asfortranarray(sim.vertex_positions())
        if ipctk.has_intersections(whole, X):
            crossed += 1
            kept = (sim.vertex_burnout_times() > sim.time)[F].any(axis=1)
            kept_crossed += ipctk.has_intersections(collision_mesh(V, F[kept]), X)
    assert (sim.cell_states() == 2).mean() > 0.15
    assert kept_crossed == 0
    if turn < 175.0:
        assert crossed == 0
