"""Running a :class:`~petsc_contact.workflows.description.Run`: the scene, its loads, the
durable results file, resume and pause, with progress reported step by step.

This is what ``petsc-contact periodic``, ``punch`` and ``demo`` do, and what an ensemble and
the paper's study do for each of their runs::

    from petsc_contact import Run, run_contact

    result = run_contact(Run(heights="scan.di", detrend="slope", modulus=1e9,
                             pressures=[1e5, 1e6], output="scan.h5"))
    result.to_dataframe()             # one row per step, the scalars of the output file

:func:`opened` is the one door every run goes through, ``run_contact``, the command line and
the Python API's ``periodic_contact`` and ``punch_contact`` (:func:`contact_steps`) alike: it
takes the signals, the output's lock and the run's PETSc options, and gives the run prepared
(:func:`prepare`: the scene and the driver made, the grid, the solver, the loads; every input
checked before the output is touched).  :meth:`Prepared.execute` solves the steps, commits
each to the output (:mod:`petsc_contact.io.store`), gives the run's warnings and its
progress, and stops cleanly after ``stop_after`` minutes.  Both geometries have one driver
(:class:`~petsc_contact.workflows.drivers.Driver`): a generator of steps from a list of loads.

The run's warnings (:class:`~petsc_contact.conventions.warnings.PetscContactWarning`: a
doubtful map, much of the load on filled heights, a stiffness that did not converge) are
given as Python warnings, and their texts kept in the result (:attr:`RunResult.warnings`) and
the file (its ``warnings`` attribute, a JSON list).
"""

from __future__ import annotations

import json
import os
import time
import warnings
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager, nullcontext
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any

import numpy as np

from ..backend import _petsc
from ..backend.solve import Monitor
from ..conventions.grid import Grid, world
from ..conventions.warnings import (
    FilledLoad,
    PetscContactWarning,
    ResumeWarning,
    option,
    recorded,
    step_warnings,
    user_level,
)
from ..devices.device import get_device
from ..devices.fft import make_fft
from ..geometries.step import FIELD_NAMES, Step, Steps
from ..io.names import csv_path
from ..io.paths import check_input, check_outputs
from ..io.progress import reporting
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
    read_complete,
    read_resume,
    warn_replaced,
)
from ..physics.continuation import Held
from ..solver.backends import SolverBackend
from .choice import scoped_options, solver_backend, uses_petsc
from .description import Run
from .drivers import Driver, Start, driver_for
from .drivers import swept as swept  # where scripts and the CLI import it from
from .periodic_steps import Progress
from .scene import Scene, prepare_scene

PAUSED, COMPLETE = "paused", "complete"
FILLED_LOAD = 0.1  # a share of the load on filled heights above this warns


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
        The steps solved by this call (fields when ``fields``; the last keeps ``state``):
        none when ``resume=True`` found the run's complete output (the file holds its
        fields, read with ``h5py`` or ``xarray``).
    record
        The run record (the output file's root attributes).
    output
        The results file, when the run wrote one.
    warnings
        The texts of the run's warnings, once each (a resumed run's earlier ones included;
        the file's ``warnings`` attribute; those of the map on rank 0 only).
    """

    status: str
    table: list[dict[str, Any]]
    steps: list[Step]
    record: dict[str, Any]
    output: str | None = None
    warnings: list[str] = field(default_factory=list)

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
        """The step table as a pandas ``DataFrame`` (one row per step, from 1), its columns in
        :func:`~petsc_contact.io.results.read_frame`'s order."""
        from ..io.results import table_frame

        return table_frame(self.table, str(self.record.get("geometry", "")))

    def _repr_html_(self) -> str:
        """A notebook's display: the status, the output, the warnings and the step table."""
        from ..io.tables import html_table

        about: dict[str, Any] = {
            "status": self.status,
            "steps": len(self.table),
            "converged": self.converged,
            "accurate": self.accurate,
            "output": self.output or "none (in memory)",
        }
        about |= {f"warning {i}": text for i, text in enumerate(self.warnings, 1)}
        caption = f"{self.record.get('geometry', '')} run".strip()
        return html_table(caption, about) + str(self.to_dataframe().to_html(max_rows=30))


@dataclass
class Prepared:
    """A run ready to solve: its scene, its driver (loads and solver) and its record, with
    what an interrupted run left to go on from and the warnings given so far (see
    :func:`prepare`)."""

    run: Run
    scene: Scene
    driver: Driver
    record: dict[str, Any]
    resumable: Finished = field(default_factory=lambda: Finished(0))
    warnings: list[str] = field(default_factory=list)

    @property
    def loads(self) -> list[float]:
        """Every load of the run, in order."""
        return self.driver.loads

    @property
    def intro(self) -> str:
        """One line on the problem: the full contact pressure, or ``K_flat``."""
        return self.driver.intro

    def execute(
        self, progress: Progress | bool | None = True, monitor: Monitor | None = None
    ) -> RunResult:
        """Solve every load not yet finished; commit each step to the output (if any).

        A signal (see :func:`~petsc_contact.io.store.interrupt`) is checked after each
        step's commit and before and after the output is assembled: wherever it came, the
        run ends with :class:`RunInterrupted` saying what was kept.  The run's warnings are
        given as they come, and kept in the result and the file.  ``progress`` and
        ``monitor`` as :func:`run_contact` takes them."""
        if self.resumable.whole:  # resumed on its complete output: its steps, nothing solved
            self.driver.close()
            table = self.resumable.rows()
            self._say_flagged(self._flagged(table))
            return RunResult(COMPLETE, table, [], self.record, self.run.output, self.warnings)
        shown = self.scene.grid.comm.rank == 0
        total, done = len(self.loads), self.resumable.steps
        with (
            reporting(progress, monitor, total, done, shown) as (report, watch),
            recorded(self.warnings),
        ):
            status, table, steps = self._run(report, watch)
        return RunResult(status, table, steps, self.record, self.run.output, list(self.warnings))

    def _run(
        self, progress: Progress | None, monitor: Monitor | None
    ) -> tuple[str, list[dict[str, Any]], list[Step]]:
        """:meth:`execute`'s work: the status, every step's scalars, this call's steps."""
        store, start = self._store()
        table = self.resumable.rows()
        steps: list[Step] = []
        try:
            try:
                status = self._solve(store, start, table, steps, progress, monitor)
            finally:
                self.driver.close()
            if status == COMPLETE:
                self._check_filled_load(table)
                flagged = self._flagged(table)  # said once the file is whole
                if store is not None:
                    check_interrupt()
                    self._note(store)
                    store.finish()
                    check_interrupt()
                self._say_flagged(flagged)
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
        return status, table, steps

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
        steps_of = self.driver.solve(todo, start, monitor, tuple(table)) if todo else iter(())
        for i, step in enumerate(steps_of, len(table)):
            if store is not None:
                fields: dict[str, Any] | None = (
                    {n: step.field(n) for n in field_names(run)} if run.fields else None
                )
                self._note(store)
                store.append(step.scalars, fields, state=step.state, held=step.held)
            check_interrupt()
            if steps:
                steps[-1].forget_resume()  # a long sweep keeps one field
            steps.append(step)
            table.append(step.scalars)
            if progress is not None:
                progress(i, len(self.loads), step.scalars)
            elapsed = grid.max(time.perf_counter() - began)  # every rank stops together
            if i + 1 < len(self.loads) and elapsed > limit:
                step.take_resume()
                return PAUSED
        if steps:
            steps[-1].take_resume()  # the one kept, on the host
        return COMPLETE

    def _flagged(self, table: list[dict[str, Any]]) -> list[tuple[str, type[PetscContactWarning]]]:
        """The texts of ``table``'s flagged steps with their classes (:class:`Unconverged`,
        :class:`FullContact`: :func:`step_warnings`), added to the run's warnings."""
        flagged = step_warnings(table, self.run.output)
        self.warnings += [text for text, _ in flagged if text not in self.warnings]
        return flagged

    def _say_flagged(self, flagged: list[tuple[str, type[PetscContactWarning]]]) -> None:
        """Warn each of ``flagged`` (rank 0): the steps stay in the results, flagged."""
        if self.scene.grid.comm.rank == 0:
            for text, kind in flagged:
                warnings.warn(text, kind, stacklevel=user_level())

    def _check_filled_load(self, table: list[dict[str, Any]]) -> None:
        """Warn (:class:`FilledLoad`, rank 0) when more than :data:`FILLED_LOAD` of the load
        rests on filled heights at some step: the answer depends on how they were filled."""
        on_filled = [(s.get("filled_load_fraction", 0.0), i) for i, s in enumerate(table, 1)]
        share, step = max(on_filled, default=(0.0, 0))
        if share > FILLED_LOAD and self.scene.grid.comm.rank == 0:
            warnings.warn(
                f"{share:.0%} of the load rests on filled heights at step {step} "
                f"({option('fill_undefined', self.run.fill_undefined)}): the answer depends on "
                "how they were filled (the output's 'filled' map and filled_load_fraction)",
                FilledLoad,
                stacklevel=user_level(),
            )

    def _note(self, store: StepStore) -> None:
        """The run's warnings so far in the record ``store`` writes next."""
        store.attributes["warnings"] = list(self.warnings)

    def _store(self) -> tuple[StepStore | None, Start]:
        run, grid = self.run, self.scene.grid
        if run.output is None:
            return None, None
        fields = field_names(run) if run.fields else ()
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
        earlier = json.loads(str(store.attributes.get("warnings", "")) or "[]")  # rank 0's
        self.warnings[:0] = [w for w in earlier if w not in self.warnings]
        return store, start


def field_names(run: Run) -> tuple[str, ...]:
    """The fields a step of ``run`` keeps with ``--fields``: the gap, pressure and contact,
    and its interaction's (``plastic_displacement`` under a hardness cap)."""
    return (*FIELD_NAMES, *run.interaction.field_names)


def _maps(run: Run, scene: Scene) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The maps ``run`` stores: its heights (unless ``scalars_only``) and a measured map's
    mask of filled heights."""
    return (None if run.scalars_only else scene.heights), scene.filled


Posing = Callable[[Run, SolverBackend], tuple[Scene, Driver]]
"""What poses a run's problem: its scene and driver from the run and its solver backend
(:func:`posed`; the Python API's pose a map as it is, :func:`contact_steps`)."""


def posed(run: Run, backend: SolverBackend) -> tuple[Scene, Driver]:
    """``run``'s scene (:func:`~petsc_contact.workflows.scene.prepare_scene`) and the driver of
    its geometry there (:func:`~petsc_contact.workflows.drivers.driver_for`)."""
    scene = prepare_scene(run, default_solver=backend.runs_default_type)
    return scene, driver_for(run, scene, backend)


def prepare(
    run: Run,
    command_line: str | None = None,
    petsc: ModuleType | None = None,
    posing: Posing | None = None,
) -> Prepared:
    """The scene and driver of ``run``, every input checked; the output is not touched yet.

    Parameters
    ----------
    run
        The run.
    command_line
        What to record as the command line (default: the arguments that describe ``run``).
    petsc
        ``petsc4py.PETSc``, initialised by the caller (default: initialised here); an array
        device's run (``run.device``) uses no PETSc.
    posing
        What poses its problem in place of :func:`posed`: the Python API's, for a run with
        no output, whose result keeps no record (empty).

    Raises
    ------
    DeviceUnavailable
        For ``device="gpu"`` where CuPy or a GPU is missing, before anything is computed.
    ValueError, FileNotFoundError
        For a heights file that cannot be read or an output that cannot be written
        (:func:`check_files`), before anything is read.
    """
    check_files(run)
    if uses_petsc(run.device):
        petsc = petsc or _petsc.init()
    # chosen once: its options refused before the device is looked for
    backend = solver_backend(run.device, run.options, run.options_prefix)
    texts: list[str] = []
    with recorded(texts):  # the map's warnings, what a resume computes again
        scene, driver = (posing or posed)(run, backend)
        try:
            _hint_ranks(scene)
            record: dict[str, Any] = {}
            if posing is None:
                record = _record(run, command_line, petsc, scene, driver) | {"warnings": texts}
            finished = _finished(run, scene, record, len(driver.loads))
        except BaseException:
            driver.close()
            raise
    return Prepared(run, scene, driver, record, finished, texts)


def check_files(run: Run) -> None:
    """``ValueError`` naming the option (``FileNotFoundError`` for a file that does not exist)
    unless ``run``'s heights file is a regular, readable, non-empty file and its output (with
    its ``OUT.csv``) a regular file or a new name that is not the heights file
    (:mod:`~petsc_contact.io.paths`)."""
    if run.heights_file is not None:
        check_input(run.heights_file, "--heights")
    if run.output is not None:
        outputs = [("--output", run.output), ("the table of --output", csv_path(run.output))]
        check_outputs(outputs, [("--heights", run.heights_file)])


_HINTED: set[str] = set()  # the rank hints this process gave: each once (an ensemble's seeds)


def _hint_ranks(scene: Scene) -> None:
    """Say once, on rank 0, that the run has more MPI ranks than help (:class:`IdleRanks`,
    :func:`~petsc_contact.conventions.resources.rank_excess`; collective)."""
    from ..conventions.resources import rank_excess
    from ..conventions.warnings import IdleRanks

    grid = scene.grid
    excess = rank_excess(grid.comm, grid.shape[0])
    if excess and grid.comm.rank == 0 and excess not in _HINTED:
        _HINTED.add(excess)
        (nx, ny), ranks = grid.shape, grid.comm.size
        warnings.warn(
            f"{ranks} MPI ranks are more than this {nx}x{ny} grid can use: {excess}; fewer "
            "ranks give the same result, likely sooner",
            IdleRanks,
            stacklevel=user_level(),
        )


def _record(
    run: Run, command_line: str | None, petsc: ModuleType | None, scene: Scene, driver: Driver
) -> dict[str, Any]:
    """The run record of ``run`` (:func:`run_record`) on its scene, with its driver's loads
    (the surface's rms measured on the host)."""
    from ..physics.surface import rms_of

    grid, fft, heights = scene.grid, scene.fft, scene.heights
    if not fft.device.on_host:
        fft = make_fft(grid, get_device("cpu-array"))
    realised = {
        "rms_height": rms_of(grid, fft, heights),
        "rms_slope": rms_of(grid, fft, heights, slope=True),
        **scene.realised,
    }
    line = command_line or " ".join(["petsc-contact", *run.arguments()])
    resolved = {**scene.resolved, **scene.record, **driver.resolved}
    return run_record(run, line, petsc, realised, resolved) | {"fft_backend": driver.backend}


def _finished(run: Run, scene: Scene, record: dict[str, Any], total: int) -> Finished:
    """What an interrupted ``run`` of ``total`` steps left to go on from (none unless it
    resumes; a :class:`ResumeWarning` when its next step starts from first touch); without
    ``resume`` or ``overwrite``, ``ValueError`` when its output holds finished steps."""
    if run.resume and run.output is not None:
        finished = _resumable(run.output, run, scene, record)
        if not finished.steps:  # a complete output of this run: nothing to compute
            finished = read_complete(run.output, record["parameters"], record.get("heights_sha256"))
        if finished.steps and finished.state is None and finished.steps < total:
            step = finished.steps + 1  # the same result, at more cost
            warnings.warn(
                f"{finished.state_problem}: step {step} starts from first touch",
                ResumeWarning,
                stacklevel=user_level(),
            )
        return finished
    if run.output is not None and not run.overwrite:
        check_nothing_lost(run.output)
        warn_replaced(run.output, stacklevel=user_level())
    return Finished(0)


def _resumable(output: str, run: Run, scene: Scene, record: dict[str, Any]) -> Finished:
    """What an interrupted ``run`` of record ``record`` left in ``output``'s files to go on
    from (none of another run or another map), less what its part files cannot give (computed
    again, with a warning saying what); rank 0 reads the parts; each rank checks the state's
    slabs that hold its rows."""
    finished = read_resume(output, record["parameters"], scene.grid, record.get("heights_sha256"))
    comm = scene.grid.comm
    maps = any(m is not None for m in _maps(run, scene))
    mine = check_parts(output, finished, maps, run.fields) if comm.rank == 0 else None
    check: PartsCheck = comm.bcast(mine, root=0)
    if check.problem:
        warnings.warn(check.problem, ResumeWarning, stacklevel=user_level())
    return finished.redo(check, output)


def run_contact(
    run: Run,
    progress: Progress | bool | None = True,
    monitor: Monitor | None = None,
    command_line: str | None = None,
) -> RunResult:
    """Run ``run`` (see :class:`~petsc_contact.workflows.description.Run`): its output locked
    for the whole run, its PETSc options for this call only.  ``SIGTERM``, as ``Ctrl-C``,
    raises :class:`RunInterrupted` (the finished steps kept for ``resume``) where the caller
    has no handler of its own (:func:`~petsc_contact.io.interrupts.interruptible`).

    Parameters
    ----------
    run
        The run.
    progress
        Called as ``progress(index, total, scalars)`` after each step, ``index`` from 0
        (:data:`Progress`; the table and ``--step`` number that step ``index + 1``), in place
        of the default ``True``: a progress bar where a person watches (a terminal, a
        notebook; the iterations of the step under way too), nothing where the output is
        captured; ``False`` or ``None``: nothing.
    monitor
        Called as ``monitor(iteration, f, gnorm)`` at every TAO iteration; ``True`` stops.
    command_line
        What to record as the command line (default: the arguments that describe ``run``).
    """
    with opened(run, command_line) as prepared:
        return prepared.execute(progress, monitor)


@contextmanager
def opened(
    run: Run, command_line: str | None = None, lock: bool = True, posing: Posing | None = None
) -> Iterator[Prepared]:
    """``run`` prepared (:func:`prepare`) for a ``with`` block, which executes it: the door
    every run goes through (:func:`run_contact`, the command line, :func:`contact_steps`).

    Within the block ``SIGTERM``, as ``Ctrl-C``, raises :class:`RunInterrupted` where the
    caller has no handler of its own (:func:`~petsc_contact.io.interrupts.interruptible`),
    the output is locked unless ``lock`` is False (the caller holds the lock:
    :func:`locked`), and PETSc holds the run's options with its prefix
    (:func:`run_options`).  ``command_line`` and ``posing`` as :func:`prepare` takes them."""
    from ..io.interrupts import interruptible

    check_files(run)
    with interruptible(), locked(run.output) if lock else nullcontext(), run_options(run) as petsc:
        yield prepare(run, command_line, petsc, posing)


def contact_steps(
    run: Run, posing: Posing, progress: Progress | bool | None, monitor: Monitor | None
) -> Steps:
    """The steps of ``run`` (no output) whose problem ``posing`` poses, through
    :func:`opened` (its warnings and progress those of every run), as
    :class:`~petsc_contact.geometries.step.Steps` of its geometry: what
    :func:`~petsc_contact.workflows.periodic_sweep.periodic_contact` and
    :func:`~petsc_contact.workflows.punch_sweep.punch_contact` return."""
    with opened(run, posing=posing) as prepared:
        return Steps(prepared.execute(progress, monitor).steps, kind=run.geometry)


def posed_scene(grid: Grid, fft: Any = None, heights: Any = None) -> Scene:
    """The scene of a problem posed from a map as it is (the Python API's): its grid, and the
    map's ``fft`` and local ``heights`` where its driver poses the problem from the scene (else
    the problem holds them); no file records them."""
    resolved = {"length": list(grid.lengths), "length_unit": ""}
    local = np.empty((0, grid.shape[1])) if heights is None else heights
    return Scene(grid, fft, local, resolved)


def run_options(run: Run) -> AbstractContextManager[ModuleType | None]:
    """PETSc with ``run``'s options and its ``options_prefix`` where its solver backend is
    PETSc's; nothing for the array backend (its settings hold ``run.options``)."""
    return scoped_options(run.device, list(run.options), run.options_prefix)


@contextmanager
def locked(path: str | None) -> Iterator[None]:
    """Hold the exclusive right to write ``path`` (rank 0 takes it; every rank raises the same
    error when another run holds it: :class:`~petsc_contact.io.store.OutputBusy`)."""
    if path is None:  # nothing to lock: no collective step either
        yield
        return
    comm = world()
    lock = OutputLock(path) if comm.rank == 0 else None
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


def provenance(run: Run, petsc: Any | None = None) -> dict[str, Any]:
    """What a record says of how ``run`` was computed: its PETSc options (an array device's
    run, which loads no PETSc: the options it was given), the versions, the MPI ranks and
    the device (:meth:`~petsc_contact.devices.device.Device.describe`).  ``petsc``: PETSc,
    initialised here for a ``cpu`` run where not given."""
    from ..io.provenance import petsc_options, versions

    if petsc is None and uses_petsc(run.device):
        petsc = _petsc.init()
    return {
        "petsc_options": petsc_options(petsc) if petsc is not None else " ".join(run.options),
        "versions": versions(petsc),
        "mpi_size": petsc.COMM_WORLD.getSize() if petsc is not None else world().size,
        **get_device(run.device).describe(),
    }


def run_record(
    run: Run,
    command_line: str,
    petsc: Any | None,
    realised: dict[str, float],
    resolved: dict[str, Any],
) -> dict[str, Any]:
    """What reproduces the run: its description (defaults resolved), versions, PETSc options
    (an array device's run, with ``petsc`` None: the options it was given), its device."""
    from ..conventions.units import force_unit
    from ..io.provenance import input_digest

    params = run.parameters() | {k: v for k, v in resolved.items() if k not in FILE_RECORD}
    lengths, unit = resolved["length"], resolved["length_unit"]
    attrs: dict[str, Any] = {
        "geometry": run.geometry,
        "command_line": command_line,
        "parameters": params,
        **provenance(run, petsc),
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
        attrs["heights_sha256"] = input_digest(run.heights)  # a resume joins only this map
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
