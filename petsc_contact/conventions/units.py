"""Units: lengths (``100um``, ``2.5 nm``, ``1e-3`` with no unit), pressures (``1GPa``) and
forces (``1mN``), and conversions between them.

A run computes in one length unit, the unit of its lengths (``--length``, or the file's
physical size).  Heights given in another unit (``--height-unit``, or the file's) are
converted into it; a run with no unit anywhere is unit-free, as before: lengths and
heights then share whatever unit the user has in mind.  Pressures and stiffness per area
are in the unit of the modulus: ``--modulus 1GPa`` makes GPa the run's pressure unit, and
``--pressures 2MPa`` is converted into it; a force's unit is the pressure unit times the
length unit squared (``GPa*um^2``, which is a millinewton), so ``--forces 1mN`` needs both.
Bare numbers keep their meaning: pressures in the unit of the modulus, forces in that times
the length unit squared.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

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
    parts = text.split(",")
    if not 1 <= len(parts) <= 2 or not all(p.strip() for p in parts):  # 150um, is no square
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


PASCALS = {
    "Pa": 1.0,
    "kPa": 1e3,
    "MPa": 1e6,
    "GPa": 1e9,
    "TPa": 1e12,
    "bar": 1e5,
    "psi": 6894.757293168361,
}
"""Pascals per unit, for every pressure unit accepted."""
NEWTONS = {"N": 1.0, "kN": 1e3, "mN": 1e-3, "uN": 1e-6, "µN": 1e-6, "μN": 1e-6, "nN": 1e-9}
"""Newtons per unit, for every force unit accepted."""


@dataclass(frozen=True)
class Quantity:
    """A number and the unit it was given in (``None``: a bare number)."""

    value: float
    unit: str | None


def parse_quantity(given: float | str, units: dict[str, float], what: str) -> Quantity:
    """``2.5``, ``"2.5"``, ``"2MPa"`` or ``"2 MPa"`` as a :class:`Quantity` whose unit is one
    of ``units``; ``ValueError`` naming ``what`` otherwise (the value must be finite)."""
    if isinstance(given, (int, float)):
        return Quantity(float(given), None)
    m = _QUANTITY.match(str(given))
    unit = m.group(2) if m else None
    if m is None or (unit is not None and unit not in units):
        known = ", ".join(k for k in units if k.isascii())
        raise ValueError(
            f"{what}: expected a number with an optional unit ({known}), got '{given}'"
        )
    try:
        value = float(m.group(1))
    except ValueError:
        raise ValueError(f"{what}: expected a number, got '{given}'") from None
    return Quantity(value, unit)


def _converted(
    given: float | str, units: dict[str, float], unit: str | None, what: str, needs: str
) -> float:
    """``given`` in ``unit`` (a bare number is taken to be in it already)."""
    q = parse_quantity(given, units, what)
    if q.unit is None:
        return q.value
    if unit is None:
        raise ValueError(f"{what} in {q.unit} need {needs}")
    return q.value * units[q.unit] / units[unit]


def pressure_value(given: float | str, unit: str | None, what: str) -> float:
    """A pressure in the run's pressure ``unit`` (the modulus's: ``None`` when it has none)."""
    return _converted(given, PASCALS, unit, what, "a modulus with a unit, e.g. --modulus 1GPa")


def force_value(
    given: float | str, pressure_unit: str | None, length_unit: str | None, what: str
) -> float:
    """A force in the run's force unit: the pressure unit times the length unit squared."""
    q = parse_quantity(given, NEWTONS, what)
    if q.unit is None:
        return q.value
    if pressure_unit is None or length_unit is None:
        raise ValueError(
            f"{what} in {q.unit} need a modulus and lengths with units (--modulus 1GPa, "
            "--length 100um, or a file with its size)"
        )
    return q.value * NEWTONS[q.unit] / (PASCALS[pressure_unit] * METRES[length_unit] ** 2)


def length_value(given: float | str, unit: str | None, what: str) -> float:
    """A length (an approach: ``"10nm"`` or a bare number) in the run's length ``unit``."""
    return _converted(given, METRES, unit, what, "lengths with a unit, e.g. --length 100um")


def force_unit(pressure_unit: str | None, length_unit: str | None) -> str:
    """The run's force unit in words (``GPa*um^2``), or ``""`` when it has no units."""
    if pressure_unit is None or length_unit is None:
        return ""
    return f"{pressure_unit}*{length_unit}^2"


PREFIXES = (("E", 1e18), ("P", 1e15), ("T", 1e12), ("G", 1e9), ("M", 1e6), ("k", 1e3),
            ("", 1.0), ("m", 1e-3), ("u", 1e-6), ("n", 1e-9), ("p", 1e-12))  # fmt: skip
"""The SI prefixes values are shown with (``u`` for micro, as the package spells ``um``)."""
_COMPOUND = re.compile(r"^([^*/^\s]+)([*/])([^*/^\s]+)(\^2)?$")


def _prefix(magnitude: float) -> tuple[float, str]:
    """The factor and SI prefix that put ``magnitude`` (in an SI unit) at 1 to 999; none for
    zero or a non-finite one."""
    if magnitude == 0 or not np.isfinite(magnitude):
        return 1.0, ""
    for name, size in PREFIXES:
        if magnitude >= size:
            return size, name
    return PREFIXES[-1][1], PREFIXES[-1][0]


def si_unit(unit: str) -> tuple[float, str]:
    """One ``unit`` in SI units and their name: ``um`` is ``(1e-6, "m")``, ``GPa`` is
    ``(1e9, "Pa")``, ``mN`` is ``(1e-3, "N")``, and a run's compound units (:func:`force_unit`)
    ``GPa*um^2`` (a force) is ``(1e-3, "N")``, ``GPa*um`` ``(1e3, "N/m")`` and ``GPa/um``
    ``(1e15, "Pa/m")``.  ``ValueError`` for another unit."""
    for table, name in ((METRES, "m"), (PASCALS, "Pa"), (NEWTONS, "N")):
        if unit in table:
            return table[unit], name
    m = _COMPOUND.match(unit)
    if m is None or m[1] not in PASCALS or m[3] not in METRES or (m[4] and m[2] == "/"):
        raise ValueError(f"no SI form known for the unit '{unit}'")
    pressure, length = PASCALS[m[1]], METRES[m[3]] ** (2 if m[4] else 1)
    if m[2] == "/":
        return pressure / length, "Pa/m"
    return pressure * length, "N" if m[4] else "N/m"


def format_quantity(value: float, unit: str | None, digits: int = 4) -> str:
    """``value``, given in ``unit``, as people read it: in the form :func:`display_scale`
    gives, with 1 to 999 in front, to ``digits`` significant digits.

    ``format_quantity(1e-3, "GPa")`` is ``"1 MPa"``, ``format_quantity(5.623e-4, "m")``
    ``"562.3 um"``, ``format_quantity(2.5, "GPa*um^2")`` ``"2.5 mN"`` and
    ``format_quantity(0.01986, "GPa/um")`` ``"19.86 MPa/um"`` (a stiffness per area, in any
    length unit, is per micrometre).  A unit-free value (``unit``
    ``None`` or ``""``) is the number alone (``"0.0001"``); zero and non-finite values keep
    the unprefixed unit.  ``ValueError`` for a unit :func:`si_unit` does not know.
    """
    if not unit:
        return f"{value:.{digits}g}"
    factor, shown = display_scale(abs(value), unit)
    if abs(float(f"{value * factor:.{digits}g}")) >= 1e3:  # 999.96 rounds up: next prefix
        factor, shown = display_scale(1e3 / factor, unit)
    return f"{value * factor:.{digits}g} {shown}"


def display_scale(magnitude: float, unit: str | None) -> tuple[float, str]:
    """The factor and unit that show values of size ``magnitude`` (in ``unit``) with 1 to 999
    in front, in the field's customary form: a length, pressure or force in its SI unit with
    a prefix (``2e-5 m`` as ``20 um``: factor 1e6), a stiffness per area (``GPa/um``,
    ``GPa/m``) as a pressure with a prefix per micrometre (``0.01986 GPa/um`` and
    ``1.986e4 GPa/m`` as ``19.86 MPa/um``), the run's other compound units (:func:`si_unit`)
    in SI with a prefix.
    Unit-free values (``None`` or ``""``) stay as they are: ``(1.0, "")``; zero and
    non-finite magnitudes take no prefix."""
    if not unit:
        return 1.0, ""
    per = _COMPOUND.match(unit)
    if per and per[2] == "/" and per[1] in PASCALS and per[3] in METRES and not per[4]:
        pascals_per_um = PASCALS[per[1]] * METRES["um"] / METRES[per[3]]
        size, prefix = _prefix(magnitude * pascals_per_um)
        return pascals_per_um / size, f"{prefix}Pa/um"
    scale, name = si_unit(unit)
    size, prefix = _prefix(magnitude * scale)
    return scale / size, prefix + name


def display_unit(extent: float, unit: str | None) -> tuple[float, str]:
    """Deprecated (until 0.3.0): :func:`display_scale` of a length ``extent`` in ``unit``."""
    warnings.warn(
        "conventions.units.display_unit is deprecated: use display_scale",
        DeprecationWarning,
        stacklevel=2,
    )
    return display_scale(extent, unit) if unit else (1.0, unit or "")


def display_force(newtons: np.ndarray) -> tuple[np.ndarray, str]:
    """Deprecated (until 0.3.0): forces in newtons scaled by :func:`display_scale`."""
    warnings.warn(
        "conventions.units.display_force is deprecated: use display_scale",
        DeprecationWarning,
        stacklevel=2,
    )
    factor, name = display_scale(float(np.max(np.abs(newtons), initial=0.0)), "N")
    return newtons * factor, name


def typical_magnitude(values: Any) -> float:
    """The size a figure's unit is chosen for (:func:`display_scale`): the median magnitude of
    the finite values that are not zero (0 when there is none), so that one value at full
    contact or one spike does not push the rest to a thousandth of the unit."""
    v = np.abs(np.asarray(values, dtype=float))
    v = v[np.isfinite(v) & (v > 0)]
    return float(np.median(v)) if v.size else 0.0


def typeset(unit: str) -> str:
    """A unit as a figure writes it: micro as ``µ`` (``um`` is ``µm``, ``MPa/um`` ``MPa/µm``)."""
    return re.sub(r"(?<![A-Za-z])u(?=[mN]\b)", "µ", unit)
