"""Length units: ``100um``, ``2.5 nm``, ``1e-3`` (no unit), and conversions between them.

A run computes in one length unit, the unit of its lengths (``--length``, or the file's
physical size).  Heights given in another unit (``--height-unit``, or the file's) are
converted into it; a run with no unit anywhere is unit-free, as before: lengths and
heights then share whatever unit the user has in mind.  Pressures and stiffness per area
are in the unit of the modulus.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

METRES = {
    "km": 1e3,
    "m": 1.0,
    "cm": 1e-2,
    "mm": 1e-3,
    "um": 1e-6,
    "µm": 1e-6,
    "μm": 1e-6,
    "micron": 1e-6,
    "nm": 1e-9,
    "A": 1e-10,
    "Å": 1e-10,
    "pm": 1e-12,
}
"""Metres per unit, for every unit name accepted."""

_CANONICAL = {"µm": "um", "μm": "um", "micron": "um", "Å": "A"}
_QUANTITY = re.compile(r"^\s*([-+0-9.eE]+)\s*([^\s0-9.+-][^\s]*)?\s*$")


def unit_name(unit: str) -> str:
    """The package's spelling of a unit (``um`` for ``µm``), ``ValueError`` for an unknown one."""
    name = unit.strip()
    if name not in METRES:
        raise ValueError(f"unknown length unit '{unit}' (known: {', '.join(sorted(METRES))})")
    return _CANONICAL.get(name, name)


def factor(source: str | None, target: str | None) -> float:
    """The number a length in ``source`` is multiplied by to be in ``target`` (1 when either is
    unit-free: then both are the same unknown unit)."""
    if source is None or target is None:
        return 1.0
    return METRES[unit_name(source)] / METRES[unit_name(target)]


@dataclass(frozen=True)
class Lengths:
    """One or two lengths (``Lx`` or ``Lx, Ly``) and their unit (``None``: unit-free)."""

    values: tuple[float, ...]
    unit: str | None

    @property
    def pair(self) -> float | tuple[float, float]:
        """A single length as a float, two as a tuple (what
        :class:`~petsc_contact.conventions.grid.Grid` and the Python API take)."""
        return self.values[0] if len(self.values) == 1 else (self.values[0], self.values[1])

    def describe(self) -> str:
        suffix = f" {self.unit}" if self.unit else ""
        return " x ".join(f"{v:g}" for v in self.values) + suffix


def parse_lengths(text: str) -> Lengths:
    """``"100um"``, ``"1.5"``, ``"100um,50um"`` or ``"100,50 um"``: one or two positive lengths
    with at most one unit.  ``ValueError`` with a one-line reason otherwise."""
    parts = [p for p in text.split(",") if p.strip()]
    if not 1 <= len(parts) <= 2:
        raise ValueError(f"expected L or LX,LY (with an optional unit), got '{text}'")
    values, units = [], set()
    for part in parts:
        m = _QUANTITY.match(part)
        if m is None:
            raise ValueError(f"expected a length such as 100um or 1.5, got '{part.strip()}'")
        try:
            value = float(m.group(1))
        except ValueError:
            raise ValueError(f"expected a length such as 100um or 1.5, got '{part}'") from None
        if not value > 0 or value == float("inf"):
            raise ValueError(f"a length must be positive and finite, got '{part.strip()}'")
        values.append(value)
        if m.group(2):
            units.add(unit_name(m.group(2)))
    if len(units) > 1:
        raise ValueError(f"give both lengths in one unit, got '{text}'")
    return Lengths(tuple(values), units.pop() if units else None)
