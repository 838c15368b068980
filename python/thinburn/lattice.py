"""The FFD lattice (Liu et al. 2009 §4.1): builders for rest lattices and thin wrappers.

Control vertex index: ((i * M) + j) * 2 + k, i = row (the sheet's v axis), j = column (u axis),
k = 0 bottom, 1 top. See docs/dynamics.md.
"""
from __future__ import annotations

import numpy as np

from . import _core
from . import _validate as V

FfdLattice = _core.FfdLattice
Embedding = _core.Embedding

__all__ = ["Embedding", "FfdLattice", "drape", "flat_rest", "vertex_index"]


def vertex_index(M: int, i, j, k):
    """Index of control vertex (i, j, k) in a lattice of M x M couples (arrays broadcast)."""
    return ((np.asarray(i) * M) + np.asarray(j)) * 2 + np.asarray(k)


def drape(mid: np.ndarray, normals: np.ndarray, thickness: float) -> np.ndarray:
    """Rest lattice over a surface: couple (i, j) = mid[i, j] -/+ thickness/2 * normals[i, j].

    mid, normals: (M, M, 3) arrays (normals need not be unit; they are normalised).
    Returns the (2 M^2) x 3 rest positions.
    """
    mid = V.real_array(mid, "mid", (-1, -1, 3), finite=False)
    normals = V.real_array(normals, "normals", (-1, -1, 3), finite=False)
    if mid.ndim != 3 or mid.shape[0] != mid.shape[1] or mid.shape[2] != 3 or mid.shape[0] < 2:
        raise ValueError(f"mid must have shape (M, M, 3) with M >= 2, got {mid.shape}")
    if normals.shape != mid.shape:
        raise ValueError(f"normals must have shape {mid.shape}, got {normals.shape}")
    thickness = V.real(thickness, "thickness", low=0.0, low_open=True)
    length = np.linalg.norm(normals, axis=2, keepdims=True)
    if not np.all(length > 0) or not np.all(np.isfinite(mid)):
        raise ValueError("normals must be non-zero and mid finite")
    half = 0.5 * thickness * normals / length
    M = mid.shape[0]
    out = np.empty((M, M, 2, 3))
    out[:, :, 0] = mid - half
    out[:, :, 1] = mid + half
    return out.reshape(2 * M * M, 3)


def flat_rest(M: int, width: float, height: float, thickness: float,
              origin=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Rest lattice of a flat width x height sheet in the z = origin[2] plane, u along x (columns
    j), v along y (rows i), its corner couple (0, 0) at origin, top layer at +z."""
    if isinstance(M, bool) or not isinstance(M, (int, np.integer)) or M < 2:
        raise ValueError(f"M must be an int >= 2, got {M!r}")
    width = V.real(width, "width", low=0.0, low_open=True)
    height = V.real(height, "height", low=0.0, low_open=True)
    origin = V.vector3(origin, "origin")
    t = np.linspace(0.0, 1.0, M)
    mid = np.zeros((M, M, 3))
    mid[:, :, 0] = origin[0] + width * t[None, :]
    mid[:, :, 1] = origin[1] + height * t[:, None]
    mid[:, :, 2] = origin[2]
    normals = np.zeros_like(mid)
    normals[:, :, 2] = 1.0
    return drape(mid, normals, thickness)
