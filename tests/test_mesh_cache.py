"""The mesh's deformed vertices kept between frames (cpp/lattice.hpp, CachedDeform; issue #11
item 4, docs/bench.md "film"): a vertex_positions call recomputes only the vertices whose
couples moved, and its result is bit-identical to deforming every vertex."""
import numpy as np
import pytest

import thinburn
from thinburn.scenes import rect_sheet

DT = 1 / 24


def corner_fire(mesh, threads=1, lattice=33):
    # On a table: a sheet in free fall moves every couple every frame, and redoes every vertex.
    sim = thinburn.Simulation(*mesh, material="paper", cells=64, lattice=lattice, threads=threads,
                              floor=0.0)
    sim.ignite((0.0, 0.0, 0.0), time=0.0, radius=0.03)
    return sim


@pytest.fixture(scope="module")
def sheet():
    """A 1 m square at 101 x 101 vertices (the film bench's sheet, smaller): with a 33 x 33
    lattice a corner fire moves the couples near it while the rest sleep."""
    return rect_sheet(1.0, 1.0, nx=101, ny=101)


# Measured over the 72 frames (10201 vertices): at M = 33 every frame after the second redid
# 19-33 % of the vertices, by their stencil groups; at M = 17 more than half moved in all but
# one frame, which deform every vertex straight into the result instead.
@pytest.mark.parametrize("lattice, min_partial, min_full", [(33, 60, 0), (17, 1, 40)])
def test_kept_vertices_are_bit_identical_to_a_full_deform(sheet, lattice, min_partial, min_full):
    # Sim a asks for the mesh every frame (each call redoes only what moved); sim b, the same
    # deterministic run, asks only at frames 24, 48, 72 and its first call deforms every vertex.
    frames, checks = 72, (24, 48, 72)
    a = corner_fire(sheet, lattice=lattice)
    fresh = {k: corner_fire(sheet, lattice=lattice) for k in checks}
    partial = full = 0
    for f in range(1, frames + 1):
        a.step(DT)
        pa = a.vertex_positions()
        partial += 0 < a.mesh_points_redone < a.n_vertices
        full += f > 1 and a.mesh_points_redone == a.n_vertices
        for k, b in list(fresh.items()):
            b.step(DT)
            if f == k:
                pb = b.vertex_positions()
                assert b.mesh_points_redone == b.n_vertices  # the first call: every vertex
                assert np.array_equal(pa, pb), f"frame {f}: max |diff| {np.abs(pa - pb).max()}"
                del fresh[k]
    # Both ways of skipping were exercised.
    assert partial >= min_partial and full >= min_full, (partial, full)


def test_a_frame_without_motion_redoes_nothing(square):
    sim = thinburn.Simulation(*square, cells=32, gravity=(0.0, 0.0, 0.0))
    p0 = sim.vertex_positions()
    assert sim.mesh_points_redone == sim.n_vertices
    # The first call deformed every vertex straight into its result (everything "moved"); the
    # second, with nothing moved, deforms them once more to keep them.
    assert np.array_equal(sim.vertex_positions(), p0)
    assert sim.mesh_points_redone == sim.n_vertices
    sim.step(DT)
    assert np.array_equal(sim.vertex_positions(), p0)
    assert sim.mesh_points_redone == 0


def test_threads_give_the_same_kept_vertices(sheet):
    one, two = corner_fire(sheet, 1), corner_fire(sheet, 2)
    for _ in range(30):
        one.step(DT), two.step(DT)
        assert np.array_equal(one.vertex_positions(), two.vertex_positions())


def test_vertex_positions_into_a_kept_array(sheet):
    sim = corner_fire(sheet)
    out = np.empty((sim.n_vertices, 3))
    for _ in range(10):
        sim.step(DT)
        assert sim.vertex_positions(out=out) is out
        assert np.array_equal(out, sim.vertex_positions())
    for bad in (np.empty((sim.n_vertices, 3), dtype=np.float32), np.empty((3, sim.n_vertices)).T,
                np.empty((sim.n_vertices - 1, 3)), [[0.0, 0.0, 0.0]]):
        with pytest.raises(ValueError, match="out"):
            sim.vertex_positions(out=bad)
    flat = thinburn.Simulation(*sheet, cells=32, shell=False)  # no shell: the rest mesh
    out = np.empty((flat.n_vertices, 3))
    assert np.array_equal(flat.vertex_positions(out=out), sheet[0])


def test_phase_seconds_name_every_phase(sheet):
    sim = corner_fire(sheet)
    assert set(sim.phase_seconds()) == {"fire_front", "cells", "sources", "particles", "heat",
                                        "dynamics", "mesh"}
    assert all(v == 0.0 for v in sim.phase_seconds().values())
    sim.step(DT)
    sim.vertex_positions()
    after = sim.phase_seconds()
    assert all(v > 0.0 for v in after.values()), after
