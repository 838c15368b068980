"""The fire front on the sheet's cell grid (paper §3, eq 1): arrival (ignition) times.

Methods (``FRONT_METHODS``):

- ``"cellular"``: the paper's rule, a burning cell ignites each of its 8 neighbours at
  t_ig + distance / V, earliest wins (Dijkstra). Octagonal fronts, up to 8.24 % late.
- ``"cellular16"``: the same rule with knight moves added; up to 2.75 % late.
- ``"fmm1"``: first-order fast marching for F |grad T| = 1.
- ``"fmm"``: second-order fast marching, factored at the sources (T = t0 + T0 tau); exact
  for uniform speed and drive, second order in smooth isotropic media.

Speeds are per cell (m/s); an optional drive (e_row, e_col), |e| < 1, makes spread
direction-dependent: the front from a point is the ellipse with the source at a focus, head
speed v(1+|e|), back speed v(1-|e|). See docs/fire_front.md.
"""
from __future__ import annotations

import numbers
from typing import Iterable, Sequence

import numpy as np

from . import _core

__all__ = ["FRONT_METHODS", "FireFront", "FrontMethod", "arrival_times", "method_enum"]

FRONT_METHODS = ("cellular", "cellular16", "fmm1", "fmm")
FireFront = _core.FireFront
FrontMethod = _core.FrontMethod
_ENUMS = {
    "cellular": _core.FrontMethod.Cellular8,
    "cellular16": _core.FrontMethod.Cellular16,
    "fmm1": _core.FrontMethod.Fmm1,
    "fmm": _core.FrontMethod.Fmm2,
}


def method_enum(method: str) -> _core.FrontMethod:
    """The C++ FrontMethod for a name in FRONT_METHODS."""
    if not isinstance(method, str):
        raise TypeError(f"method must be a str, one of {FRONT_METHODS}, got {type(method).__name__}")
    if method not in _ENUMS:
        raise ValueError(f"method must be one of {FRONT_METHODS}, got {method!r}")
    return _ENUMS[method]


def _real_array(x, name: str) -> np.ndarray:
    """x as a float64 array; refuses bool, complex, object and text dtypes."""
    try:
        arr = np.asarray(x)
    except (TypeError, ValueError) as err:
        raise TypeError(f"{name} must be a numeric array: {err}") from None
    if arr.dtype.kind not in "fiu":
        raise TypeError(f"{name} must have a real numeric dtype (float or int), got {arr.dtype}")
    arr = arr.astype(np.float64, copy=False)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    return arr


def _real_scalar(x, name: str) -> float:
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, numbers.Real):
        raise TypeError(f"{name} must be a real number, got {type(x).__name__}")
    try:
        value = float(x)
    except OverflowError:
        raise ValueError(f"{name} must be finite, got an int too large for a float") from None
    if not np.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value}")
    return value


def _speed(speed) -> np.ndarray:
    arr = _real_array(speed, "speed")
    if arr.ndim != 2:
        raise ValueError(f"speed must be a 2-D (ny, nx) array, got shape {arr.shape}")
    if arr.shape[0] < 1 or arr.shape[1] < 1:
        raise ValueError(f"speed must have at least one row and column, got shape {arr.shape}")
    if np.any(arr < 0.0):
        raise ValueError("speed must be >= 0 everywhere (0 marks a cell that never burns)")
    return np.ascontiguousarray(arr)


def _spacing(spacing) -> tuple[float, float]:
    if isinstance(spacing, (str, bytes)):
        raise TypeError(f"spacing must be a positive number or a (dy, dx) pair, got {type(spacing).__name__}")
    if isinstance(spacing, numbers.Real) and not isinstance(spacing, (bool, np.bool_)):
        pair = (spacing, spacing)
    elif isinstance(spacing, (Sequence, np.ndarray)) and not isinstance(spacing, (bool, np.bool_)):
        pair = tuple(spacing) if np.ndim(spacing) == 1 else ()
        if len(pair) != 2:
            raise ValueError(f"spacing must be a number or a (dy, dx) pair, got {spacing!r}")
    else:
        raise TypeError(f"spacing must be a positive number or a (dy, dx) pair, got {type(spacing).__name__}")
    dy, dx = (_real_scalar(s, "spacing") for s in pair)
    if dy <= 0.0 or dx <= 0.0:
        raise ValueError(f"spacing must be > 0, got {(dy, dx)}")
    return dy, dx


def _sources(sources, ny: int, nx: int) -> list[tuple[float, float, float]]:
    if isinstance(sources, (str, bytes, dict)) or not isinstance(sources, (Iterable, np.ndarray)):
        raise TypeError(f"sources must be a list of (row, col) or (row, col, t0), got {type(sources).__name__}")
    out = []
    for i, src in enumerate(sources):
        if isinstance(src, (str, bytes)) or not isinstance(src, (Sequence, np.ndarray)):
            raise TypeError(f"sources[{i}] must be (row, col) or (row, col, t0), got {type(src).__name__}")
        if len(src) not in (2, 3):
            raise ValueError(f"sources[{i}] must have 2 or 3 entries (row, col[, t0]), got {len(src)}")
        row = _real_scalar(src[0], f"sources[{i}] row")
        col = _real_scalar(src[1], f"sources[{i}] col")
        t0 = _real_scalar(src[2], f"sources[{i}] t0") if len(src) == 3 else 0.0
        if not (-0.5 <= row <= ny - 0.5 and -0.5 <= col <= nx - 0.5):
            raise ValueError(f"sources[{i}] = ({row}, {col}) lies outside the grid "
                             f"(rows -0.5..{ny - 0.5}, cols -0.5..{nx - 0.5})")
        out.append((row, col, t0))
    return out


def _drive(drive, ny: int, nx: int):
    if drive is None:
        return None, None
    arr = _real_array(drive, "drive")
    if arr.shape == (2,):
        arr = np.broadcast_to(arr, (ny, nx, 2))
    elif arr.shape != (ny, nx, 2):
        raise ValueError(f"drive must be None, a (2,) pair or shape ({ny}, {nx}, 2), got {arr.shape}")
    if np.any(np.hypot(arr[..., 0], arr[..., 1]) >= 1.0):
        raise ValueError("drive must have |e| < 1 everywhere")
    return np.ascontiguousarray(arr[..., 0]), np.ascontiguousarray(arr[..., 1])


def arrival_times(speed, sources, spacing=1.0, method: str = "fmm", drive=None) -> np.ndarray:
    """Arrival (ignition) times of the fire front from point sources.

    speed: (ny, nx) spread speeds >= 0 in m/s, finite; 0 marks a cell that never burns.
    sources: list of (row, col) or (row, col, t0): fractional grid coordinates (cell centres
        at integers, inside [-0.5, ny-0.5] x [-0.5, nx-0.5]) and ignition time (default 0).
    spacing: cell size in metres, a number or (dy, dx).
    method: one of FRONT_METHODS.
    drive: None, an (e_row, e_col) pair used everywhere, or (ny, nx, 2); |e| < 1. Spread is
        then fastest along e: the front from a point is the focus-at-source ellipse.
    Returns (ny, nx) float64 times in seconds, +inf where the fire never arrives.
    """
    speed = _speed(speed)
    ny, nx = speed.shape
    dy, dx = _spacing(spacing)
    m = method_enum(method)
    src = _sources(sources, ny, nx)
    e_row, e_col = _drive(drive, ny, nx)
    return _core.arrival_times(speed, ny, nx, e_row, e_col, src, dy, dx, m)
