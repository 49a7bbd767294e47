"""``plot`` and ``experiment``: maps of stored fields and load plots drawn again from a
results file, and a measured squeeze test."""

from __future__ import annotations

import argparse
import json
import os
from typing import Any

import numpy as np

from .common import InputError

FIGURE_FILES = ("theory", "periodic ensemble")  # no maps: ``plot`` draws their figure
SWEEP_COLUMNS = ("nominal_pressure", "area_fraction", "mean_gap", "converged")
PUNCH_COLUMNS = ("approach", "force", "nominal_pressure", "interfacial_stiffness", "converged")


def run_plot(args: argparse.Namespace) -> int:
    """``petsc-contact plot``: one field of one step as a map or, with ``--sweep`` (a theory
    or ensemble file always), the file's load plot drawn again as ``OUT_redrawn.png``."""
    import h5py

    stem = args.file.removesuffix(".h5")
    with h5py.File(args.file, "r") as f:
        if args.sweep or f.attrs.get("geometry") in FIGURE_FILES:
            out = args.output or f"{stem}_redrawn.png"
            _check_plot_output(out, args.file)
            _draw_file(f, args.file, out)
            print(f"# wrote {out}")
            return 0
        values, title, label, step = _field(f, args)
        lx, ly = (float(v) for v in f.attrs.get("lengths", (1.0, 1.0)))
        length_unit = str(f.attrs.get("length_unit", ""))
    from ..io.plot import plot_map

    out = args.output or f"{stem}_{args.field}" + (f"_step{step}.png" if step else ".png")
    _check_plot_output(out, args.file)
    plot_map(
        out, values, (lx, ly), length_unit, args.field, title, label, args.scale, args.vmin,
        args.vmax,
    )  # fmt: skip
    print(f"# wrote {out}")
    return 0


def _draw_file(f: Any, path: str, out: str) -> None:
    """The figure the command that wrote ``path`` (open as ``f``) draws with ``--plot``, from
    the file, in the units it records."""
    from ..io.plot import plot_punch, plot_sweep

    geometry = str(f.attrs.get("geometry", ""))
    if geometry == "theory":
        _plot_theory_file(f, out)
    elif geometry == "periodic ensemble":
        _plot_ensemble_file(f, path, out)
    elif geometry == "punch":
        plot_punch(out, _steps(f, path, PUNCH_COLUMNS), _units(f))
    elif geometry == "periodic":
        rms_height = float(f.attrs.get("rms_height", 0.0))
        plot_sweep(out, _steps(f, path, SWEEP_COLUMNS), float(f.attrs["modulus"]), rms_height)
    else:
        raise InputError(f"'{path}' holds no load sweep to draw (geometry '{geometry}')")


def _steps(f: Any, path: str, columns: tuple[str, ...]) -> list[dict[str, Any]]:
    """The run's table, one dictionary per step: ``columns`` and, if computed, ``stiffness``."""
    missing = [name for name in columns if name not in f]
    if missing:
        raise InputError(f"'{path}' holds no load sweep to draw (no {', '.join(missing)})")
    table = {name: f[name][...] for name in (*columns, "stiffness") if name in f}
    return [dict(zip(table, row, strict=True)) for row in zip(*table.values(), strict=True)]


def _units(f: Any) -> dict[str, str]:
    """The units a results file records (``length``, ``pressure``, ``force``)."""
    return {name: str(f.attrs.get(f"{name}_unit", "")) for name in ("length", "pressure", "force")}


def _plot_ensemble_file(f: Any, path: str, out: str) -> None:
    """An ensemble's statistics, the stiffness scaled by its seeds' mean rms height (their
    files, which the ensemble names, give it and the modulus)."""
    import h5py

    from ..io.plot import plot_ensemble
    from ..workflows.seeds import mean_rms_height

    seeds = json.loads(f.attrs["seed_files"])
    absent = [name for name in seeds if not os.path.exists(name)]
    if absent:
        raise InputError(f"'{path}': its seeds' files are needed, and {absent[0]} is missing")
    with h5py.File(seeds[0], "r") as seed:
        modulus = float(seed.attrs["modulus"])  # the same for every seed
    summary = {name: f[name][...] for name in f}
    plot_ensemble(out, summary, modulus, mean_rms_height(seeds))


def _check_plot_output(out: str, source: str) -> None:
    """The PNG ``out`` (given, or named after the file) can be written and is not ``source``."""
    from ..io.lock import check_writable
    from ..io.paths import check_output

    check_output(out, [("the file to plot", source)])
    check_writable(out)


def _field(f: Any, args: argparse.Namespace) -> tuple[np.ndarray, str, str, int]:
    """The map ``--field`` of step ``--step`` (counted from 1 as the table counts; negative
    from the end), its title, its colour bar's label and the step (0 for the heights)."""
    from ..conventions.units import METRES, display_unit, format_quantity
    from ..io.schema import ENTRIES, in_unit

    name = args.field
    if name not in f:
        raise InputError(_missing_map(f, args.file, name))
    data = f[name]
    units = in_unit(ENTRIES[name], str(f.attrs.get("length_unit", "")),
                    str(f.attrs.get("pressure_unit", "")))  # fmt: skip
    symbolic = {"length": "unit of --length", "pressure": "unit of --modulus"}
    label = f"{name} ({symbolic.get(units.units, units.units)})"
    scale = 1.0
    if ENTRIES[name].units == "length" and units.units in METRES:  # with an SI prefix: nm
        scale, shown = display_unit(float(np.max(np.abs(data[...]))), units.units)
        label = f"{name} ({shown})"
    if data.ndim == 2:
        titles = {"filled": "points whose heights were undefined and filled"}
        return data[...] * scale, titles.get(name, f"{name} of the map as solved"), label, 0
    steps = data.shape[0]
    if args.step == 0 or not -steps <= args.step <= steps:
        raise InputError(
            f"--step {args.step} is out of range: the steps count from 1 to {steps}, as the "
            "run's table does (-1 is the last)"
        )
    step = args.step if args.step > 0 else steps + 1 + args.step
    modulus = float(f.attrs.get("modulus", 1.0))
    p0 = float(f["nominal_pressure"][step - 1]) if "nominal_pressure" in f else np.nan
    unit = str(f.attrs.get("pressure_unit", ""))
    load = f"p0 = {p0 / modulus:.3g} E*" + (f" = {format_quantity(p0, unit)}" if unit else "")
    return data[step - 1] * scale, f"{name}, step {step} of {steps}, {load}", label, step


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
        fit_range=tuple(json.loads(f.attrs["fit_range"])),
    )
    units = {"length": str(f.attrs.get("length_unit", ""))}
    plot_theory(out, result, float(f.attrs.get("modulus", 1.0)), units=units)


def run_experiment(args: argparse.Namespace) -> int:
    """``petsc-contact experiment``: Eq. C3 on a measured ``p(s)`` table."""
    from ..workflows.experiment import squeeze_test

    found = squeeze_test(args.table, args.modulus, args.thickness, args.output, args.plot)
    if not args.quiet:
        print(f"{'p':>12} {'s':>12} {'K*':>12} {'K':>12}")
        rows = (found.pressure, found.displacement, found.measured_stiffness, found.stiffness)
        for row in zip(*rows, strict=True):
            print(" ".join(f"{v:>12.5g}" for v in row))
    return 0
