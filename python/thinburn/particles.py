"""Fire particles (Reeves 1983), the heat source of Liu et al. 2009 §4.2 eq (2).

Particles are born at burning fringe cells, carry a temperature (K above ambient) that
decays as ``temperature0 * exp(-cooling * age)``, rise with a buoyancy proportional to it,
relax toward the wind at rate ``drag``, feel a turbulent velocity fluctuation of rms
``turbulence`` (an Ornstein-Uhlenbeck process), and die at a jittered lifetime. The pool
has a fixed capacity; a birth that finds it full is dropped and counted in ``dropped``.
Results are bit-identical for a given seed and inputs, at any thread count.

SI units, z up. See docs/particles.md for the model and its defaults.
"""
from __future__ import annotations

import numpy as np

from . import _core
from .heat import _int, _points, _real, _vector
from .params import FIELDS

__all__ = ["ParticleSystem", "DEFAULTS"]

#: The default parameters (a burning sheet of paper: flames about 3-10 cm tall).
DEFAULTS = dict(_core.ParticleSystem().params)

# name -> (low, high, low_open, high_open) for real parameters: the core's table's bounds.
_REAL_RANGES = {f.name: (f.low, f.high, f.low_open, f.high_open)
                for f in FIELDS["particles"].values() if f.kind == "real"}
_CAPACITY = FIELDS["particles"]["capacity"]


def _validate_params(kwargs: dict) -> dict:
    unknown = set(kwargs) - set(DEFAULTS)
    if unknown:
        raise TypeError(f"unknown particle parameter(s): {', '.join(sorted(unknown))}")
    out = {}
    for name, value in kwargs.items():
        if name == "capacity":
            out[name] = _int(name, value, low=int(_CAPACITY.low), high=int(_CAPACITY.high))
        elif name == "seed":
            out[name] = _int(name, value, low=0, high=2**64 - 1)
        else:
            lo, hi, lo_open, hi_open = _REAL_RANGES[name]
            out[name] = _real(name, value, low=lo, high=hi, low_open=lo_open, high_open=hi_open)
    return out


class ParticleSystem(_core.ParticleSystem):
    """A fixed-capacity, deterministic pool of fire particles.

    Keyword arguments (all optional, defaults in DEFAULTS): capacity, birth_rate (1/(s m)),
    temperature0 (K above ambient), cooling (1/s), lifetime (s), lifetime_jitter (fraction),
    buoyancy (m/s^2 at temperature0), drag (1/s), turbulence (m/s rms), birth_speed (m/s),
    vertical_band (|n.z| below which both sides emit), seed.
    """

    def __init__(self, **params):
        super().__init__(**_validate_params(params))

    def emit(self, pos, normal, length, dt) -> None:
        """Emit for one step of length dt (s) from k emitters: positions (k, 3), sheet normals
        (k, 3, nonzero), front lengths (k,) in m. Expected births: birth_rate * length * dt."""
        p = _points("pos", pos)
        n = _points("normal", normal)
        if n.shape != p.shape:
            raise ValueError(f"normal must have shape {p.shape}, got {n.shape}")
        if n.size and np.min(np.linalg.norm(n, axis=1)) <= 1e-12:
            raise ValueError("normal must be nonzero in every row")
        ln = _vector("length", length, p.shape[0])
        dt = _real("dt", dt, low=0.0)
        super().emit(p, n, ln, dt)

    def step(self, dt, wind=(0.0, 0.0, 0.0)) -> None:
        """Advance by dt (s) in a uniform wind (3,) in m/s: cool, drag, buoyancy, turbulence,
        age, and remove the dead."""
        dt = _real("dt", dt, low=0.0)
        w = np.asarray(wind)
        if w.dtype.kind not in "iuf":
            raise TypeError(f"wind must be a real numeric array, got dtype {w.dtype}")
        if w.shape != (3,):
            raise ValueError(f"wind must have shape (3,), got {w.shape}")
        w = w.astype(np.float64)
        if not np.all(np.isfinite(w)):
            raise ValueError("wind must be finite")
        super().step(dt, w)
