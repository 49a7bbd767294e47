"""Figures drawn again from a results file (``petsc-contact plot``): one stored map of one
step, or the load plot of the command that wrote the file, in the units the file records.

Steps count from 1 as the run's table counts (negative from the end); the heights and the
filled points are maps of the run as a whole.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..io.lock import check_writable
from ..io.paths import check_output

FIGURE_FILES = ("theory", "periodic ensemble", "experiment")  # no maps: their figure is their plot
LOAD_PLOTS = {
    "periodic": ("nominal_pressure", "area_fraction", "mean_gap", "converged"),
    "punch": ("approach", "force", "nominal_pressure", "interfacial_stiffness", "converged"),
}
"""The datasets each geometry's load plot draws (with ``stiffness`` where the file has it)."""


@dataclass
class FieldMap:
    """One stored map as :func:`~petsc_contact.io.plot.plot_map` draws it."""

    name: str  # the dataset: pressure, gap, contact, heights, filled
    values: np.ndarray  # in the unit of ``label``
    title: str
    label: str  # the colour bar's: the field and its unit
    step: int  # counted from 1; 0 for a map of the run as a whole (heights, filled)
    lengths: tuple[float, float]
    length_unit: str


def results_file(path: str) -> Any:
    """``path`` opened for reading as a results file of the package's commands; ``ValueError``
    in one line for a file that is no HDF5 file, or a comparison (no maps, no load sweep);
    h5py's ``OSError`` for a file it cannot open (missing, unreadable)."""
    import h5py

    if os.path.isfile(path) and not h5py.is_hdf5(path):
        raise ValueError(
            f"'{path}' is not an HDF5 file: plot draws the files the commands write (OUT.h5)"
        )
    f = h5py.File(path, "r")
    if "solvers" in f.attrs:
        f.close()
        png = path.removesuffix(".h5") + ".png"
        raise ValueError(
            f"'{path}' is a solver comparison, with no maps and no load sweep: compare drew "
            f"its figure as {png}"
        )
    return f


def draws_load_plot(path: str, sweep: bool) -> bool:
    """Whether ``plot`` draws the file's load plot (``--sweep``, or a file with no maps)."""
    with results_file(path) as f:
        return sweep or f.attrs.get("geometry") in FIGURE_FILES


def redraw(path: str, out: str | None = None) -> str:
    """Draw again the load plot of the command that wrote ``path``, as ``out`` (default
    ``PATH_redrawn.png``); returns the file written.

    Raises
    ------
    ValueError
        When the file holds no load sweep, or ``out`` cannot be written or is ``path``.
    """
    out = out or f"{path.removesuffix('.h5')}_redrawn.png"
    _check_figure(out, path)
    with results_file(path) as f:
        _draw_file(f, path, out)
    return out


def field_map(path: str, name: str, step: int) -> FieldMap:
    """The map ``name`` of step ``step`` (from 1; negative from the end) of the file
    ``path``, in the unit its file records (lengths with an SI prefix).

    Raises
    ------
    ValueError
        When the file has no such map (and why: no ``--fields``, an unfinished run) or the
        step is out of range, or the file is none of the commands' results.
    """
    with results_file(path) as f:
        if name not in f:
            raise ValueError(_missing_map(f, path, name))
        values, label = _scaled(f, name)
        lengths = tuple(float(v) for v in f.attrs.get("lengths", (1.0, 1.0)))
        length_unit = str(f.attrs.get("length_unit", ""))
        if values.ndim == 2:
            titles = {"filled": "points whose heights were undefined and filled"}
            title = titles.get(name, f"{name} of the map as solved")
            return FieldMap(name, values, title, label, 0, (lengths[0], lengths[1]), length_unit)
        index = _step(step, values.shape[0])
        title = f"{name}, step {index} of {values.shape[0]}, {_load(f, index)}"
        return FieldMap(
            name, values[index - 1], title, label, index, (lengths[0], lengths[1]), length_unit
        )


def map_file(path: str, name: str, step: int) -> str:
    """The PNG ``plot`` writes a map to by default: ``PATH_NAME[_stepK].png``."""
    return f"{path.removesuffix('.h5')}_{name}" + (f"_step{step}.png" if step else ".png")


def draw_map(
    found: FieldMap, out: str, source: str, scale: str = "auto", vmin: Any = None, vmax: Any = None
) -> str:
    """Draw ``found`` (read from ``source``) as ``out``; returns ``out``."""
    from ..io.plot import plot_map

    _check_figure(out, source)
    plot_map(
        out, found.values, found.lengths, found.length_unit, found.name,
        found.title, found.label, scale, vmin, vmax,
    )  # fmt: skip
    return out


def _scaled(f: Any, name: str) -> tuple[np.ndarray, str]:
    """Dataset ``name`` of ``f`` (all its steps) and its colour bar's label, in the file's
    units with the prefix that suits its typical value (a gap in nm, a pressure in MPa)."""
    from ..conventions.units import display_scale, typeset, typical_magnitude
    from ..io.schema import ENTRIES, in_unit

    data = f[name][...]
    units = in_unit(ENTRIES[name], str(f.attrs.get("length_unit", "")),
                    str(f.attrs.get("pressure_unit", "")))  # fmt: skip
    symbolic = {"length": "unit of --length", "pressure": "unit of --modulus"}
    if units.units != ENTRIES[name].units and units.units not in symbolic:  # with a prefix
        scale, shown = display_scale(typical_magnitude(data), units.units)
        return data * scale, f"{name} ({typeset(shown)})"
    return data, f"{name} ({symbolic.get(units.units, units.units)})"


def _step(step: int, steps: int) -> int:
    """Step ``step`` (from 1, negative from the end) of ``steps``, counted from 1."""
    if step == 0 or not -steps <= step <= steps:
        raise ValueError(
            f"--step {step} is out of range: the steps count from 1 to {steps}, as the "
            "run's table does (-1 is the last)"
        )
    return step if step > 0 else steps + 1 + step


def _load(f: Any, step: int) -> str:
    """The load of step ``step`` (from 1), in ``E*`` and in the unit the run was given in."""
    from ..conventions.units import format_quantity

    modulus = float(f.attrs.get("modulus", 1.0))
    p0 = float(f["nominal_pressure"][step - 1]) if "nominal_pressure" in f else np.nan
    unit = str(f.attrs.get("pressure_unit", ""))
    return f"p0 = {p0 / modulus:.3g} E*" + (f" = {format_quantity(p0, unit)}" if unit else "")


def _missing_map(f: Any, path: str, name: str) -> str:
    """Why the file ``path`` (open as ``f``) has no map ``name``: an unfinished run keeps its
    maps apart until it ends, and a run without ``--fields`` has none of every step."""
    from ..io.names import PARTIAL, is_partial, parts_path

    per_step = name in ("pressure", "gap", "contact")
    had_fields = json.loads(f.attrs.get("parameters", "{}")).get("fields", False)
    if is_partial(path) and (had_fields or not per_step):
        parts = parts_path(path.removesuffix(PARTIAL))
        return (
            f"'{path}' is an unfinished run's file: its maps are in {parts} until the run "
            "ends (--resume finishes it)"
        )
    advice = " (run with --fields); --sweep draws its load plot" if per_step else ""
    return f"'{path}' has no dataset '{name}'{advice}"


def _check_figure(out: str, source: str) -> None:
    """The PNG ``out`` can be written and is not ``source``."""
    check_output(out, [("the file to plot", source)])
    check_writable(out)


def _draw_file(f: Any, path: str, out: str) -> None:
    """The figure the command that wrote ``path`` (open as ``f``) draws with ``--plot``."""
    from ..io.plot import plot_punch, plot_sweep

    geometry = str(f.attrs.get("geometry", ""))
    if geometry == "theory":
        _plot_theory_file(f, out)
    elif geometry == "experiment":
        from ..io.plot import plot_experiment

        plot_experiment(out, *(f[k][...] for k in ("pressure", "measured_stiffness", "stiffness")))
    elif geometry == "periodic ensemble":
        _plot_ensemble_file(f, path, out)
    elif geometry in LOAD_PLOTS:
        draw = plot_punch if geometry == "punch" else plot_sweep
        modulus, rms_height = float(f.attrs["modulus"]), float(f.attrs.get("rms_height", 0.0))
        steps = _steps(f, path, LOAD_PLOTS[geometry])
        draw(out, steps, modulus=modulus, h_rms=rms_height, units=_units(f))
    else:
        raise ValueError(f"'{path}' holds no load sweep to draw (geometry '{geometry}')")


def _steps(f: Any, path: str, columns: tuple[str, ...]) -> list[dict[str, Any]]:
    """The run's table, one dictionary per step: ``columns`` and, if computed, ``stiffness``."""
    missing = [name for name in columns if name not in f]
    if missing:
        raise ValueError(f"'{path}' holds no load sweep to draw (no {', '.join(missing)})")
    table = {name: f[name][...] for name in (*columns, "stiffness") if name in f}
    return [dict(zip(table, row, strict=True)) for row in zip(*table.values(), strict=True)]


def _units(f: Any) -> dict[str, str]:
    """The units a results file records (``length``, ``pressure``, ``force``)."""
    return {name: str(f.attrs.get(f"{name}_unit", "")) for name in ("length", "pressure", "force")}


def _plot_ensemble_file(f: Any, path: str, out: str) -> None:
    """An ensemble's statistics, in its seeds' units or, unit-free, each seed's stiffness
    scaled by its own rms height (their files, which the ensemble names, give them and the
    modulus)."""
    import h5py

    from ..io.plot import plot_ensemble
    from ..workflows.seeds import seed_files, seed_scales

    seeds = seed_files(path, f)
    with h5py.File(seeds[0], "r") as seed:
        modulus = float(seed.attrs["modulus"])  # the same for every seed
    summary = {name: f[name][...] for name in f}
    plot_ensemble(out, summary, modulus, *seed_scales(seeds))


def _plot_theory_file(f: Any, out: str) -> None:
    """A theory file's spectrum and prediction, drawn again from the file."""
    from types import SimpleNamespace

    from ..io.plot import plot_theory

    appendix = float(f.attrs["crossover_pressure_appendix"])
    result = SimpleNamespace(
        **{
            k: f[k][...] for k in ("wavevector", "psd", "nominal_pressure", "mean_gap", "stiffness")
        },
        **{k: f.attrs[k] for k in ("hurst_fit", "rms_height", "crossover_pressure")},
        # files before 0.2.0's paper reading: twice the appendix reading (theory.READINGS)
        crossover_pressure_paper=float(f.attrs.get("crossover_pressure_paper", 2 * appendix)),
        # files before Persson's area was computed have none
        area_fraction=f["area_fraction"][...] if "area_fraction" in f else None,
        fit_range=tuple(json.loads(f.attrs["fit_range"])),
    )
    plot_theory(out, result, float(f.attrs.get("modulus", 1.0)), units=_units(f))
