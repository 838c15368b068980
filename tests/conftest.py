import numpy as np
import pytest

from thinburn.scenes import rect_sheet


@pytest.fixture
def a4():
    """An A4 sheet lying flat: (vertices, faces)."""
    return rect_sheet(0.210, 0.297, nx=22, ny=31)


@pytest.fixture
def square():
    """A 0.2 m square sheet lying flat: (vertices, faces)."""
    return rect_sheet(0.2, 0.2, nx=21, ny=21)


def disk_mesh(radius=0.1, rings=12, segments=48):
    """A flat disk fan mesh in the xy-plane."""
    verts = [(0.0, 0.0, 0.0)]
    for r in range(1, rings + 1):
        rr = radius * r / rings
        for s in range(segments):
            a = 2 * np.pi * s / segments
            verts.append((rr * np.cos(a), rr * np.sin(a), 0.0))
    faces = []
    for s in range(segments):
        faces.append((0, 1 + s, 1 + (s + 1) % segments))
    for r in range(1, rings):
        b0, b1 = 1 + (r - 1) * segments, 1 + r * segments
        for s in range(segments):
            s1 = (s + 1) % segments
            faces.append((b0 + s, b1 + s, b1 + s1))
            faces.append((b0 + s, b1 + s1, b0 + s1))
    return np.array(verts), np.array(faces)
