"""Built-in meshes and scenes: numpy arrays, no Blender needed."""
from __future__ import annotations

import numpy as np

from . import _validate as V

A4 = (0.210, 0.297)  # metres


def rect_sheet(width=A4[0], height=A4[1], nx=43, ny=61, *, vertical=False, z=0.0):
    """A flat rectangular sheet as a triangle grid: (vertices (nx*ny, 3), faces (m, 3)).

    Lying in the xy-plane at height z, or hanging in the xz-plane (vertical=True) with its
    bottom edge at z. Vertex (i, j) is row i (along y, or z when hanging), column j (along x).
    """
    w = V.real(width, "width", low=0.0, low_open=True)
    h = V.real(height, "height", low=0.0, low_open=True)
    nx = V.integer(nx, "nx", low=2)
    ny = V.integer(ny, "ny", low=2)
    x, y = np.meshgrid(np.linspace(0.0, w, nx), np.linspace(0.0, h, ny))
    if vertical:
        verts = np.stack([x.ravel(), np.zeros(x.size), y.ravel() + z], axis=1)
    else:
        verts = np.stack([x.ravel(), y.ravel(), np.full(x.size, float(z))], axis=1)
    i, j = np.meshgrid(np.arange(ny - 1), np.arange(nx - 1), indexing="ij")
    a = (i * nx + j).ravel()
    b, c, d = a + 1, a + nx, a + nx + 1
    faces = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]).astype(np.int32)
    return verts, faces


def grid_uv(nx, ny):
    """The natural UV of rect_sheet(nx=nx, ny=ny): (nx*ny, 2) in [0, 1]^2."""
    u, v = np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 1, ny))
    return np.stack([u.ravel(), v.ravel()], axis=1)


def disk_sheet(radius=0.1, rings=12, segments=48, z=0.0):
    """A flat disk in the xy-plane at height z, as a fan of rings: (vertices, faces)."""
    radius = V.real(radius, "radius", low=0.0, low_open=True)
    rings = V.integer(rings, "rings", low=1)
    segments = V.integer(segments, "segments", low=3)
    rr = np.repeat(radius * np.arange(1, rings + 1) / rings, segments)
    a = np.tile(2 * np.pi * np.arange(segments) / segments, rings)
    verts = np.concatenate([[[0.0, 0.0, z]], np.stack([rr * np.cos(a), rr * np.sin(a), np.full(a.size, float(z))], 1)])
    s = np.arange(segments)
    s1 = (s + 1) % segments
    faces = [np.stack([np.zeros(segments, int), 1 + s, 1 + s1], 1)]
    for r in range(1, rings):
        b0, b1 = 1 + (r - 1) * segments, 1 + r * segments
        faces.append(np.stack([b0 + s, b1 + s, b1 + s1], 1))
        faces.append(np.stack([b0 + s, b1 + s1, b0 + s1], 1))
    return verts, np.concatenate(faces).astype(np.int32)
