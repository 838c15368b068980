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


MIN_BANDWIDTH_BYTES = 3 * 8 * 1024


def measure_memory_bandwidth(bytes: int = 512 * 2**20, repeat: int = 10) -> float:
    """Machine probe: sustained memory bandwidth in bytes/s on the core's current threads.

    A STREAM-style triad a = b + s·c over three float64 arrays of ``bytes`` in all (default
    512 MiB, many times a usual last-level cache; at least 24576), fastest of ``repeat``
    passes (>= 1), counted as STREAM counts it: 24 bytes per element (two reads, one write;
    the write-allocate read is not counted). Releases the GIL. Bad arguments raise ValueError
    (TypeError for non-integers) naming the argument.
    """
    from . import _validate as V
    n = V.integer(bytes, "bytes", low=MIN_BANDWIDTH_BYTES)
    r = V.integer(repeat, "repeat", low=1)
    return float(_core.measure_memory_bandwidth(n, r))
