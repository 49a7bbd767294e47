"""``periodic``, ``punch`` and ``demo``: a load sweep with a table, HDF5 output and resume."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..geometries.step import FIELD_NAMES
from ..io.store import StorageError
from .common import (
    EXIT_INTERRUPTED,
    EXIT_NOT_CONVERGED,
    EXIT_PAUSED,
    InputError,
    output_lock,
    run_record,
    say,
    swept,
)
from .scene import prepare_scene

PERIODIC_COLUMNS = (("p0", "nominal_pressure", "{:>11.4e}"), ("mean_gap", "mean_gap", "{:>12.6e}"))


PUNCH_COLUMNS = (
    ("approach", "approach", "{:>11.4e}"),
    ("force", "force", "{:>12.6e}"),
    ("K_tot", "total_stiffness", "{:>10.4e}"),
)


def _header(columns: tuple[tuple[str, str, str], ...]) -> str:
    widths = [len(fmt.format(0.0)) for _, _, fmt in columns]
    head = " ".join(f"{title:>{w}}" for (title, _, _), w in zip(columns, widths, strict=True))
    return f"{'step':>7} {head} {'area':>9} {'its':>6} {'time_s':>8} {'kkt':>9}  tao_reason"


def _row(i: int, total: int, s: dict[str, Any], columns: tuple[tuple[str, str, str], ...]) -> str:
    flag = "" if s["converged"] else "   <-- NOT CONVERGED: " + s["verification"]
    values = " ".join(fmt.format(s[key]) for _, key, fmt in columns)
    return (
        f"{f'{i + 1}/{total}':>7} {values} {s['area_fraction']:>9.5f} {s['iterations']:>6d} "
        f"{s['solve_time']:>8.3f} {s['kkt_residual']:>9.1e}  {s['tao_reason']}{flag}"
    )


def _disk(n: int) -> np.ndarray:
    """The disk inscribed in an ``n x n`` footprint (pixel centres within radius n/2)."""
    x = np.arange(n) + 0.5 - n / 2
    return x[:, None] ** 2 + x[None, :] ** 2 < (n / 2) ** 2


def run(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    """Run ``periodic``, ``demo`` or ``punch``; write the HDF5 file (and plot)."""
    with output_lock(args.output):
        return _locked_run(args, argv, petsc_args)


def _locked_run(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    petsc, grid, fft, heights, resolved = prepare_scene(args, petsc_args)
    from ..physics.surface import rms_of

    realised = {
        "rms_height": rms_of(grid, fft, heights),
        "rms_slope": rms_of(grid, fft, heights, slope=True),
    }
    if args.command == "punch":
        plan = _punch_plan(args, grid, heights)
    else:
        plan = _periodic_plan(args, grid, fft, heights)
    attributes = run_record(args, argv, petsc, realised, {**resolved, **plan.resolved})
    attributes["fft_backend"] = plan.fft_backend
    root = grid.comm.rank == 0
    show = root and not args.quiet
    unit = resolved["length_unit"]
    try:
        store, finished, start = _open_store(args, grid, attributes, heights, len(plan.loads), show)
        table = finished.rows() if root else []
        if show:
            print(
                f"# {args.command} {grid.describe()}{' ' + unit if unit else ''}, "
                f"E* = {args.modulus:g}, "
                f"h_rms = {realised['rms_height']:.4g}, h'_rms = {realised['rms_slope']:.4g}"
                f"{plan.intro}",
                flush=True,
            )
            print(_header(plan.columns), flush=True)
        try:
            if not _run_steps(args, plan, store, finished.steps, start, table, show):
                limit = f"{args.stop_after:.3g} minutes"
                say(store.abandon(f"paused: the --stop-after limit of {limit} has passed"), "note")
                return EXIT_PAUSED
        except KeyboardInterrupt:
            say(store.abandon("interrupted"), "note")
            return EXIT_INTERRUPTED
        except StorageError as exc:
            raise StorageError(exc.errno, store.abandon(exc.strerror or str(exc))) from None
        except Exception:
            if store.steps == 0:  # nothing finished: nothing is left behind
                store.discard()
            raise
        store.finish()
    finally:
        plan.close()
    return _conclude(args, plan, table, realised, root)


def _open_store(
    args: argparse.Namespace,
    grid: Any,
    attributes: dict[str, Any],
    heights: np.ndarray,
    total: int,
    show: bool,
) -> tuple[Any, Any, np.ndarray | None]:
    """The run's store, the steps already finished and the state to start from (``--resume``)."""
    from ..io.store import Finished, StepStore, partial_path, read_resume

    fields = FIELD_NAMES if args.fields else ()
    finished = read_resume(args.output, attributes["parameters"]) if args.resume else Finished(0)
    if not finished.steps:
        stored = None if args.scalars_only else heights
        return StepStore.create(args.output, grid, attributes, stored, fields), finished, None
    if show:
        print(
            f"# resuming {partial_path(args.output)} after {finished.steps} of {total} steps",
            flush=True,
        )
    if finished.state is None and finished.steps < total:  # the same result, maybe more cost
        step = finished.steps + 1
        say(f"{finished.state_problem}: step {step} starts from first touch", "warning")
    start = grid.scatter(finished.state) if finished.state is not None else None
    return StepStore.resume(args.output, grid, finished, attributes, fields), finished, start


def _run_steps(
    args: argparse.Namespace,
    plan: Plan,
    store: Any,
    done: int,
    start: np.ndarray | None,
    table: list[dict[str, Any]],
    show: bool,
) -> bool:
    """Solve the remaining loads; write, tabulate and print each step as it finishes.

    Returns ``False`` when ``--stop-after`` ended the run before the last load.
    """
    total = len(plan.loads)
    if done == total:  # every step was committed before the run was cut: only assemble
        return True
    began = time.perf_counter()
    limit = np.inf if args.stop_after is None else 60.0 * args.stop_after
    for i, step in enumerate(plan.steps(plan.loads[done:], start, args.fields), done):
        fields = {name: step.field(name) for name in FIELD_NAMES} if args.fields else None
        store.append(step.scalars, fields, state=step.state)
        table.append(step.scalars)
        if show:
            print(_row(i, total, step.scalars, plan.columns), flush=True)
        elapsed = store.grid.max(time.perf_counter() - began)  # every rank stops together
        if i + 1 < total and elapsed > limit:
            return False
    return True


def _conclude(
    args: argparse.Namespace,
    plan: Plan,
    table: list[dict[str, Any]],
    realised: dict[str, float],
    root: bool,
) -> int:
    """Plot, report the steps that did not converge, and return the exit status."""
    if args.plot and root:
        from ..io.plot import plot_punch, plot_sweep

        if args.command == "punch":
            plot_punch(args.plot, table)
        else:
            plot_sweep(args.plot, table, args.modulus, realised["rms_height"])
    failed = [s for s in table if not s["converged"]]
    if failed and root:
        load = plan.columns[0]
        print(
            f"petsc-contact: error: {len(failed)} of {len(table)} load steps did NOT converge "
            f"(first: {load[0]} = {failed[0][load[1]]:g}, {failed[0]['verification']}); "
            f"they are flagged converged = False in {args.output}",
            file=sys.stderr,
        )
    if root and not args.quiet:
        print(f"# wrote {args.output}" + (f" and {args.plot}" if args.plot else ""))
    return EXIT_NOT_CONVERGED if failed else 0


@dataclass
class Plan:
    """What a geometry runs: its loads, a step generator, table columns, a closer."""

    loads: list[float]
    steps: Callable[[list[float], np.ndarray | None, bool], Iterator[Any]]
    columns: tuple[tuple[str, str, str], ...]
    intro: str
    close: Callable[[], None] = lambda: None
    fft_backend: str = ""  # class name of the operator's FFT backend (fft module)
    resolved: dict[str, Any] = field(default_factory=dict)  # options the plan resolved


def _periodic_plan(args: argparse.Namespace, grid: Any, fft: Any, heights: np.ndarray) -> Plan:
    from ..geometries.periodic import PeriodicProblem
    from ..workflows.periodic_sweep import sweep

    problem = PeriodicProblem(grid, fft, heights, args.modulus)
    p_full = problem.full_contact_pressure()
    resolved = {}
    pressures = args.pressures
    if args.sweep is not None:
        pressures = swept(args.sweep, 1e-4 * p_full, 0.9 * p_full)
        resolved = {"pressures": pressures, "sweep": None}  # the file records the loads
    for p0 in pressures:
        problem.check_pressure(p0)  # before the output is touched

    def steps(loads: list[float], start: np.ndarray | None, fields: bool) -> Iterator[Any]:
        return sweep(problem, loads, fields, stiffness=args.stiffness, start=start)

    return Plan(
        list(pressures),
        steps,
        PERIODIC_COLUMNS,
        f", full contact at p0 = {p_full:.4g}",
        fft_backend=type(fft).__name__,
        resolved=resolved,
    )


def _punch_plan(args: argparse.Namespace, grid: Any, heights: np.ndarray) -> Plan:
    from ..geometries.punch import PHARR_BETA, PunchProblem
    from ..workflows.punch_sweep import PunchSolver

    if args.footprint == "disk" and not grid.square:
        raise InputError("--footprint disk needs a square grid")
    mask = grid.scatter(_disk(grid.shape[0])) > 0 if args.footprint == "disk" else None
    beta = 1.0 if args.footprint == "disk" else PHARR_BETA
    problem = PunchProblem(grid, heights, args.modulus, mask, args.flat_stiffness, beta)
    solver = PunchSolver(problem)
    by_force = args.forces is not None
    resolved = {}
    approaches = args.approaches
    if args.sweep is not None:
        approaches = swept(args.sweep, 0.01 * problem.scale_length, 3 * problem.scale_length)
        resolved = {"approaches": approaches, "sweep": None}  # the file records the loads

    def steps(loads: list[float], start: np.ndarray | None, fields: bool) -> Iterator[Any]:
        if start is not None:
            solver.restart_from(start)
        for v in loads:
            if by_force:
                yield solver.at_force(v, fields, stiffness=args.stiffness)
            else:
                yield solver.at_approach(v, fields, stiffness=args.stiffness)

    intro = (
        f", K_flat = {solver.k_flat:.6g} ({args.flat_stiffness}; analytic "
        f"{solver.k_flat_analytic:.6g})"
    )
    return Plan(
        list(args.forces if by_force else approaches),
        steps,
        PUNCH_COLUMNS + (("p0", "nominal_pressure", "{:>10.3e}"),),
        intro,
        solver.close,
        type(problem.compliance.fft).__name__,
        resolved,
    )
