"""Input checks shared by the public API: every message names the argument."""
from __future__ import annotations

import numbers

import numpy as np


def _check_kind(a: np.ndarray, name: str, kinds: str) -> None:
    if a.dtype.kind not in kinds:
        raise TypeError(f"{name} must hold {'integers' if kinds == 'iu' else 'real numbers'}, got dtype {a.dtype}")


def real_array(value, name: str, shape: tuple, *, finite: bool = True) -> np.ndarray:
    """A float64 C-contiguous copy of value, with shape checked (-1 = any length)."""
    if value is None:
        raise TypeError(f"{name} must be an array, got None")
    try:
        a = np.asarray(value)
    except Exception as exc:  # ragged lists and the like
        raise TypeError(f"{name} must be an array of numbers: {exc}") from None
    if a.dtype == object:
        raise TypeError(f"{name} must be an array of numbers, got objects")
    _check_kind(a, name, "iuf")
    if a.ndim != len(shape) or any(s != -1 and s != n for s, n in zip(shape, a.shape)):
        want = "(" + ", ".join("n" if s == -1 else str(s) for s in shape) + ")"
        raise ValueError(f"{name} has invalid shape: expected {want} but got {a.shape}")
    a = np.ascontiguousarray(a, dtype=np.float64)
    if finite and not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or inf")
    return a


def index_array(value, name: str, shape: tuple, upper: int) -> np.ndarray:
    """An int32 C-contiguous copy, each entry in [0, upper)."""
    if value is None:
        raise TypeError(f"{name} must be an array, got None")
    a = np.asarray(value)
    if a.dtype == object:
        raise TypeError(f"{name} must be an array of integers, got objects")
    if a.dtype.kind == "f" and a.size and np.all(np.isfinite(a)) and np.all(a == np.round(a)):
        if np.abs(a).max() >= 2.0**62:  # would not cast to int64
            raise ValueError(f"{name} has indices out of range [0, {upper}): min {a.min():g}, max {a.max():g}")
        a = a.astype(np.int64)
    _check_kind(a, name, "iu")
    if a.ndim != len(shape) or any(s != -1 and s != n for s, n in zip(shape, a.shape)):
        want = "(" + ", ".join("n" if s == -1 else str(s) for s in shape) + ")"
        raise ValueError(f"{name} has invalid shape: expected {want} but got {a.shape}")
    if a.size and (a.min() < 0 or a.max() >= upper):
        raise ValueError(f"{name} has indices out of range [0, {upper}): min {a.min()}, max {a.max()}")
    return np.ascontiguousarray(a, dtype=np.int32)


def real(value, name: str, *, low=None, high=None, low_open=False, high_open=False) -> float:
    """A finite float within bounds."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__}")
    try:
        v = float(value)
    except OverflowError:
        raise ValueError(f"{name} must be finite, got an int too large for a float") from None
    if not np.isfinite(v):
        raise ValueError(f"{name} must be finite, got {v}")
    if low is not None and (v < low or (low_open and v == low)):
        raise ValueError(f"{name} must be {'>' if low_open else '>='} {low}, got {v}")
    if high is not None and (v > high or (high_open and v == high)):
        raise ValueError(f"{name} must be {'<' if high_open else '<='} {high}, got {v}")
    return v


def integer(value, name: str, *, low=None, high=None) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an int, got {type(value).__name__}")
    v = int(value)
    if low is not None and v < low:
        raise ValueError(f"{name} must be >= {low}, got {v}")
    if high is not None and v > high:
        raise ValueError(f"{name} must be <= {high}, got {v}")
    return v


def vector3(value, name: str) -> np.ndarray:
    return real_array(value, name, (3,))


def choice(value, name: str, options) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a str, one of {sorted(options)}, got {type(value).__name__}")
    if value not in options:
        raise ValueError(f"{name}: unknown value {value!r}; choose one of {sorted(options)}")
    return value
