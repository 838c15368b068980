"""The core's thread count: explicit, settable, never read from the environment."""
from __future__ import annotations

import warnings

from . import _core


def has_openmp() -> bool:
    """Whether the C++ core was built with OpenMP."""
    return bool(_core.has_openmp())


def set_threads(n: int | None) -> int:
    """Set the number of threads the core uses; None means all logical cores.

    Returns the count now in force. Results are identical for every count.
    """
    if n is None:
        n = _core.max_hardware_threads()
    if isinstance(n, bool) or not isinstance(n, int):
        raise TypeError(f"threads must be an int or None, got {type(n).__name__}")
    if n < 1:
        raise ValueError(f"threads must be >= 1, got {n}")
    if n > 1 and not _core.has_openmp():
        warnings.warn("thinburn was built without OpenMP; running on 1 thread", RuntimeWarning,
                      stacklevel=2)
        n = 1
    _core.set_num_threads(n)
    return n


def get_threads() -> int:
    """The number of threads the core uses now."""
    return int(_core.num_threads())
