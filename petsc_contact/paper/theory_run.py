"""What the ``theory`` command reads besides a map: a line scan (its heights and length), its
record, and the periodic runs drawn beside the prediction (``--compare``)."""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..io.results import trusted

COMPARED = ("nominal_pressure", "mean_gap", "stiffness", "area_fraction")  # a run's, drawn


def line_scan(heights: str | None, channel: Any = None) -> Any:
    """The line scan the file ``heights`` holds (read and checked), or ``None`` for a map
    (or no file).

    Raises
    ------
    ValueError
        When the scan has undefined heights.
    """
    from ..io.topography import NotAMap, read_profile, read_topography

    if heights is None:
        return None
    try:
        read_topography(heights, channel)
        return None
    except NotAMap as exc:
        if "line scan" not in str(exc):
            raise
    profile = read_profile(heights, channel)
    undefined = int(np.count_nonzero(~np.isfinite(profile.heights)))
    if undefined:
        raise ValueError(f"the line scan has {undefined} undefined heights")
    return profile


def profile_length(length: str | None, profile: Any) -> float:
    """The scan's length: the file's, else ``length`` (``--length``; its unit must agree)."""
    from ..conventions.units import factor, parse_lengths

    if length is None:
        if profile.length is None:
            raise ValueError("the line scan has no length: give --length")
        return float(profile.length)
    given = parse_lengths(length)
    if given.unit and profile.unit:
        return given.values[0] * factor(given.unit, profile.unit)
    return given.values[0]


def profile_record(run: Any, command_line: str, profile: Any) -> dict[str, Any]:
    """What reproduces a prediction for a line scan (the file attributes of ``theory``)."""
    from ..io.provenance import file_digest, versions

    unit = profile.unit or ""
    return {
        "command_line": command_line,
        "parameters": run.parameters(),
        "versions": versions(),
        "heights_file": os.path.abspath(run.heights),
        "heights_sha256": file_digest(run.heights),
        "heights_reader": profile.reader + profile.note,
        "length": profile.length or 0.0,
        "length_unit": unit,
        "modulus": run.modulus_value,
        "pressure_unit": run.pressure_unit or "",
        "units": f"lengths and heights in {unit or 'the unit of --length'}",
    }


def check_compared(paths: Sequence[str] | None, plot: str | None) -> None:
    """``ValueError`` unless the runs to compare (``--compare``) come with a plot to draw
    them in (``--plot``) and are periodic runs' files (a punch's mean gap is over its
    footprint, not a cell's) on the half-space, whose contact the theory predicts (not on a
    layer)."""
    if not paths:
        return
    if not plot:
        raise ValueError("--compare draws runs beside the theory's plot: give --plot PNG")
    for path in paths:
        geometry = _geometry(path)
        if geometry != "periodic":
            what = f"geometry '{geometry}'" if geometry else "no geometry: not a run's file"
            raise ValueError(f"--compare takes periodic runs; '{path}' is not one ({what})")
        if _parameters(path).get("thickness") is not None:
            raise ValueError(
                f"--compare: '{path}' is a run on a layer (--thickness); the theory is the "
                "half-space's"
            )


def compared_runs(
    paths: Sequence[str] | None, units: dict[str, str]
) -> list[tuple[str, dict[str, np.ndarray]]]:
    """Each run to draw beside the theory: its file's name and its trusted steps' loads,
    mean gaps, stiffnesses and contact areas, converted into the theory's ``units`` (``length``,
    ``pressure``; ``""`` where it has none).

    Raises
    ------
    ValueError
        When a run and the theory do not both have a unit (or both none) for lengths and for
        pressures: a bare number cannot be converted.
    """
    return [(os.path.basename(path), _in_units(path, units)) for path in paths or ()]


def _in_units(path: str, units: dict[str, str]) -> dict[str, np.ndarray]:
    """The run ``path``'s table (:func:`_run_table`) in the theory's ``units``."""
    from ..conventions.units import METRES, PASCALS

    table, given = _run_table(path)
    factors = {}
    for kind, table_of_units in (("length", METRES), ("pressure", PASCALS)):
        theirs, ours = given[kind], units.get(kind, "")
        if bool(theirs) != bool(ours):
            raise ValueError(
                f"--compare: '{path}' has {_unit_words(kind, theirs)} and the theory has "
                f"{_unit_words(kind, ours)}: a bare number cannot be converted; give both "
                "units (--modulus 1GPa, --length 100um), or neither"
            )
        factors[kind] = table_of_units[theirs] / table_of_units[ours] if ours else 1.0
    scales = {"nominal_pressure": factors["pressure"], "mean_gap": factors["length"],
              "stiffness": factors["pressure"] / factors["length"],
              "area_fraction": 1.0}  # fmt: skip
    return {name: values * scales[name] for name, values in table.items()}


def _unit_words(kind: str, unit: str) -> str:
    """``pressures in GPa``, or ``unit-free pressures``."""
    return f"{kind}s in {unit}" if unit else f"unit-free {kind}s"


def _parameters(path: str) -> dict[str, Any]:
    """The ``parameters`` record of a run's file (read after :func:`_geometry`)."""
    import h5py

    with h5py.File(path, "r") as f:
        return dict(json.loads(f.attrs.get("parameters", "{}")))


def _geometry(path: str) -> str:
    """The ``geometry`` attribute of a results file ('' when it has none)."""
    import h5py

    try:
        with h5py.File(path, "r") as f:
            return str(f.attrs.get("geometry", ""))
    except OSError:
        raise ValueError(f"--compare: '{path}' is not an HDF5 results file") from None


def _run_table(path: str) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """A simulation's loads, mean gaps, stiffnesses and contact areas (:data:`COMPARED`), to
    draw beside the theory, and the units its file records (``length``, ``pressure``; ``""``
    for none)."""
    import h5py

    try:
        with h5py.File(path, "r") as f:
            table = {k: f[k][...] for k in COMPARED if k in f}
            if "converged" in f:
                table = {k: v[trusted(f)] for k, v in table.items()}
            units = {k: str(f.attrs.get(f"{k}_unit", "")) for k in ("length", "pressure")}
    except OSError as exc:
        raise OSError(f"--compare: cannot read '{path}' ({exc})") from None
    if "mean_gap" not in table:
        raise ValueError(f"--compare: '{path}' is not a periodic run's file (no mean_gap)")
    return table, units
