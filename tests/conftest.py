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
