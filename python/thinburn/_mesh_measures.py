"""Measures of a deformed mesh used by tests and scripts: its edges and their strain, adjacent
faces, the angle between them (facets), and the faces far from the fire."""
from __future__ import annotations

import numpy as np


def mesh_edges(faces):
    """Each edge of the triangles once, (n, 2) vertex indices, the smaller first."""
    f = np.asarray(faces)
    return np.unique(np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), 1), axis=0)


class EdgeStrain:
    """|l / L - 1| per edge of a mesh, against its lengths L at rest."""

    def __init__(self, rest, faces):
        self.edges = mesh_edges(faces)
        self.rest_length = self.lengths(rest)

    def lengths(self, x):
        return np.linalg.norm(x[self.edges[:, 0]] - x[self.edges[:, 1]], axis=1)

    def __call__(self, x):
        return np.abs(self.lengths(x) / self.rest_length - 1.0)

    def unburnt(self, sim, mask=None):
        """|l / L - 1| of a Simulation's mesh now over the edges whose two vertices are both
        unburnt (char 0), and also in `mask` (per edge) if given."""
        char = sim.vertex_char()
        keep = (char[self.edges[:, 0]] == 0) & (char[self.edges[:, 1]] == 0)
        if mask is not None:
            keep &= mask
        return self(sim.vertex_positions())[keep]


class SurfaceStrain(EdgeStrain):
    """|s / L - 1| per edge, s the edge's length along the sheet's surface now
    (Simulation.surface_lengths, `samples` pieces). Where the lattice folds sharply between
    two couples the surface has a crease, and an edge across it is a chord, shorter than the
    surface under it (docs/lattice.md, "Creases between couples"); this measures the surface,
    EdgeStrain the mesh."""

    def __init__(self, rest, faces, samples=16):
        super().__init__(rest, faces)
        self.samples = samples

    def __call__(self, sim):
        return np.abs(sim.surface_lengths(self.edges, self.samples) / self.rest_length - 1.0)


def face_adjacency(faces):
    """Pairs of faces sharing an edge."""
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    e = np.sort(e, 1)
    fid = np.tile(np.arange(len(faces)), 3)
    order = np.lexsort((e[:, 1], e[:, 0]))
    e, fid = e[order], fid[order]
    same = np.all(e[1:] == e[:-1], axis=1)
    return np.stack([fid[:-1][same], fid[1:][same]], 1)


def dihedral_angles(x, faces, pairs):
    n = np.cross(x[faces[:, 1]] - x[faces[:, 0]], x[faces[:, 2]] - x[faces[:, 0]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    c = np.clip((n[pairs[:, 0]] * n[pairs[:, 1]]).sum(1), -1.0, 1.0)
    return np.degrees(np.arccos(c))


def far_from_fire(rest, faces, char, distance):
    """Faces whose vertices are all unburnt and >= distance from every charred vertex."""
    burnt = rest[char > 0.0]
    if len(burnt) == 0:
        ok = np.ones(len(rest), bool)
    else:
        d = np.sqrt(((rest[:, None, :2] - burnt[None, ::7, :2]) ** 2).sum(-1)).min(1)
        ok = (char == 0.0) & (d >= distance)
    return ok[faces].all(1)


def lattice_turns(sim):
    """(M, M): per couple of a flat sheet's grid lattice, the larger turn (degrees) between its
    couple-to-couple segments along its two grid lines (0 where a line ends at it). FoldBlend
    (docs/lattice.md, "Where the lattice folds") blends the mesh towards the couples from 20
    degrees and follows them wholly from 40: a crease on the couple's lines."""
    x = sim.lattice_positions()
    m = x.shape[0]
    c = x.mean(2)
    out = np.zeros((m, m))
    for axis in (0, 1):
        d = np.diff(c, axis=axis)
        a, b = np.take(d, range(0, m - 2), axis=axis), np.take(d, range(1, m - 1), axis=axis)
        cos = (a * b).sum(-1) / np.maximum(np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1), 1e-15)
        turn = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
        inner = (slice(1, m - 1), slice(None)) if axis == 0 else (slice(None), slice(1, m - 1))
        out[inner] = np.maximum(out[inner], turn)
    return out
