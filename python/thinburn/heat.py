"""Heat from fire particles and pyrolysis from ignition points (Liu et al. 2009, §4.2).

Both are kernel sums ``S(y) = sum_i w_i / (|y - x_i| + d_min)**p`` with ``w_i >= 0``:

* eq (2), heat received by a control vertex in one step, ``p = 2``:
  ``dT_B = Ct * dt / (4 pi) * sum_A T_A / (d_AB + d_min)**2``;
* eq (3), pyrolysis from ignition points, ``p = 1``: ``P_B = Cp * sum_i 1 / (dis_iB + d_min)``.

``method="direct"`` sums every pair (the reference). ``method="fast"`` walks an octree and
replaces a cell by its moments (weight, centroid, second and third moments) when a proven
bound says the error is small enough: every result is within ``tolerance`` relative error
of the direct sum, and ``return_bound=True`` also gives a per-target absolute bound on the
error, itself at most ``tolerance`` times the sum. See docs/heat.md.

SI units: positions in m, ``d_min`` in m.
"""
from __future__ import annotations

import numbers

import numpy as np

from . import _core

__all__ = ["KernelSummer", "kernel_sum", "particle_heat", "pyrolysis"]

_METHODS = ("direct", "fast")


def _points(name: str, a) -> np.ndarray:
    """An (n, 3) finite float64 C-contiguous array, or ValueError/TypeError naming `name`."""
    arr = np.asarray(a)
    if arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must be a real numeric array, got dtype {arr.dtype}")
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), got {arr.shape}")
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    return arr


def _vector(name: str, a, n: int, nonnegative: bool = True) -> np.ndarray:
    """A length-n finite float64 vector (>= 0 if asked), or ValueError/TypeError naming `name`."""
    arr = np.asarray(a)
    if arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must be a real numeric array, got dtype {arr.dtype}")
    if arr.ndim != 1 or arr.shape[0] != n:
        raise ValueError(f"{name} must have shape ({n},), got {arr.shape}")
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    if nonnegative and arr.size and arr.min() < 0.0:
        raise ValueError(f"{name} must be >= 0")
    return arr


def _real(name: str, v, *, low=None, high=None, low_open=False, high_open=False) -> float:
    """A finite real scalar within [low, high] (open ends as asked), or ValueError/TypeError."""
    if isinstance(v, bool) or not isinstance(v, numbers.Real):
        raise TypeError(f"{name} must be a real number, got {type(v).__name__}")
    try:
        x = float(v)
    except OverflowError:
        raise ValueError(f"{name} must be finite, got an int too large for a float") from None
    if not np.isfinite(x):
        raise ValueError(f"{name} must be finite, got {x}")
    if low is not None and (x <= low if low_open else x < low):
        raise ValueError(f"{name} must be {'>' if low_open else '>='} {low}, got {x}")
    if high is not None and (x >= high if high_open else x > high):
        raise ValueError(f"{name} must be {'<' if high_open else '<='} {high}, got {x}")
    return x


def _int(name: str, v, *, low=None, high=None) -> int:
    """An integer within [low, high], or ValueError/TypeError naming `name`."""
    if isinstance(v, bool) or not isinstance(v, numbers.Integral):
        raise TypeError(f"{name} must be an int, got {type(v).__name__}")
    i = int(v)
    if (low is not None and i < low) or (high is not None and i > high):
        raise ValueError(f"{name} must be in [{low}, {high}], got {i}")
    return i


def _options(power, d_min, method, tolerance, return_bound):
    if isinstance(power, bool) or not isinstance(power, numbers.Integral):
        raise TypeError(f"power must be an int (1 or 2), got {type(power).__name__}")
    if int(power) not in (1, 2):
        raise ValueError(f"power must be 1 or 2, got {power}")
    d_min = _real("d_min", d_min, low=0.0, low_open=True)
    if not isinstance(method, str):
        raise TypeError(f"method must be a str, got {type(method).__name__}")
    if method not in _METHODS:
        raise ValueError(f"method must be one of {_METHODS}, got {method!r}")
    tolerance = _real("tolerance", tolerance, low=0.0, high=1.0, low_open=True, high_open=True)
    if not isinstance(return_bound, bool):
        raise TypeError(f"return_bound must be a bool, got {type(return_bound).__name__}")
    return int(power), d_min, method, tolerance


def kernel_sum(sources, weights, targets, power=2, d_min=0.01, method="fast", tolerance=0.01,
               return_bound=False, cutoff=0.0):
    """``out[j] = sum_i weights[i] / (|targets[j] - sources[i]| + d_min)**power``.

    Args:
        sources: (n, 3) source positions, m.
        weights: (n,) weights, finite and >= 0.
        targets: (m, 3) target positions, m.
        power: 1 (pyrolysis, eq 3) or 2 (heat, eq 2).
        d_min: m, > 0; keeps the kernel finite at zero distance.
        method: "direct" (every pair) or "fast" (octree with a proven error bound).
        tolerance: in (0, 1); with "fast" every out[j] is within this relative error.
        return_bound: also return a per-target bound on |out[j] - exact[j]| (zero for direct).
        cutoff: m, >= 0. 0: every source counts. > 0: the kernel minus its value at the cutoff,
            summed exactly over the sources closer than the cutoff (method and tolerance unused):
            differences between targets keep the sources within the cutoff of both.

    Returns:
        out, or (out, bound) with return_bound.
    """
    power, d_min, method, tolerance = _options(power, d_min, method, tolerance, return_bound)
    cutoff = _real("cutoff", cutoff, low=0.0)
    src = _points("sources", sources)
    w = _vector("weights", weights, src.shape[0])
    tgt = _points("targets", targets)
    return _core.kernel_sum(src, w, tgt, power=power, d_min=d_min, method=method,
                            tolerance=tolerance, return_bound=return_bound, cutoff=cutoff)


def particle_heat(particles, temperatures, vertices, ct, dt, d_min=0.01, method="fast",
                  tolerance=0.01, return_bound=False):
    """Heat received in one step by each vertex, eq (2):
    ``ct * dt / (4 pi) * sum_A temperatures[A] / (|vertices[j] - particles[A]| + d_min)**2``.

    temperatures are K above ambient (>= 0); ct >= 0; dt >= 0 in s. Other arguments as in
    kernel_sum.
    """
    _, d_min, method, tolerance = _options(2, d_min, method, tolerance, return_bound)
    ct = _real("ct", ct, low=0.0)
    dt = _real("dt", dt, low=0.0)
    src = _points("particles", particles)
    t = _vector("temperatures", temperatures, src.shape[0])
    tgt = _points("vertices", vertices)
    return _core.particle_heat(src, t, tgt, ct=ct, dt=dt, d_min=d_min, method=method,
                               tolerance=tolerance, return_bound=return_bound)


def pyrolysis(ignition_points, vertices, cp, d_min=0.01, method="fast", tolerance=0.01,
              return_bound=False, cutoff=0.0):
    """Pyrolysis of each vertex from the ignition points, eq (3):
    ``cp * sum_i 1 / (|vertices[j] - ignition_points[i]| + d_min)``; with ``cutoff`` > 0 over
    the points closer than it, each less ``1 / (cutoff + d_min)`` (the Simulation's
    ``pyrolysis_range``, docs/dynamics.md §2).

    cp >= 0. Other arguments as in kernel_sum.
    """
    _, d_min, method, tolerance = _options(1, d_min, method, tolerance, return_bound)
    cp = _real("cp", cp, low=0.0)
    cutoff = _real("cutoff", cutoff, low=0.0)
    src = _points("ignition_points", ignition_points)
    tgt = _points("vertices", vertices)
    return _core.pyrolysis(src, tgt, cp=cp, d_min=d_min, method=method, tolerance=tolerance,
                           return_bound=return_bound, cutoff=cutoff)


class KernelSummer:
    """An octree over weighted sources, built once and evaluated at many targets.

    It keeps its buffers between builds; a simulation holds one and rebuilds it each step.
    """

    def __init__(self):
        self._core = _core.KernelSummer()

    def build(self, sources, weights) -> None:
        """Build the tree over sources (n, 3) with weights (n,), finite and >= 0."""
        src = _points("sources", sources)
        w = _vector("weights", weights, src.shape[0])
        self._core.build(src, w)

    def evaluate(self, targets, power=2, d_min=0.01, method="fast", tolerance=0.01,
                 return_bound=False):
        """The kernel sum of the built sources at targets (m, 3); arguments as in kernel_sum."""
        power, d_min, method, tolerance = _options(power, d_min, method, tolerance, return_bound)
        tgt = _points("targets", targets)
        return self._core.evaluate(tgt, power=power, d_min=d_min, method=method,
                                   tolerance=tolerance, return_bound=return_bound)

    @property
    def size(self) -> int:
        """Number of sources given to the last build."""
        return int(self._core.size)

    @property
    def node_count(self) -> int:
        """Number of tree nodes."""
        return int(self._core.node_count)
