"""Material presets: the paper's Table 1, with documented defaults for what it leaves out.

Units are SI with the scene unit = 1 m. Table 1 gives no units; our readings:

* ``mass``: areal density in units of 0.1 kg/m^2 (paper 0.45 -> 45 g/m^2, a light printing
  paper; cloth 1.45 -> 145 g/m^2, a cotton shirting).
* ``V0``: spread speed in mm/s (paper 3.5 mm/s against the ~4 mm/s measured for 80 g/m^2
  paper spreading horizontally; see docs/units.md).
* ``Cp``, ``C_damping``, ``K_*``: passed to the model as they are; docs/dynamics.md gives the
  scale that turns them into forces.

Everything else is ours, chosen and documented in docs/materials.md.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace
from types import MappingProxyType


@dataclass(frozen=True)
class Material:
    """One burnable material. The first seven fields are Table 1's columns."""

    name: str
    mass: float          # Table 1, areal density in 0.1 kg/m^2
    V0: float            # Table 1, spread speed in mm/s
    Cp: float            # Table 1, pyrolysis coefficient (eq 3)
    C_damping: float     # Table 1, damping coefficient (eq 12)
    K_structure: float   # Table 1
    K_shear: float       # Table 1
    K_flex: float        # Table 1
    figure: int = 0      # the paper's figure that used this row
    # --- not in the paper; our documented defaults ---
    Cv: float = 0.5               # eq 1 spread coefficient (grad = 1, a 45° slope, halves V)
    burn_duration: float = 4.0    # s a cell burns before it is burnt
    speed_noise: float = 0.15     # relative jitter of V0, smooth over ~10 cells (organic fronts)
    duration_noise: float = 0.2   # relative per-cell jitter of the burn duration
    ash_fraction: float = 0.1     # share of its mass a burnt cell keeps as ash
    ash_strength: float = 0.1     # share of the lattice's stiffness burnt sheet keeps (Fig. 9)
    alpha: float = 1.0            # eq 6: radians of rotation per unit heat difference
    beta: float = 1e-3            # eq 6: radians per unit pyrolysis difference (1/m)
    # The sheet's flexural rigidity B, N m (bending ∝ thickness^3; docs/materials.md): the
    # lattice's layers bend with it instead of their own, much stiffer, rigidity. 0: the lattice's.
    flexural_rigidity: float = 0.0
    # Largest stretch or squash of the intact sheet's mid-surface (docs/dynamics.md §3.4): Table
    # 1's springs let a soft, heavy fabric stretch under its own weight. 0: no limit.
    strain_limit: float = 0.0

    @property
    def areal_density(self) -> float:
        """kg/m^2."""
        return self.mass * 0.1

    @property
    def v0(self) -> float:
        """Spread speed V0 in m/s."""
        return self.V0 * 1e-3

    def with_(self, **changes) -> "Material":
        """A copy with some fields changed (validated by Simulation)."""
        return replace(self, **changes)

    def as_dict(self) -> dict:
        return asdict(self)


_TABLE1 = (
    # name, mass, V0, Cp, C_damping, K_structure, K_shear, K_flex, figure, then ours:
    # burn_duration, flexural_rigidity (N m, docs/materials.md "Bending"), ash_strength,
    # strain_limit (docs/materials.md "Stretch")
    ("paper", 0.45, 3.5, 1.0, 1.7, 0.05, 0.05, 0.05, 8, 4.0, 0.0, 0.1, 0.0),
    ("cloth", 1.45, 4.0, 0.8, 2.5, 0.3, 0.01, 0.04, 9, 6.0, 5e-6, 0.03, 0.03),
    ("hard_paper", 10.45, 3.5, 1.0, 1.7, 0.5, 0.01, 0.001, 10, 6.0, 0.5, 0.1, 0.0),
    ("silk", 6.45, 4.0, 0.8, 2.5, 0.01, 0.01, 0.01, 11, 3.0, 3e-6, 0.03, 0.03),
    ("curtain", 1.45, 4.0, 0.8, 2.5, 0.3, 0.01, 0.04, 12, 6.0, 2e-5, 0.03, 0.03),
)

MATERIALS = MappingProxyType({
    row[0]: Material(*row[:9], burn_duration=row[9], flexural_rigidity=row[10], ash_strength=row[11],
                     strain_limit=row[12])
    for row in _TABLE1
})
"""The five presets of Table 1, by name."""

# Heat ignites (Simulation(heat_ignites=True); docs/heat.md, "Heat ignites"): the temperature
# above a 20 °C room at which an unburnt cell of a preset catches fire, K. Paper's autoignition
# is usually quoted as 218-246 °C (233 °C, "Fahrenheit 451", is the middle: 213 K above the
# room); cotton (cloth, curtain) about 255 °C; silk chars more than it flames, about 300 °C
# is assumed. Not in the paper (it ignites by igniters only); approximate values.
IGNITION_TEMPERATURE = MappingProxyType({
    "paper": 213.0, "hard_paper": 213.0, "cloth": 235.0, "curtain": 235.0, "silk": 280.0,
})
"""K above ambient at which each preset's unburnt cells catch fire from heat."""

MATERIAL_FIELDS = tuple(f.name for f in fields(Material) if f.name != "name")


def resolve_material(material) -> Material:
    """A Material from a preset name or a Material; bad input names the argument."""
    if isinstance(material, Material):
        _check_fields(material)
        return material
    if isinstance(material, str):
        if material not in MATERIALS:
            raise ValueError(f"material: unknown preset {material!r}; choose one of {sorted(MATERIALS)}")
        return MATERIALS[material]
    raise TypeError(f"material must be a preset name or a thinburn.Material, got {type(material).__name__}")


def _check_fields(m: Material) -> None:
    """Every numeric field of a Material is a finite real number (bounds are checked where the
    field is used); a TypeError/ValueError names the field as ``material.FIELD``."""
    import math
    import numbers
    if not isinstance(m.name, str):
        raise TypeError(f"material.name must be a str, got {type(m.name).__name__}")
    if isinstance(m.figure, bool) or not isinstance(m.figure, numbers.Integral):
        raise TypeError(f"material.figure must be an int, got {type(m.figure).__name__}")
    for f in fields(Material):
        if f.name in ("name", "figure"):
            continue
        value = getattr(m, f.name)
        if isinstance(value, bool) or not isinstance(value, numbers.Real) or type(value).__name__ == "bool_":
            raise TypeError(f"material.{f.name} must be a real number, got {type(value).__name__}")
        if not math.isfinite(float(value)):
            raise ValueError(f"material.{f.name} must be finite, got {value}")
