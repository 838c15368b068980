"""The lattice of a curved shell (paper §4.1, Fig. 3; issue #11; docs/lattice.md).

``ControlSurface(vertices, faces, spacing, thickness)`` samples the shell at the lattice's
spacing (its couples' mid-points lie on the shell, their axes along its normals), builds the
springs from that coarse surface's triangulation and embeds points smoothly (C²) in the layer:
``embed(points)`` gives per point up to 12 couples with moving-least-squares weights (linear
in 3-D, so a rigid turn of the lattice turns the points rigidly) and ``deform(embedding,
control)`` the points' positions for control positions (2 couples, 3). A Simulation on a
curved shell builds one itself; this module exposes it for tests and tools.
"""
from __future__ import annotations

import numpy as np

from . import _core
from ._validate import index_array, real, real_array

__all__ = ["ControlSurface", "SPRING_KINDS"]

# Spring kinds of LatticeTopology (kind column of ControlSurface.springs).
SPRING_KINDS = ("structure", "shear", "flex", "thickness", "transverse")


class ControlSurface:
    """Couples on a coarse control surface fitted to a triangle mesh.

    spacing: metres between neighbouring couples (> 0); thickness: metres between a couple's
    bottom and top control vertices (> 0); crease_angle: degrees (None: the core's 25), mesh
    edges whose faces turn by more are creases, hinges the embedding does not smooth across (180: none;
    docs/lattice.md, "Creases"). A mesh SurfaceCells refuses (non-manifold edges,
    zero area) raises ValueError naming ``faces`` or ``vertices``; a spacing that leaves a
    piece with fewer than 3 couples, or a couple with no neighbour, names ``lattice``.
    """

    def __init__(self, vertices, faces, spacing: float, thickness: float, crease_angle: float | None = None):
        v = real_array(vertices, "vertices", (-1, 3))
        if v.shape[0] < 3:
            raise ValueError(f"vertices must have at least 3 rows, got {v.shape[0]}")
        f = index_array(faces, "faces", (-1, 3), v.shape[0])
        creases = {} if crease_angle is None else {"crease_angle": real(crease_angle, "crease_angle", low=0.0, high=180.0)}
        self._c = _core.ControlSurface(v, f.astype(np.int32), real(spacing, "spacing", low=0.0, low_open=True),
                                       real(thickness, "thickness", low=0.0, low_open=True), **creases)

    couples = property(lambda self: self._c.couples, doc="Number of couples.")
    spacing = property(lambda self: self._c.spacing, doc="Target spacing between couples, m.")
    thickness = property(lambda self: self._c.thickness, doc="Bottom-top distance of a couple, m.")

    @property
    def rest(self) -> np.ndarray:
        """(couples, 2, 3) rest control vertices: [couple, 0 bottom / 1 top, xyz]."""
        return self._c.rest.reshape(-1, 2, 3)

    @property
    def springs(self) -> np.ndarray:
        """(s, 3) int: control vertex a, control vertex b (2 couple + layer), kind (SPRING_KINDS)."""
        return self._c.springs

    def neighbours(self, couple: int) -> np.ndarray:
        """The couples joined to `couple` by structure springs."""
        off = self._c.nbr_offset
        return np.asarray(self._c.nbr_index[off[couple]:off[couple + 1]])

    def shape_operators(self) -> np.ndarray:
        """(couples, 3, 3) the rest shell's shape operator at each couple, in its tangent plane,
        fitted to how the couples' axes turn towards their neighbours (I/R on a sphere of radius
        R, tops outward; zero on a flat sheet). The bimetal curl keeps the part of itself that
        leaves the Gaussian curvature alone (docs/dynamics.md §2, "Curved shells")."""
        return self._c.shape_operators()

    def edge_curvature(self, quantile: float = 0.9) -> float:
        """The quantile over couples of their most curved edge's (angle between normals) / length, 1/m."""
        return self._c.edge_curvature(real(quantile, "quantile", low=0.0, high=1.0))

    def embed(self, points):
        """Embed (n, 3) rest points on the shell; returns an embedding with (n, 12) ``couple``,
        ``weight`` (sum 1 per point) and ``share`` (>= 0, sum 1), plus ``rest``, ``rest_normal``
        and ``offset`` (along the normal from the interpolated mid-surface)."""
        return self._c.embed(real_array(points, "points", (-1, 3)))

    def deform(self, embedding, control) -> np.ndarray:
        """(n, 3) positions of embedded points for control positions ((couples, 2, 3) or (2 couples, 3))."""
        x = real_array(np.asarray(control).reshape(-1, 3), "control", (2 * self.couples, 3))
        return self._c.deform(embedding, x)

    def normals(self, embedding, control) -> np.ndarray:
        """(n, 3) the layer's unit normal (bottom -> top) at each embedded point."""
        x = real_array(np.asarray(control).reshape(-1, 3), "control", (2 * self.couples, 3))
        return self._c.normals(embedding, x)
