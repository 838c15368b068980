"""The core's parameter tables (cpp/param_table.hpp): one per parameter struct, every field
once with its kind, default, bounds and a line of doc. The core validates, parses keywords and
reports parameters by them; the key lists of the Python layer (``simulation.DYNAMICS_KEYS``,
``bending.KEYS``, the particles' ranges, the wedge's names) are derived from them here.

    from thinburn.params import FIELDS
    FIELDS["dynamics"]["plasticity"]   # Field(name='plasticity', kind='real', default=1.0, low=0.0, ...)
"""
from __future__ import annotations

from typing import NamedTuple

from . import _core

#: The tables: the Simulation's scalars and the shell's three parameter groups.
GROUPS = ("simulation", "dynamics", "particles", "bending")


class Field(NamedTuple):
    """One field of a table: kind is real, int, seed, flag, vector or choice; low / high are
    None where there is no bound; choices are a choice's names."""

    name: str
    kind: str
    default: object
    low: float | None
    high: float | None
    low_open: bool
    high_open: bool
    choices: list
    doc: str

    def bounds(self) -> dict:
        """The bounds as ``_validate.real`` takes them (low, high, low_open, high_open)."""
        return dict(low=self.low, high=self.high, low_open=self.low_open, high_open=self.high_open)


#: group -> {name: Field}, in the table's order.
FIELDS = {g: {f["name"]: Field(**f) for f in _core.param_fields(g)} for g in GROUPS}


def names(group: str, exclude: tuple = ()) -> tuple:
    """A table's field names in order, less ``exclude`` (each of which must be one of them, so
    a renamed field cannot stay in a key list by mistake)."""
    table = FIELDS[group]
    unknown = sorted(set(exclude) - set(table))
    if unknown:
        raise KeyError(f"{group} has no fields {unknown}")
    return tuple(k for k in table if k not in exclude)
