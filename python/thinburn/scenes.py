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


def lantern(radius=0.1, height=0.3, segments=128, rings=60, z=0.0):
    """An open paper cylinder (a lantern) standing on its rim at height z, axis along +z:
    (vertices (segments * (rings + 1), 3), faces). Vertex (s, k) is segment s round the axis
    (angle 2 pi s / segments from +x), ring k up the side."""
    r = V.real(radius, "radius", low=0.0, low_open=True)
    h = V.real(height, "height", low=0.0, low_open=True)
    segments = V.integer(segments, "segments", low=3)
    rings = V.integer(rings, "rings", low=1)
    from ._surface_shapes import cylinder

    v, f = cylinder(r=r, h=h, nt=segments, nz=rings)
    return v + np.array([0.0, 0.0, float(z)]), f


def sphere(radius=0.1, level=4, centre=(0.0, 0.0, 0.0)):
    """A closed sphere as a subdivided icosahedron (level 4: 2562 vertices, 5120 faces)."""
    r = V.real(radius, "radius", low=0.0, low_open=True)
    level = V.integer(level, "level", low=0, high=7)
    from ._surface_shapes import icosphere

    v, f = icosphere(level, r)
    return v + np.asarray(centre, float), f


def folded_sheet(width=A4[0], height=A4[1], angle=30.0, nx=43, ny=61, z=0.0):
    """A sheet folded across its middle (the fold along x at y = height/2): the half y < height/2
    lies flat at height z, the other half rises from the fold at `angle` degrees.
    (vertices (nx * ny, 3), faces); ny odd puts a row of vertices on the fold."""
    a = np.radians(V.real(angle, "angle", low=0.0, high=180.0))
    v, f = rect_sheet(width, height, nx=nx, ny=ny, z=z)
    half = 0.5 * V.real(height, "height", low=0.0, low_open=True)
    up = v[:, 1] > half
    s = v[up, 1] - half
    v[up, 1] = half + s * np.cos(a)
    v[up, 2] = z + s * np.sin(a)
    return v, f
