"""``periodic``, ``punch`` and ``demo``: parse, describe the run, run it, print its table."""

from __future__ import annotations

import argparse
import re
from collections.abc import Sequence
from typing import Any

from ..conventions.units import format_quantity
from ..io.names import csv_path
from .common import EXIT_INTERRUPTED, EXIT_NOT_CONVERGED, EXIT_PAUSED, describe, say

LOAD_COLUMNS = {
    "periodic": (("p0", "nominal_pressure"), ("mean_gap", "mean_gap")),
    "punch": (
        ("approach", "approach"),
        ("force", "force"),
        ("K_tot", "total_stiffness"),
        ("p0", "nominal_pressure"),
    ),
}
"""The load columns of each geometry's table: (header, dataset), shown with an SI prefix."""
STEP_COLUMNS = (
    ("area", "area_fraction", "{:>10.5g}"),  # 6.1035e-05 and 0.99996 alike
    ("its", "iterations", "{:>6d}"),
    ("time_s", "solve_time", "{:>8.3f}"),
    ("kkt", "kkt_residual", "{:>9.1e}"),
)
"""The columns after the load columns: (header, dataset, format)."""
TARGET_COLUMN = ("target", "target_mean_gap")  # after the load columns of --mean-gaps
PLASTIC_COLUMN = ("plastic", "plastic_area_fraction", "{:>10.5g}")  # after area, --hardness
WIDTH = 12  # of a load column: "346.7 kPa/um"
Columns = tuple[tuple[str, str, str], ...]  # (header, dataset, its unit in the run)
StepColumns = tuple[tuple[str, str, str], ...]  # (header, dataset, format)


def _unit(key: str, record: dict[str, Any]) -> str:
    """The unit of the dataset ``key`` in the run's output (``GPa``, ``um``, ``GPa*um^2``,
    ``s``); ``""`` for a number, a count, and a unit the run does not have."""
    from ..io.schema import ENTRIES, in_unit

    entry = in_unit(ENTRIES[key], record["length_unit"], record["pressure_unit"])
    symbolic = re.search(r"\b(length|pressure)\b", entry.units)
    return "" if entry.units in ("1", "count") or symbolic else entry.units


def _columns(description: Any, record: dict[str, Any]) -> tuple[Columns, StepColumns]:
    """The columns of the table of the run ``description``: its geometry's load columns (with
    ``--mean-gaps``, the target mean gap after them; with ``--stiffness``, the stiffness per
    area ``K``; with ``--adhesion``, no held-set stiffness), with their units in the run
    ``record``; then :data:`STEP_COLUMNS` (with ``--hardness``, the plastic area fraction
    after the area)."""
    held = "total_stiffness" if description.adhesion is not None else ""  # none measured
    titled = (
        *(c for c in LOAD_COLUMNS[description.geometry] if c[1] != held),
        *((TARGET_COLUMN,) if description.mean_gaps is not None else ()),
        *((("K", "stiffness"),) if description.stiffness else ()),
    )
    area, *rest = STEP_COLUMNS
    plastic = (PLASTIC_COLUMN,) if description.hardness is not None else ()
    load = tuple((title, key, _unit(key, record)) for title, key in titled)
    return load, (area, *plastic, *rest)


def _legend(columns: Columns, steps: StepColumns, record: dict[str, Any]) -> str:
    """The line above the table: each column's dataset in the output, with its unit there."""
    parts = []
    for title, key, _ in (*columns, *steps):
        unit = _unit(key, record)
        parts.append(("" if title == key else f"{title} = ") + key + (f" [{unit}]" if unit else ""))
    return "# the output's datasets [in its units]: " + ", ".join(parts)


def _header(columns: Columns, steps: StepColumns) -> str:
    load = " ".join(f"{title:>{WIDTH}}" for title, _, _ in columns)
    step = " ".join(f"{title:>{len(fmt.format(0))}}" for title, _, fmt in steps)
    return f"{'step':>7} {load} {step}  tao_reason"


def _flag(s: dict[str, Any]) -> str:
    """The marker of a step that did not converge, or whose measured accuracy is beyond the
    package's (:meth:`~petsc_contact.solver.report.Accuracy.assess`), or at full contact
    (:func:`~petsc_contact.geometries.step.mark_full_contact`), or whose contact is not
    resolved (``contact_resolved``); '' for a good step."""
    if not s["converged"]:
        return "   <-- NOT CONVERGED: " + s["verification"]
    if not s.get("accurate", True):  # a step resumed from an older file has no verdict
        return "   <-- NOT ACCURATE: " + s["verification"]
    if s.get("full_contact", False):
        return "   <-- FULL CONTACT: interfacial stiffness NaN"
    if not s.get("contact_resolved", True):
        return "   <-- UNRESOLVED: contact on too few pixels"
    return ""


def _row(i: int, total: int, s: dict[str, Any], columns: Columns, steps: StepColumns) -> str:
    load = " ".join(f"{format_quantity(s[key], unit):>{WIDTH}}" for _, key, unit in columns)
    step = " ".join(fmt.format(s[key]) for _, key, fmt in steps)
    return f"{f'{i + 1}/{total}':>7} {load} {step}  {s['tao_reason']}{_flag(s)}"


def run(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    """Run ``periodic``, ``demo`` or ``punch``; write the HDF5 file (and plot)."""
    from ..backend import _petsc

    _petsc.init(petsc_args)
    return execute(describe(args), args, argv)


def execute(
    description: Any, args: argparse.Namespace, argv: Sequence[str], lock: bool = True
) -> int:
    """Run ``description`` (a :class:`~petsc_contact.workflows.description.Run`) through the
    door every run goes through (:func:`~petsc_contact.workflows.runner.opened`), printing as
    ``args`` asks (``--quiet``, ``--plot``): the intro once it is prepared, a row per step
    (its ``progress``); the exit status.  Its output is locked for the run unless ``lock`` is
    False (the caller holds the lock)."""
    from ..io.store import partial_path
    from ..workflows.runner import PAUSED, RunInterrupted, opened

    with opened(description, " ".join(["petsc-contact", *argv]), lock) as prepared:
        root = prepared.scene.grid.comm.rank == 0
        show = root and not args.quiet
        columns, steps = _columns(description, prepared.record)
        if show:
            _introduce(args.command, description, prepared)
            print(_header(columns, steps), flush=True)

        def progress(i: int, total: int, scalars: dict[str, Any]) -> None:
            if show:
                print(_row(i, total, scalars, columns, steps), flush=True)

        try:
            result = prepared.execute(progress)
            if prepared.resumable.whole:  # nothing solved: the file's steps
                for i, scalars in enumerate(result.table):
                    progress(i, len(result.table), scalars)
        except RunInterrupted as exc:
            say(str(exc), "note")
            return EXIT_INTERRUPTED
        if result.status == PAUSED:
            limit = f"{description.stop_after:.3g} minutes"
            say(
                f"paused: the --stop-after limit of {limit} has passed; {len(result.table)} "
                f"finished step(s) kept in {partial_path(description.output)} (--resume "
                "continues)",
                "note",
            )
            return EXIT_PAUSED
    return _conclude(args, description, result, root, wrote=not prepared.resumable.whole)


def _introduce(command: str, description: Any, prepared: Any) -> None:
    """The lines before the table: the map read, the problem, a resume, the columns."""
    from ..io.store import partial_path

    if prepared.scene.reading:
        print(f"# {prepared.scene.reading}", flush=True)
    print(f"# {command} {_problem(description, prepared)}", flush=True)
    finished = prepared.resumable
    if finished.whole:
        print(
            f"# {description.output} is complete, with this run's {finished.steps} steps: "
            "nothing to compute (--overwrite computes them again)",
            flush=True,
        )
    elif finished.steps:
        total = len(prepared.loads)
        where = partial_path(description.output)
        print(f"# resuming {where} after {finished.steps} of {total} steps", flush=True)
    print(_legend(*_columns(description, prepared.record), prepared.record), flush=True)


def _problem(description: Any, prepared: Any) -> str:
    """The grid, its sides, the modulus and the surface's rms height and slope, in words."""
    grid, record, unit = prepared.scene.grid, prepared.record, prepared.record["length_unit"]
    (nx, ny), (lx, ly) = grid.shape, grid.lengths
    inside = record.get("rms_slope_inside", float("nan"))
    slope = f"h'_rms = {record['rms_slope']:.4g}"
    what = "face" if "parent_rms_slope" in record else "map"
    if abs(inside - record["rms_slope"]) > 0.2 * record["rms_slope"]:  # NaN: never
        slope += f" (the {what} taken as periodic; {inside:.4g} inside it)"
    modulus = format_quantity(description.modulus_value, description.pressure_unit)
    return (
        f"{nx}x{ny} on {format_quantity(lx, unit)} x {format_quantity(ly, unit)}, "
        f"E* = {modulus}, h_rms = {format_quantity(record['rms_height'], unit)}, "
        f"{slope}{prepared.intro}"
    )


ADHESIVE_SUMMARY = ("pull_off_pressure", "hysteresis_energy")
"""The datasets of an adhesive run's last step printed after its table."""


def _adhesive_summary(last: dict[str, Any], record: dict[str, Any]) -> str:
    """The line after an adhesive run's table: its last step's :data:`ADHESIVE_SUMMARY`
    (as it stands at the end: NaN where the cycle gave none), each in its unit."""
    parts = []
    for key in ADHESIVE_SUMMARY:
        if key in last:
            unit = _unit(key, record)
            parts.append(f"{key} = {last[key]:.6g}" + (f" [{unit}]" if unit else ""))
    return "# " + ", ".join(parts)


def _conclude(
    args: argparse.Namespace, description: Any, result: Any, root: bool, wrote: bool = True
) -> int:
    """Plot, say what was written (``wrote``: the output, unless it was complete already),
    and return the exit status (:data:`EXIT_NOT_CONVERGED` where steps did not converge or
    are not accurate: the run's warning has named them)."""
    table = result.table
    plot = getattr(args, "plot", None)
    if plot and root:
        from ..io.plot import plot_punch, plot_sweep

        record = result.record
        units = {"length": record["length_unit"], "pressure": record["pressure_unit"],
                 "force": record["force_unit"]}  # fmt: skip
        draw = plot_punch if description.geometry == "punch" else plot_sweep
        draw(plot, table, modulus=description.modulus_value, h_rms=record["rms_height"],
             units=units)  # fmt: skip
    if root and not args.quiet and description.adhesion is not None and table:
        print(_adhesive_summary(table[-1], result.record), flush=True)
    written = [description.output, csv_path(description.output)] if wrote else []
    written += [plot] if plot else []
    if root and not args.quiet and written:
        *others, last = written
        print(f"# wrote {', '.join(others)}{' and ' if others else ''}{last}")
    flagged = [s for s in table if not s["converged"] or not s.get("accurate", True)]
    return EXIT_NOT_CONVERGED if flagged else 0  # the run's Unconverged warning said which
