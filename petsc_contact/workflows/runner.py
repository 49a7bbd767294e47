"""Running a :class:`~petsc_contact.workflows.description.Run`: the scene, its loads, the
durable results file, resume and pause, with progress reported step by step.

This is what ``petsc-contact periodic``, ``punch`` and ``demo`` do, and what an ensemble and
the paper's study do for each of their runs::

    from petsc_contact import Run, run_contact

    result = run_contact(Run(heights="scan.di", detrend="slope", modulus=1e9,
                             pressures=[1e5, 1e6], output="scan.h5"))
    result.to_dataframe()             # one row per step, the scalars of the output file

:func:`prepare` makes the scene and the plan (the grid, the solver, the loads; every input
checked before the output is touched); :meth:`Prepared.execute` solves the steps, commits
each to the output (:mod:`petsc_contact.io.store`), and stops cleanly after ``stop_after``
minutes.  Both geometries have one driver shape: a generator of steps from a list of loads.
"""

from __future__ import annotations

import os
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..backend import _petsc
from ..backend.solve import Monitor
from ..conventions.grid import world
from ..geometries.step import FIELD_NAMES, Step
from ..io.schema import FILE_RECORD
from ..io.store import (
    Finished,
    OutputLock,
    PartsCheck,
    StepStore,
    StorageError,
    check_interrupt,
    check_nothing_lost,
    check_parts,
    check_writable,
    read_resume,
)
from ..physics.continuation import Held
from .description import Run
from .periodic_sweep import Progress
from .scene import Scene, prepare_scene

Start = tuple[np.ndarray, Held | None] | None
"""Where a resumed run's sweep goes on from: its last state (a local slab) and what the sweep
held beside it (``None`` in a state file of an earlier version); ``None``: first touch."""


PAUSED, COMPLETE = "paused", "complete"


class RunInterrupted(KeyboardInterrupt):
    """A run stopped by ``Ctrl-C`` or ``SIGTERM``; its message says what was kept."""


@dataclass
class RunResult:
    """What a run gave: its status, every step's scalars, this call's steps, its record.

    Attributes
    ----------
    status
        ``complete``, or ``paused`` (``stop_after`` passed: ``resume=True`` goes on).
    table
        One dict of scalars per finished step (a resumed run's earlier steps included), the
        same as the output file's datasets of one entry per step.
    steps
        The steps solved by this call (fields when ``fields``; the last keeps ``state``).
    record
        The run record (the output file's root attributes).
    output
        The results file, when the run wrote one.
    """

    status: str
    table: list[dict[str, Any]]
    steps: list[Step]
    record: dict[str, Any]
    output: str | None = None

    @property
    def converged(self) -> bool:
        """Whether every step converged (and was verified)."""
        return all(bool(s["converged"]) for s in self.table)

    @property
    def accurate(self) -> bool:
        """Whether every step met the package's accuracy (docs/solvers.md), whatever the
        options; a step of an earlier version's file, which does not record it, counts."""
        return all(bool(s.get("accurate", True)) for s in self.table)

    def to_dataframe(self) -> Any:
        """The step table as a pandas ``DataFrame`` (one row per step, from 1)."""
        from ..io.results import table_frame

        return table_frame(self.table)


@dataclass
class Prepared:
    """A run ready to solve: its scene, its loads and its solver (see :func:`prepare`)."""

    run: Run
    scene: Scene
    loads: list[float]
    record: dict[str, Any]
    intro: str  # one line on the problem: full contact pressure, or K_flat
    solve: Callable[[list[float], Start, Monitor | None], Iterator[Step]]
    close: Callable[[], None] = lambda: None
    resumable: Finished = field(default_factory=lambda: Finished(0))

    def execute(
        self, progress: Progress | None = None, monitor: Monitor | None = None
    ) -> RunResult:
        """Solve every load not yet finished; commit each step to the output (if any).

        A signal (see :func:`~petsc_contact.io.store.interrupt`) is checked after each
        step's commit and before and after the output is assembled: wherever it came, the
        run ends with :class:`RunInterrupted` saying what was kept."""
        store, start = self._store()
        table = self.resumable.rows()
        steps: list[Step] = []
        try:
            try:
                status = self._solve(store, start, table, steps, progress, monitor)
            finally:
                self.close()
            if store is not None and status == COMPLETE:
                check_interrupt()
                store.finish()
                check_interrupt()
        except StorageError as exc:
            kept = store.abandon(exc.strerror or str(exc)) if store is not None else str(exc)
            raise StorageError(exc.errno, kept) from None
        except KeyboardInterrupt:
            kept = store.abandon("interrupted") if store is not None else "interrupted"
            raise RunInterrupted(kept) from None
        except Exception:
            if store is not None and store.steps == 0:  # nothing finished: nothing is left
                store.discard()
            raise
        return RunResult(status, table, steps, self.record, self.run.output)

    def _solve(
        self,
        store: StepStore | None,
        start: Start,
        table: list[dict[str, Any]],
        steps: list[Step],
        progress: Progress | None,
        monitor: Monitor | None,
    ) -> str:
        """Solve the loads not yet finished, committing each step to ``store`` and adding it
        to ``table`` and ``steps``; the status (paused once ``stop_after`` has passed)."""
        run, grid = self.run, self.scene.grid
        began = time.perf_counter()
        limit = np.inf if run.stop_after is None else 60.0 * run.stop_after
        todo = self.loads[len(table) :]
        for i, step in enumerate(self.solve(todo, start, monitor) if todo else (), len(table)):
            if store is not None:
                fields: dict[str, Any] | None = (
                    {n: step.field(n) for n in FIELD_NAMES} if run.fields else None
                )
                store.append(step.scalars, fields, state=step.state, held=step.held)
            check_interrupt()
            if steps:
                steps[-1].state = steps[-1].held = None  # a long sweep keeps one field
            steps.append(step)
            table.append(step.scalars)
            if progress is not None:
                progress(i, len(self.loads), step.scalars)
            elapsed = grid.max(time.perf_counter() - began)  # every rank stops together
            if i + 1 < len(self.loads) and elapsed > limit:
                return PAUSED
        return COMPLETE

    def _store(self) -> tuple[StepStore | None, Start]:
        run, grid = self.run, self.scene.grid
        if run.output is None:
            return None, None
        fields = FIELD_NAMES if run.fields else ()
        finished = self.resumable
        heights, filled = _maps(run, self.scene)
        if not finished.steps:
            store = StepStore.create(run.output, grid, self.record, heights, fields, filled)
            return store, None
        start: Start = None
        if finished.state is not None:
            held = finished.held
            if held is not None:
                held = Held(held.scalars, tuple(grid.scatter(f) for f in held.fields))
            start = (grid.scatter(finished.state), held)
        store = StepStore.resume(run.output, grid, finished, self.record, fields, heights, filled)
        return store, start


def _maps(run: Run, scene: Scene) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The maps ``run`` stores: its heights (unless ``scalars_only``) and a measured map's
    mask of filled heights."""
    return (None if run.scalars_only else scene.heights), scene.filled


def prepare(run: Run, command_line: str | None = None) -> Prepared:
    """The scene and plan of ``run``, every input checked; the output is not touched yet.

    ``command_line`` is recorded (default: the arguments that describe ``run``)."""
    from ..backend.solve import DEFAULT_TYPE, requested_type
    from ..physics.surface import rms_of

    petsc = _petsc.init()
    scene = prepare_scene(run, default_solver=requested_type(petsc) == DEFAULT_TYPE)

    grid, fft, heights = scene.grid, scene.fft, scene.heights
    realised = {
        "rms_height": rms_of(grid, fft, heights),
        "rms_slope": rms_of(grid, fft, heights, slope=True),
        **scene.realised,
    }
    plan = _punch_plan(run, scene) if run.geometry == "punch" else _periodic_plan(run, scene)
    loads, resolved, intro, solve, close, backend = plan
    line = command_line or " ".join(["petsc-contact", *run.arguments()])
    record = run_record(run, line, petsc, realised, {**scene.resolved, **scene.record, **resolved})
    record["fft_backend"] = backend
    finished = Finished(0)
    try:
        if run.resume and run.output is not None:
            finished = _resumable(run.output, run, scene, record["parameters"])
        elif run.output is not None and not run.overwrite:
            check_nothing_lost(run.output)
    except BaseException:
        close()
        raise
    return Prepared(run, scene, loads, record, intro, solve, close, finished)


def _resumable(output: str, run: Run, scene: Scene, parameters: dict[str, Any]) -> Finished:
    """What an interrupted ``run`` left in ``output``'s files to go on from, less what its
    part files cannot give (computed again, with a warning saying what); rank 0 reads the
    parts."""
    finished = read_resume(output, parameters)
    comm = scene.grid.comm
    maps = any(m is not None for m in _maps(run, scene))
    mine = check_parts(output, finished, maps, run.fields) if comm.rank == 0 else None
    check: PartsCheck = comm.bcast(mine, root=0)
    if check.problem:
        warnings.warn(check.problem, UserWarning, stacklevel=3)
    return finished.redo(check, output)


def run_contact(
    run: Run,
    progress: Progress | None = None,
    monitor: Monitor | None = None,
    command_line: str | None = None,
) -> RunResult:
    """Run ``run`` (see :class:`~petsc_contact.workflows.description.Run`): its output locked
    for the whole run, its PETSc options for this call only.

    Parameters
    ----------
    run
        The run.
    progress
        Called as ``progress(index, total, scalars)`` after each step, ``index`` from 0
        (:data:`Progress`; the table and ``--step`` number that step ``index + 1``).
    monitor
        Called as ``monitor(iteration, f, gnorm)`` at every TAO iteration; ``True`` stops.
    command_line
        What to record as the command line (default: the arguments that describe ``run``).
    """
    with locked(run.output), _petsc.scoped_options(list(run.options), run.options_prefix):
        return prepare(run, command_line).execute(progress, monitor)


@contextmanager
def locked(path: str | None) -> Iterator[None]:
    """Hold the exclusive right to write ``path`` (rank 0 takes it; every rank raises the same
    error when another run holds it: :class:`~petsc_contact.io.store.OutputBusy`)."""
    comm = world()
    lock = OutputLock(path) if path is not None and comm.rank == 0 else None
    failure: Exception | None = None
    if lock is not None:
        try:
            check_writable(lock.output)
            lock.acquire()
        except (ValueError, OSError) as exc:
            failure = exc
    if comm.size > 1:
        failure = comm.bcast(failure, root=0)
    if failure is not None:
        raise failure
    try:
        yield
    finally:
        if lock is not None:
            lock.release()


Plan = tuple[
    list[float],
    dict[str, Any],
    str,
    Callable[[list[float], Start, Monitor | None], Iterator[Step]],
    Callable[[], None],
    str,
]


def swept(
    spec: Sequence[float | str],
    low: float,
    high: float,
    value: Callable[[float | str], float] = float,
) -> list[float]:
    """The loads of a sweep ``(N,)`` or ``(N, MIN, MAX)``: ``N`` log-spaced, by default from
    ``low`` to ``high``; ``value`` turns a bound given with a unit (``"1kPa"``) into the run's
    units."""
    from ..conventions.validation import log_range

    if len(spec) == 3:
        n, lo, hi = float(spec[0]), value(spec[1]), value(spec[2])
        log_range("the sweep", n, (lo, hi))
    else:
        n, lo, hi = float(spec[0]), low, high
    return [float(v) for v in np.geomspace(lo, hi, int(n))]


def _periodic_plan(run: Run, scene: Scene) -> Plan:
    from ..conventions.units import pressure_value
    from ..geometries.periodic import PeriodicProblem
    from .periodic_sweep import check_pressures, problem_solver, sweep

    problem = PeriodicProblem(scene.grid, scene.fft, scene.heights, run.modulus_value)
    problem.filled = scene.filled
    p_full = problem.full_contact_pressure()
    resolved: dict[str, Any] = {}
    if run.sweep is not None:
        unit = run.pressure_unit
        pressures = swept(
            run.sweep, 1e-4 * p_full, 0.9 * p_full, lambda v: pressure_value(v, unit, "--sweep")
        )
        resolved = {"pressures": pressures, "sweep": None}  # the file records the loads
    elif run.pressures is not None:
        unit = run.pressure_unit
        pressures = check_pressures([pressure_value(p, unit, "--pressures") for p in run.pressures])
        if any(isinstance(p, str) for p in run.pressures):
            resolved = {"pressures_resolved": pressures}  # in the run's pressure unit
    else:
        raise ValueError("give the nominal pressures (--pressures) or a --sweep")
    if run.approaches is not None or run.forces is not None:
        raise ValueError("a periodic run takes --pressures or --sweep, not approaches or forces")
    for p0 in pressures:
        problem.check_pressure(p0)  # before the output is touched
    solver = problem_solver(problem)

    def solve(loads: list[float], start: Start, monitor: Monitor | None) -> Any:
        state, held = start or (None, None)
        return sweep(problem, loads, run.fields, monitor, run.stiffness, state, solver, held)

    intro = f", full contact at p0 = {p_full:.4g}"
    return pressures, resolved, intro, solve, solver.close, type(scene.fft).__name__


def _disk(n: int) -> np.ndarray:
    """The disk inscribed in an ``n x n`` footprint (pixel centres within radius n/2)."""
    x = np.arange(n) + 0.5 - n / 2
    return x[:, None] ** 2 + x[None, :] ** 2 < (n / 2) ** 2


def _punch_plan(run: Run, scene: Scene) -> Plan:
    from ..conventions.units import force_value, length_value, pressure_value
    from ..conventions.validation import non_negative, positive
    from ..geometries.punch import PHARR_BETA, PunchProblem
    from .punch_sweep import PunchSolver, punch_sweep

    grid = scene.grid
    if run.footprint == "disk" and not grid.square:
        raise ValueError("--footprint disk needs a square grid")
    mask = grid.scatter(_disk(grid.shape[0])) > 0 if run.footprint == "disk" else None
    beta = 1.0 if run.footprint == "disk" else PHARR_BETA
    problem = PunchProblem(grid, scene.heights, run.modulus_value, mask, run.flat_stiffness, beta)
    given = [run.forces, run.approaches, run.pressures, run.sweep]
    if sum(v is not None for v in given) != 1:
        raise ValueError("give one of --approaches, --forces, --pressures and --sweep")
    by_force = run.forces is not None or run.pressures is not None
    resolved: dict[str, Any] = {}
    length_unit = scene.resolved["length_unit"] or None
    if run.sweep is not None:
        low, high = 0.01 * problem.scale_length, 3 * problem.scale_length
        loads = swept(run.sweep, low, high, lambda v: length_value(v, length_unit, "--sweep"))
        resolved = {"approaches": loads, "sweep": None}  # the file records the loads
    elif run.forces is not None:
        units = run.pressure_unit, length_unit
        loads = [positive("--forces", force_value(f, *units, "--forces")) for f in run.forces]
        resolved = {"forces_resolved": loads}  # in the run's force unit
    elif run.pressures is not None:  # nominal pressure over the punch's face
        face = float(
            grid.sum(np.count_nonzero(mask) if mask is not None else grid.size / grid.comm.size)[0]
        )
        area = face * grid.pixel_area
        unit = run.pressure_unit
        loads = [
            positive("--pressures", pressure_value(p, unit, "--pressures")) * area
            for p in run.pressures
        ]
        resolved = {"forces_resolved": loads}  # the forces of those pressures
    else:
        loads = [
            non_negative("--approaches", length_value(v, length_unit, "--approaches"))
            for v in run.approaches  # type: ignore[union-attr]
        ]
    solver = PunchSolver(problem)

    def solve(todo: list[float], start: Start, monitor: Monitor | None) -> Any:
        state, held = start or (None, None)
        return punch_sweep(solver, todo, by_force, run.fields, monitor, run.stiffness, state, held)

    intro = (
        f", K_flat = {solver.k_flat:.6g} ({run.flat_stiffness}; analytic "
        f"{solver.k_flat_analytic:.6g})"
    )
    backend = type(problem.compliance.fft).__name__
    return loads, resolved, intro, solve, solver.close, backend


def run_record(
    run: Run, command_line: str, petsc: Any, realised: dict[str, float], resolved: dict[str, Any]
) -> dict[str, Any]:
    """What reproduces the run: its description (defaults resolved), versions, PETSc options."""
    from ..conventions.units import force_unit
    from ..io.provenance import file_digest, petsc_options, versions

    params = run.parameters() | {k: v for k, v in resolved.items() if k not in FILE_RECORD}
    lengths, unit = resolved["length"], resolved["length_unit"]
    attrs: dict[str, Any] = {
        "geometry": run.geometry,
        "command_line": command_line,
        "parameters": params,
        "petsc_options": petsc_options(petsc),
        "versions": versions(petsc),
        "mpi_size": petsc.COMM_WORLD.getSize(),
        "length": lengths[0],
        "lengths": np.array(lengths),
        "length_unit": unit,
        "modulus": run.modulus_value,
        "pressure_unit": run.pressure_unit or "",
        "force_unit": force_unit(run.pressure_unit, unit or None),
        "units": (
            f"lengths and heights in {unit}"
            if unit
            else "lengths and heights in the unit of --length (none given)"
        )
        + (
            f", pressures and stiffness per area in {run.pressure_unit}"
            if run.pressure_unit
            else ", pressures and stiffness per area in the unit of --modulus"
        ),
        **realised,
    }
    if run.measured:
        if run.heights_file is not None:
            attrs["heights_file"] = os.path.abspath(run.heights_file)
            attrs["heights_sha256"] = file_digest(run.heights_file)
        attrs.update({k: resolved[k] for k in FILE_RECORD})
    else:
        attrs.update(
            seed=run.seed,
            hurst=run.hurst,
            rolloff_ratio=run.rolloff_ratio,
            cutoff_ratio=params["cutoff_ratio"],
            grid=np.array(run.grid) if isinstance(run.grid, (tuple, list)) else run.grid,
        )
    return attrs
