"""Motion of the FFD lattice (Liu et al. 2009 §4.3): presets and input checks around
_core.LatticeDynamics. Keyword arguments of LatticeDynamics are the DynamicsParams fields; see
docs/dynamics.md for their units and readings.
"""
from __future__ import annotations

import numpy as np

from . import _core
from . import _validate as V
from .materials import MATERIALS

LatticeDynamics = _core.LatticeDynamics
Integrator = _core.Integrator
StepStats = _core.StepStats
explicit_stability_limit = _core.explicit_stability_limit
crumple_displacements = _core.crumple_displacements

__all__ = ["PRESETS", "Integrator", "LatticeDynamics", "StepStats", "crumple_displacements",
           "explicit_stability_limit", "preset", "vertex_masses"]

# The motion of each Table 1 row (thinburn.MATERIALS), as a Simulation of that material gets
# it: spring coefficients (times stiffness_unit N/m), C_damping (1/s, per kg), and what the
# core's set_material derives from them (the transverse diagonals as stiff as the structure
# springs, crumple_gain = 0.05 / K_structure; docs/materials.md).
_MATERIAL_KEYS = ("k_structure", "k_shear", "k_flex", "c_damping", "k_transverse", "crumple_gain")


def _material_motion(m) -> dict:
    p = _core.SimulationParams()
    p.set_material(k_structure=m.K_structure, k_shear=m.K_shear, k_flex=m.K_flex, c_damping=m.C_damping)
    return {k: p.dynamics[k] for k in _MATERIAL_KEYS}


PRESETS = {name: _material_motion(m) for name, m in MATERIALS.items()}


def preset(name: str, **overrides) -> dict:
    """Keyword arguments for LatticeDynamics from a Table 1 preset, with overrides."""
    if not isinstance(name, str):
        raise TypeError(f"name must be a str, one of {sorted(PRESETS)}, got {type(name).__name__}")
    if name not in PRESETS:
        raise ValueError(f"name must be one of {sorted(PRESETS)}, got {name!r}")
    return {**PRESETS[name], **overrides}


def vertex_masses(M: int, area: float, areal_density: float) -> np.ndarray:
    """Masses (kg) of the 2 M^2 control vertices of a sheet of the given area (m^2) and areal
    density (kg/m^2), spread like the trilinear embedding of a uniform sheet: border couples
    carry half, corners a quarter, split evenly between top and bottom."""
    if isinstance(M, bool) or not isinstance(M, (int, np.integer)) or M < 2:
        raise ValueError(f"M must be an int >= 2, got {M!r}")
    area = V.real(area, "area", low=0.0, low_open=True)
    areal_density = V.real(areal_density, "areal_density", low=0.0, low_open=True)
    w = np.ones(M)
    w[[0, -1]] = 0.5
    share = np.outer(w, w) / (M - 1) ** 2
    return np.repeat((share * area * areal_density / 2.0).ravel(), 2)
