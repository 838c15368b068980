"""Test and benchmark surfaces for the surface fire front, with exact geodesic distances.

Each mesh function returns (vertices (n, 3), faces (m, 3) int32); each ``*_exact`` function
returns the exact geodesic distance on the smooth surface from a source point to points
lying on it (for the polyhedral meshes here, fine enough that the two differ by < 1e-4
relative). Used by tests/test_surface_front.py and scripts/bench_surface_front.py.
"""
from __future__ import annotations

import numpy as np


def grid_faces(nu: int, nv: int, wrap_u: bool = False, flip: bool = False) -> np.ndarray:
    """Two triangles per quad of an (nu [+1]) x (nv + 1) vertex grid, u-major."""
    faces = []
    for i in range(nu):
        i2 = (i + 1) % nu if wrap_u else i + 1
        for j in range(nv):
            a, b, c, d = i * (nv + 1) + j, i2 * (nv + 1) + j, i2 * (nv + 1) + j + 1, i * (nv + 1) + j + 1
            faces += [[a, b, d], [b, c, d]] if flip else [[a, b, c], [a, c, d]]
    return np.array(faces, dtype=np.int32)


def sheet(n: int = 8, size: float = 1.0, flip: bool = False):
    """A flat size x size square in the z = 0 plane, n x n quads."""
    x = np.linspace(0.0, size, n + 1)
    X, Y = np.meshgrid(x, x, indexing="ij")
    return np.stack([X, Y, 0.0 * X], -1).reshape(-1, 3), grid_faces(n, n, flip=flip)


def plane_exact(points: np.ndarray, src: np.ndarray) -> np.ndarray:
    return np.linalg.norm(points - src, axis=1)


def cylinder(r: float = 0.1, h: float = 0.3, nt: int = 256, nz: int = 8, seam: bool = False,
             flip: bool = False):
    """Open cylinder about z (a paper lantern), nt facets round, nz rings. seam=True
    duplicates the vertices at angle 0 (a UV seam: the two columns are separate vertices)."""
    cols = nt + 1 if seam else nt
    th = np.arange(cols) * (2.0 * np.pi / nt)
    T, Z = np.meshgrid(th, np.linspace(0.0, h, nz + 1), indexing="ij")
    V = np.stack([r * np.cos(T), r * np.sin(T), Z], -1).reshape(-1, 3)
    if seam:
        return V, grid_faces(nt, nz, wrap_u=False, flip=flip)
    return V, grid_faces(nt, nz, wrap_u=True, flip=flip)


def cylinder_exact(points: np.ndarray, src: np.ndarray, r: float = 0.1) -> np.ndarray:
    """Unrolled: hypot(r * angle, dz), the angle the shorter way round."""
    th = np.arctan2(points[:, 1], points[:, 0]) - np.arctan2(src[1], src[0])
    th = np.abs(np.mod(th + np.pi, 2.0 * np.pi) - np.pi)
    return np.hypot(r * th, points[:, 2] - src[2])


def icosphere(level: int = 5, radius: float = 1.0):
    """Subdivided icosahedron (vertices on the sphere)."""
    t = (1.0 + 5.0 ** 0.5) / 2.0
    V = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    F = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [np.array(v, float) / np.linalg.norm(v) for v in V]
    for _ in range(level):
        cache: dict = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = verts[a] + verts[b]
                verts.append(m / np.linalg.norm(m))
                cache[key] = len(verts) - 1
            return cache[key]

        F = [f for a, b, c in F for f in ((a, mid(a, b), mid(c, a)), (b, mid(b, c), mid(a, b)),
                                           (c, mid(c, a), mid(b, c)), (mid(a, b), mid(b, c), mid(c, a)))]
    return radius * np.array(verts), np.array(F, dtype=np.int32)


def sphere_exact(points: np.ndarray, src: np.ndarray, radius: float = 1.0) -> np.ndarray:
    """Great-circle distance (points projected radially onto the sphere)."""
    u = points / np.linalg.norm(points, axis=1)[:, None]
    s = src / np.linalg.norm(src)
    return radius * np.arccos(np.clip(u @ s, -1.0, 1.0))


def cone(R: float = 0.2, H: float = 0.3, s_in: float = 0.25, nt: int = 256, nr: int = 16):
    """Open cone, apex at the origin, base radius R at height H; the part nearer the apex than
    s_in of the slant is cut away (a hole: geodesics wrap round its rim)."""
    th = np.arange(nt) * (2.0 * np.pi / nt)
    T, S = np.meshgrid(th, np.linspace(s_in, 1.0, nr + 1), indexing="ij")
    return np.stack([R * S * np.cos(T), R * S * np.sin(T), H * S], -1).reshape(-1, 3), grid_faces(nt, nr, wrap_u=True)


def cone_exact(points: np.ndarray, src: np.ndarray, R: float = 0.2, H: float = 0.3,
               s_in: float = 0.25) -> np.ndarray:
    """Unrolled into a sector of angle 2 pi R / L: the straight segment, or, where it would
    cross the cut-away disc round the apex, tangent segments and the arc of its rim."""
    L = np.hypot(R, H)
    rh = s_in * L
    r1, r0 = np.linalg.norm(points, axis=1), np.linalg.norm(src)
    a = (np.arctan2(points[:, 1], points[:, 0]) - np.arctan2(src[1], src[0]))
    a = np.abs(np.mod(a + np.pi, 2.0 * np.pi) - np.pi) * (R / L)
    d = np.sqrt(np.maximum(r1 ** 2 + r0 ** 2 - 2.0 * r1 * r0 * np.cos(a), 0.0))
    reach = r0 * r1 * np.sin(a) / np.maximum(d, 1e-300)  # apex to the segment's line
    foot_inside = (r0 ** 2 + d ** 2 - r1 ** 2 > 0) & (r1 ** 2 + d ** 2 - r0 ** 2 > 0)
    blocked = foot_inside & (reach < rh)
    wrap = (np.sqrt(np.maximum(r0 ** 2 - rh ** 2, 0.0)) + np.sqrt(np.maximum(r1 ** 2 - rh ** 2, 0.0))
            + rh * (a - np.arccos(np.minimum(rh / r0, 1.0)) - np.arccos(np.minimum(rh / r1, 1.0))))
    return np.where(blocked, wrap, d)


def wavy_sheet(n: int = 96, amp: float = 0.06, size: float = 1.0):
    """z = amp sin(2 pi x) sin(2 pi y) on the unit square: Gaussian curvature of both signs."""
    V, F = sheet(n, size)
    V[:, 2] = amp * np.sin(2 * np.pi * V[:, 0] / size) * np.sin(2 * np.pi * V[:, 1] / size)
    return V, F


def rigid_motion(V: np.ndarray, seed: int = 3):
    """V rotated by a random rotation and shifted; returns (moved vertices, R, shift)."""
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    shift = rng.normal(size=3) * 5.0
    return V @ q.T + shift, q, shift
