"""Bending (paper §4.2-4.3, eqs 2-6): heat and pyrolysis at a couple's two faces, and their
difference, the rotation D that bends the lattice (docs/bending.md).

    b = Bending(couples=M * M, alpha=1.0, beta=1e-3)     # the BendingParams keywords
    b.add_particle_heat(control, particles, temperatures, dt)   # eq 2, accumulates
    b.set_pyrolysis(control, ignition_points)                   # eq 3, recomputed
    D = b.rotation()                                            # eqs 4-6, (M*M,) radians

Control vertices are (2 M², 3), index 2·couple + k, k = 1 the top face. A Simulation builds
its own; this class is the part on its own, for tests and experiments.
"""
from __future__ import annotations

import numpy as np

from . import _core
from . import _validate as V
from .params import names

KEYS = names("bending")  # ct, cp, alpha, beta, d_min, pyrolysis_range, max_rotation, heat_tolerance, heat_fast
DEFAULTS = dict(_core.Bending(1).params)


class Bending:
    """Eqs 2-6 for ``couples`` couples; keyword arguments are ``KEYS`` (DEFAULTS)."""

    def __init__(self, couples: int, **params):
        n = V.integer(couples, "couples", low=1, high=2**30)
        for key in params:
            if key not in KEYS:
                raise TypeError(f"Bending() got an unexpected keyword argument {key!r}; parameters are {list(KEYS)}")
        self._b = _core.Bending(n, **params)
        self.couples = n

    def _control(self, control) -> np.ndarray:
        return V.real_array(control, "control", (2 * self.couples, 3))

    def add_particle_heat(self, control, particles, temperatures, dt) -> None:
        """Eq 2: each particle A gives each control vertex B Ct·T_A·dt / (4π (d_AB + d_min)²)."""
        p = V.real_array(particles, "particles", (-1, 3))
        t = V.real_array(temperatures, "temperatures", (len(p),))
        self._b.add_particle_heat(self._control(control), p, t, V.real(dt, "dt", low=0.0, low_open=True))

    def set_pyrolysis(self, control, ignition_points) -> None:
        """Eq 3: P_B = Cp · Σ 1 / (dis + d_min) over the ignition points, recomputed."""
        self._b.set_pyrolysis(self._control(control), V.real_array(ignition_points, "ignition_points", (-1, 3)))

    def rotation(self) -> np.ndarray:
        """Eqs 4-6: D = Dmax·tanh((α·(T_top − T_bottom) + β·(P_top − P_bottom)) / Dmax) per couple."""
        return np.asarray(self._b.rotation())

    @property
    def heat(self) -> np.ndarray:
        return np.asarray(self._b.heat)

    @property
    def heat_rate(self) -> np.ndarray:
        return np.asarray(self._b.heat_rate)

    @property
    def pyrolysis(self) -> np.ndarray:
        return np.asarray(self._b.pyrolysis)

    @property
    def params(self) -> dict:
        return dict(self._b.params)
