"""The core's thread count: explicit, settable, never read from the environment.

The core runs its parallel loops on a small pool of its own (docs/threads.md): the calling
thread claims chunks of each loop alongside the pool's helpers and never waits for a helper
that has not started, so on a busy machine extra threads cost almost nothing. A Simulation
keeps its own count (``threads=``); ``set_threads`` sets the default for the one-shot
functions (``arrival_times``, the heat sums, the FFD of ``thinburn.lattice``).
"""
from __future__ import annotations

import numbers

from . import _core


def hardware_threads() -> int:
    """Logical cores of this machine."""
    return int(_core.hardware_threads())


def max_threads() -> int:
    """The largest thread count accepted: 4 x the logical cores, at least 8."""
    return int(_core.max_threads())


def resolve_threads(n, name: str = "threads") -> int:
    """A thread count from None (all logical cores) or an integer in [1, max_threads()]."""
    if n is None:
        return hardware_threads()
    if isinstance(n, bool) or not isinstance(n, numbers.Integral):
        raise TypeError(f"{name} must be an int or None, got {type(n).__name__}")
    n = int(n)
    top = max_threads()
    if not 1 <= n <= top:
        raise ValueError(f"{name} must be in [1, {top}] (4 x the {hardware_threads()} logical cores, "
                         f"at least 8) or None for all cores, got {n}")
    return n


def set_threads(n: int | None) -> int:
    """Set the default number of threads the core uses; None means all logical cores.

    Returns the count now in force. Results are identical for every count.
    """
    n = resolve_threads(n)
    _core.set_num_threads(n)
    return n


def get_threads() -> int:
    """The default number of threads the core uses now."""
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
