"""The frame a bake simulates in when the sheet's own transform is animated (the Blender
add-on's bake, and a scene file's ``to_world``).

The core simulates in the *bake frame*: the world as it was at Start, carried along by the
sheet's transform. At frame k the map from it to the world is F_k = M_k M_0^-1 (M: the sheet's
world matrix), the identity for a sheet that does not move. The cache stores M_0^-1 times the
core's positions, i.e. object-space positions, and Blender's own animated transform places
them, so the result follows the transform exactly. What comes from the world (igniters, wind,
gravity, the fire particles going out) is mapped through F_k each frame. The moving frame's
own forces (its acceleration, the air its motion meets, centrifugal and Coriolis) are left
out: the transform is the sheet's prescribed carriage, as if a hand held it.
"""
from __future__ import annotations

import math

import numpy as np


def frame_map(matrix, start_inverse) -> np.ndarray:
    """F_k: (4, 4) from the bake frame to the world at a frame whose sheet matrix is ``matrix``."""
    return np.asarray(matrix, dtype=np.float64) @ start_inverse


def rotation(F: np.ndarray) -> np.ndarray:
    """The rotation part of F (its polar factor): scale and shear removed, so that directions
    (gravity, wind) turn without changing their length."""
    u, _, vt = np.linalg.svd(F[:3, :3])
    r = u @ vt
    if np.linalg.det(r) < 0.0:  # a mirrored transform: keep a proper rotation
        u[:, -1] *= -1.0
        r = u @ vt
    return r


def to_world(F: np.ndarray, points: np.ndarray) -> np.ndarray:
    return np.asarray(points, dtype=np.float64) @ F[:3, :3].T + F[:3, 3]


def to_bake(F: np.ndarray, points: np.ndarray) -> np.ndarray:
    inv = np.linalg.inv(F)
    return np.asarray(points, dtype=np.float64) @ inv[:3, :3].T + inv[:3, 3]


def direction_to_bake(F: np.ndarray, vectors) -> np.ndarray:
    """World directions (rows, or one vector) turned into the bake frame: R^T v."""
    return np.asarray(vectors, dtype=np.float64) @ rotation(F)


def keeps_floor(F: np.ndarray, tol: float = 1e-6) -> bool:
    """Whether the world's floor plane z = c is the plane z = c of the bake frame too: the
    motion only slides in X/Y and turns about Z (the core's floor is level in its frame)."""
    return bool(np.allclose(F[2, :3], (0.0, 0.0, 1.0), atol=tol) and abs(F[2, 3]) <= tol)


def tilt_degrees(F: np.ndarray) -> float:
    """How far the bake frame's up has turned away from the world's up, degrees."""
    return math.degrees(math.acos(max(-1.0, min(1.0, float(rotation(F)[2, 2])))))
