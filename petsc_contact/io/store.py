"""Durable run files: one writer per output, every finished step on disk whatever happens.

While a run with output ``OUT.h5`` is under way, its ranks keep beside it (the record and
the table on rank 0; every array in row slabs, each rank writing its own rows to its own
files, :mod:`~petsc_contact.io.parts`: no rank ever holds a whole field):

``OUT.h5.lock``
    held (``flock``) by the running process from before it touches anything to its end, so
    that a second run on the same output is refused at once.  The kernel drops the lock when
    the process dies, however it dies; a lock file left behind is free.
``OUT.h5.partial``
    an HDF5 file with the run record and the scalars of every finished step (bare columns:
    the units, descriptions and dimension scales are the final file's), replaced whole
    after each step (:func:`~petsc_contact.io.partial.commit`): whatever instant the process
    dies at, this file is the last step's or the one before, never a torn one.  It is the
    commit point: a step is finished when it is in this file.
``OUT.h5.parts/``
    the bulky arrays, one HDF5 file each, each written to a temporary name and renamed before
    the step is committed: ``heights.h5``, and ``step-000001.h5``, ... with a step's fields,
    compressed once, as the final file holds them (on ``P`` ranks, ``P`` slabs of each).  The
    commit records each file's SHA-256 (the ``.partial``'s attribute ``parts``); a part is
    used only when the bytes of every slab match it.
``OUT.h5.state.npz``
    the solution the next step starts from, written after the commit (on ``P`` ranks, ``P``
    slabs, :mod:`~petsc_contact.io.state`); a resume that finds it missing, damaged or stale
    starts the next step from first touch (the same result to the solver's tolerance, at a
    different cost).

When the run ends, every part is checked against its checksum, ``OUT.h5`` is assembled
from them by rank 0, a band of rows at a time (the fields' compressed chunks copied as they
are where a slab's rows fall on whole chunks), written to a temporary name and renamed into
place, then its step table ``OUT.csv`` is written, and the rest is removed.  An
earlier run's ``OUT.csv`` is removed before the new ``OUT.h5`` is renamed into place, so that
a table is never beside another run's ``OUT.h5``; a table missing beside a complete
``OUT.h5`` is written again by :func:`tidy` or ``--resume`` (the ``.partial`` is removed
only after the table is written).  A run killed before that rename leaves everything to
``--resume``; one killed after it has its whole result.  A resume computes again what a
missing or damaged part held: the heights are written again, the steps from the first
damaged one are computed again.  Disk errors (full, read-only, I/O) raise
:class:`StorageError`, after which every committed step is still there.  What is lost to a
kill is at most the step being computed.  (Power loss is another matter: nothing here calls
``fsync``.)

The pieces this rests on have a module each: :mod:`~petsc_contact.io.names` (the files'
names), :mod:`~petsc_contact.io.atomic` (a file written whole or not at all,
:class:`StorageError`), :mod:`~petsc_contact.io.lock` (the output lock),
:mod:`~petsc_contact.io.partial` (the ``.partial`` file: the commit, every read of it, the
checks that what it kept is this run's), :mod:`~petsc_contact.io.parts` (the parts'
checksums), :mod:`~petsc_contact.io.state` (the state slabs),
:mod:`~petsc_contact.io.assemble` (the files' layout, ``OUT.h5`` assembled) and
:mod:`~petsc_contact.io.interrupts` (signals that end a run); their names stay importable
from here.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import warnings
from contextlib import suppress
from dataclasses import dataclass, field
from datetime import datetime
from typing import TYPE_CHECKING, Any

import numpy as np

from ..conventions.warnings import ReplacedOutput, option
from ..physics.continuation import Held
from .assemble import FIELD_CHUNK, assemble_output, field_layout
from .atomic import (
    StorageError,
    _reason,
    atomic_h5,
    check_room,
    on_every,
    on_root,
    replaced,
    storage,
)
from .interrupts import check_interrupt, forget_interrupts, interrupt
from .lock import OutputBusy, OutputLock, _now, check_writable
from .names import (
    HEIGHTS_PART,
    LOCK,
    PARTIAL,
    PARTS,
    STATE,
    csv_path,
    is_partial,
    partial_path,
    parts_path,
    state_path,
    step_part,
)
from .partial import (
    RECORDED_SINCE,
    RESUME_FREE,
    check_nothing_lost,
    check_same_input,
    check_same_run,
    commit,
    committed_steps,
    discard,
    leftover_table,
    read_attributes,
    read_committed,
    write_steps,
)
from .parts import PartsCheck, check_parts, part_problem, slab_name, slab_of
from .provenance import source_commit
from .schema import GEOMETRIES, MISSING, Entry, describe, h5_dtype, in_unit
from .state import remove_states, saved_state, write_state

if TYPE_CHECKING:
    from ..conventions.grid import Grid, RowSource

__all__ = [  # the names of the modules this one was split into stay importable from it
    "FIELD_CHUNK",
    "HEIGHTS_PART",
    "LOCK",
    "PARTIAL",
    "PARTS",
    "RECORDED_SINCE",
    "RESUME_FREE",
    "STATE",
    "Finished",
    "OutputBusy",
    "OutputLock",
    "PartsCheck",
    "StepStore",
    "StorageError",
    "atomic_h5",
    "check_interrupt",
    "check_nothing_lost",
    "check_parts",
    "check_room",
    "check_same_input",
    "check_same_run",
    "check_writable",
    "committed_steps",
    "csv_path",
    "forget_interrupts",
    "interrupt",
    "is_partial",
    "on_root",
    "part_problem",
    "partial_path",
    "parts_path",
    "read_complete",
    "read_resume",
    "replaced",
    "state_path",
    "step_part",
    "storage",
    "tidy",
    "write_csv",
]


@dataclass
class Finished:
    """What an interrupted run left to go on from."""

    steps: int
    table: dict[str, list[Any]] = field(default_factory=dict)
    state: RowSource | None = None  # read a rank's rows at a time (grid.scatter)
    state_problem: str = ""  # why the state could not be used ("" when it can)
    held: Held | None = None  # what the sweep held beside the state (fields as row sources)
    parts: dict[str, str] = field(default_factory=dict)  # the parts' SHA-256 at their commit
    rewrite_maps: bool = False  # heights.h5 is missing or damaged: the run writes it again
    whole: bool = False  # the steps are a complete output's: nothing to compute or write

    def rows(self) -> list[dict[str, Any]]:
        """The finished steps' scalars, one dict per step."""
        return [{k: v[i] for k, v in self.table.items()} for i in range(self.steps)]

    def redo(self, check: PartsCheck, path: str) -> Finished:
        """These finished steps less what ``check`` found missing or damaged in the parts of
        output ``path``: the steps after ``check.steps`` (computed again, from first touch)
        and the heights (written again) when ``check.maps``."""
        if check.steps == self.steps and not check.maps:
            return self
        steps = check.steps
        kept = {step_part(k) for k in range(1, steps + 1)}
        if not check.maps:
            kept.add(HEIGHTS_PART)
        kept = {f for f in self.parts if any(slab_of(n, f) is not None for n in kept)}
        state, problem, held = self.state, self.state_problem, self.held
        if steps < self.steps:
            state = held = None
            problem = (
                problem or f"{state_path(path)} is of step {self.steps}, which is computed again"
            )
        return Finished(
            steps,
            {k: v[:steps] for k, v in self.table.items()},
            state,
            problem,
            held,
            {k: v for k, v in self.parts.items() if k in kept},
            check.maps,
        )


def read_resume(
    path: str, parameters: dict[str, Any], grid: Grid, digest: str | None = None
) -> Finished:
    """The finished steps of an interrupted run ``path + '.partial'``, its scalars, and the
    state to go on from, of which each rank of ``grid`` checks and reads only the slabs that
    hold its rows (collective).

    Returns ``Finished(0)`` when there is nothing to resume.  Raises ``ValueError`` when the
    partial file belongs to a different run (its ``parameters`` differ, apart from
    :data:`RESUME_FREE`, or its map is not the one of digest ``digest``:
    :func:`check_same_input`), so a resume never mixes two runs, or when it
    cannot be read (damaged by something else than a run: the run itself replaces it whole).
    """
    partial = partial_path(path)
    if not os.path.exists(partial):
        return Finished(0)
    try:
        kept = read_committed(partial)
        theirs, recorded, parts = kept.parameters, kept.digest, kept.parts
    except (OSError, KeyError, ValueError) as exc:
        raise ValueError(
            f"cannot resume '{partial}': it is damaged ({_reason(exc)}); --overwrite starts afresh"
        ) from None
    check_same_run(partial, theirs, parameters)
    check_same_input(partial, recorded, digest)
    state, held, problem = saved_state(path, kept.steps, grid)
    return Finished(kept.steps, kept.table, state, problem, held, parts)


def read_complete(path: str, parameters: dict[str, Any], digest: str | None = None) -> Finished:
    """A complete output ``path`` of this run, with no ``.partial`` beside it, as finished
    steps that need no computing (``whole``); ``Finished(0)`` when there is no such file.
    ``ValueError`` when it is a complete file of another run (``parameters`` differ, apart from
    :data:`RESUME_FREE`, or its map is not the one of digest ``digest``:
    :func:`check_same_input`): a resume never replaces another run's results."""
    if os.path.exists(partial_path(path)) or not os.path.isfile(path):
        return Finished(0)
    try:
        kept = read_committed(path)
        if not kept.attributes.get("complete"):
            return Finished(0)
        theirs, recorded = kept.parameters, kept.digest
    except (OSError, KeyError, ValueError):
        return Finished(0)  # not a results file: the run writes one (as without --resume)
    try:
        check_same_run(path, theirs, parameters)
    except ValueError as exc:
        raise ValueError(f"{exc}; --overwrite replaces it") from None
    check_same_input(path, recorded, digest)
    return Finished(kept.steps, kept.table, whole=True)


def created_stamp() -> str:
    """A run file's ``created`` stamp: the local time to the microsecond, with its offset
    from UTC (ISO 8601).  It tells a run's files from another's (a leftover ``.partial`` of
    the complete file, a seed file replaced), so two runs on one output within a second
    must not share it."""
    return datetime.now().astimezone().strftime("%Y-%m-%dT%H:%M:%S.%f%z")


def check_resume_or_overwrite(resume: bool, overwrite: bool) -> None:
    """``ValueError`` for ``resume`` and ``overwrite`` together: one continues what an
    earlier run left, the other deletes it."""
    if resume and overwrite:
        raise ValueError("--resume continues a run, --overwrite starts it afresh: not both")


def warn_replaced(path: str, stacklevel: int = 2) -> None:
    """Warn (:class:`ReplacedOutput`) where a file at output ``path`` exists: a run that
    neither resumes nor overwrites replaces it once it ends.  ``stacklevel`` as
    ``warnings.warn``'s, counted from the caller."""
    if os.path.exists(path):
        warnings.warn(
            f"'{path}' exists and is replaced when this run ends; from 0.3.0 that needs "
            f"{option('overwrite', True)}",
            ReplacedOutput,
            stacklevel=stacklevel + 1,
        )


class StepStore:
    """A run's results, durable step by step (see the module docstring).

    Rank 0 writes the record and the table; every rank writes its own rows of the maps,
    fields and state (slabs, :mod:`~petsc_contact.io.parts`), and every rank raises the same
    :class:`StorageError` when any rank cannot write.

    Parameters
    ----------
    path
        The final file, ``OUT.h5``.
    grid
        The layout of the fields.
    fields
        Names of per-step fields stored (``gap``, ``pressure``, ``contact``), or none.
    """

    def __init__(self, path: str, grid: Grid, fields: tuple[str, ...] = ()) -> None:
        self.path = path
        self.partial = partial_path(path)
        self.parts = parts_path(path)
        self.grid = grid
        self.fields = fields
        self.root = grid.comm.rank == 0
        self.attributes: dict[str, Any] = {}
        self.table: dict[str, list[Any]] = {}
        self.steps = 0
        self.digests: dict[str, str] = {}  # the parts' SHA-256, recorded at each commit
        self.maps = False  # whether the run stores heights.h5
        self.assembled = False  # OUT.h5 is in place
        self.fresh_state = True  # no state written yet: another rank count's is removed

    @classmethod
    def create(
        cls,
        path: str,
        grid: Grid,
        attributes: dict[str, Any],
        heights: np.ndarray | None,
        fields: tuple[str, ...] = (),
        filled: np.ndarray | None = None,
    ) -> StepStore:
        """A new run: whatever an earlier run left under this output is cleared (the caller
        holds the output's lock), then the record, the heights and (a measured map's) mask of
        filled heights are written (local slabs)."""
        store = cls(path, grid, fields)
        store.maps = heights is not None or filled is not None
        store.attributes = {**attributes, "created": created_stamp(), "complete": False}

        def begin() -> None:
            _clear(path, keep_steps=False)
            os.makedirs(store.parts)

        store._on_root(begin)
        try:
            if store.maps:
                store._write_part(HEIGHTS_PART, _maps(heights, filled), chunked=False)
            store._on_root(store._commit)
        except BaseException:
            if store.root:
                _clear(path, keep_steps=False)  # nothing was finished: nothing is left
            raise
        return store

    @classmethod
    def resume(
        cls,
        path: str,
        grid: Grid,
        finished: Finished,
        record: dict[str, Any],
        fields: tuple[str, ...] = (),
        heights: np.ndarray | None = None,
        filled: np.ndarray | None = None,
    ) -> StepStore:
        """Go on with an interrupted run from its ``finished`` steps; the file's ``resumed``
        list gains this segment's record (its command line, PETSc options and commit).

        ``heights`` and ``filled`` are the maps the run stores (local slabs), written again
        when ``finished.rewrite_maps`` (its ``heights.h5`` was missing or damaged)."""
        store = cls(path, grid, fields)
        store.steps = finished.steps
        store.digests = dict(finished.parts)
        stored = any(slab_of(HEIGHTS_PART, p) is not None for p in finished.parts)
        store.maps = heights is not None or filled is not None or stored
        if store.root:
            attributes = read_attributes(store.partial)
            store.attributes = {k: v for k, v in attributes.items() if k != "parts"}
            store.table = {k: list(v) for k, v in finished.table.items()}
        store.attributes = grid.comm.bcast(store.attributes, root=0)  # every rank's schema
        earlier = json.loads(str(store.attributes.get("resumed", "[]")) or "[]")
        segment = {
            "after_step": finished.steps,
            "time": _now(),
            "petsc_contact_commit": source_commit(),
            "from_saved_state": finished.state is not None,  # False: began at first touch
            "device": record.get("device", "cpu"),
            "command_line": record.get("command_line", ""),
            "petsc_options": record.get("petsc_options", ""),
        }
        store.attributes["resumed"] = json.dumps([*earlier, segment])

        def begin() -> None:
            _clear(path, keep_steps=True)
            _make_folder(store.parts)

        store._on_root(begin)
        maps = _maps(heights, filled) if finished.rewrite_maps else {}
        if maps:
            store._write_part(HEIGHTS_PART, maps, chunked=False)
        store._on_root(store._commit)
        return store

    def append(
        self,
        scalars: dict[str, Any],
        fields: dict[str, np.ndarray] | None = None,
        state: np.ndarray | None = None,
        held: Held | None = None,
    ) -> None:
        """Commit one finished step: its fields (if stored), then its scalars, then the state
        a resume would start the next step from and what the sweep ``held`` beside it
        (collective; every rank writes its own rows)."""
        step = self.steps + 1
        if fields and self.fields:
            self._write_part(step_part(step), {k: fields[k] for k in self.fields}, True)

        def commit_step() -> None:
            for key, value in scalars.items():
                if key not in self.table:  # new, or new since the version a resume began with
                    self.table[key] = [_missing(value)] * self.steps
            for key, column in self.table.items():
                column.append(scalars[key] if key in scalars else _missing(column[0]))
            try:
                self._commit()
            except BaseException:
                for column in self.table.values():
                    column.pop()
                raise

        self._on_root(commit_step)
        self.steps = step
        if state is not None:
            self._write_state(state, held, step)

    def _write_state(self, state: np.ndarray, held: Held | None, step: int) -> None:
        """Every rank saves its rows of the state after ``step`` and of the fields ``held``
        beside it (:func:`~petsc_contact.io.state.write_state`); after the first, the slabs
        another rank count left are removed (collective)."""
        comm = self.grid.comm
        write_state(self.path, comm, state, held, step)
        if self.fresh_state:
            self._on_root(lambda: remove_states(self.path, keep=comm.size))
            self.fresh_state = False

    def finish(self) -> None:
        """Assemble ``OUT.h5`` (complete), rename it into place, remove the rest (collective)."""

        def assemble() -> None:
            table = csv_path(self.path)
            assemble_output(self, table)
            self.assembled = True
            write_csv(table, self.table, self.steps)
            _clear(self.path, keep_steps=False)

        self._on_root(assemble)
        self.grid.comm.Barrier()

    def discard(self) -> None:
        """Remove everything of a run that finished no step (a failure before the first)."""
        if self.root:
            _clear(self.path, keep_steps=False)

    def abandon(self, why: str = "interrupted") -> str:
        """The one line to say when a run stops early: its finished steps stay committed (as
        many as the ``.partial`` holds), or its ``OUT.h5`` is complete already."""
        if self.assembled and not os.path.exists(self.partial):
            return f"{why}; {self.path} is complete ({self.steps} steps)"
        kept = self.steps
        if self.root:
            with suppress(OSError):
                kept = committed_steps(self.partial)
        return f"{why}; {kept} finished step(s) kept in {self.partial} (--resume continues)"

    # -- rank 0's writes ---------------------------------------------------------------------

    def _on_root(self, work: Any) -> None:
        on_root(self.grid.comm, work)

    def entry(self, name: str) -> Entry:
        """The schema entry of dataset ``name`` of this run's files, in the run's units."""
        schema = GEOMETRIES.get(str(self.attributes.get("geometry", "")), {})
        try:
            entry = schema[name]
        except KeyError:
            raise KeyError(f"no schema entry for dataset '{name}' (petsc_contact.io)") from None
        attrs = self.attributes
        return in_unit(
            entry, str(attrs.get("length_unit", "")), str(attrs.get("pressure_unit", ""))
        )

    def _commit(self) -> None:
        """Replace the ``.partial`` file by one holding every finished step."""
        commit(
            self.path,
            {**self.attributes, "parts": self.digests},
            lambda f: write_steps(f, self.table),
        )

    def _write_part(self, name: str, arrays: dict[str, np.ndarray], chunked: bool) -> None:
        """Every rank writes its rows of part ``name`` (``arrays``, local slabs) to its slab
        file; their checksums go into rank 0's next commit (collective)."""
        comm = self.grid.comm
        slab = os.path.join(self.parts, slab_name(name, comm.rank, comm.size))
        mine: dict[str, str] = {}

        def write() -> None:
            with atomic_h5(slab, digests=mine) as f:
                for key, value in arrays.items():
                    if chunked:
                        d = f.create_dataset(key, data=value[None], **field_layout(value.shape))
                    else:
                        d = f.create_dataset(key, data=value)
                    describe(d, self.entry(key))

        on_every(comm, write)
        for digests in comm.gather(mine, root=0) or ():
            self.digests.update(digests)


def _maps(heights: np.ndarray | None, filled: np.ndarray | None) -> dict[str, np.ndarray]:
    """The maps a run stores (local slabs): its heights and a measured map's filled mask."""
    return {k: v for k, v in {"heights": heights, "filled": filled}.items() if v is not None}


def _missing(value: Any) -> Any:
    """What the steps without a column read in it: NaN, -1, '' or False (never a plausible
    0 for a number; an array of them for an array)."""
    dtype = h5_dtype(value)
    if isinstance(value, np.ndarray):
        return np.full(value.shape, MISSING[dtype], dtype=dtype)
    if dtype in MISSING:
        return MISSING[dtype]
    return False if dtype is bool else ""


def write_csv(path: str, table: dict[str, list[Any]], steps: int) -> None:
    """The step table ``path`` (``OUT.csv``): one row per step of ``table``'s scalars."""
    import csv

    names = [k for k, v in table.items() if not (v and isinstance(v[0], np.ndarray))]
    with storage(path), replaced(path) as temporary, open(temporary, "w", newline="") as out:
        writer = csv.writer(out)
        writer.writerow(["step", *names])
        for i in range(steps):
            writer.writerow([i + 1, *(table[k][i] for k in names)])


def tidy(path: str) -> None:
    """Finish what the writer of a complete ``path`` left undone when it was killed after
    renaming ``path`` into place: the step table written (again) and the run files removed;
    only when they are that very run's (the same ``created`` stamp and steps), and only when
    no other run holds the output."""
    if not (os.path.exists(partial_path(path)) and os.path.exists(path)):
        return
    with suppress(OutputBusy), OutputLock(path):
        table = leftover_table(path)
        if table is not None:
            write_csv(csv_path(path), table, len(table["converged"]))
            _clear(path, keep_steps=False)


def remove_temporaries(path: str) -> None:
    """Remove the temporary files that writers of output ``path`` killed mid-write left
    (``OUT.h5.PID.tmp``, ``OUT.h5.partial.PID.tmp``, the table's); the caller holds the
    output's lock."""
    _clear(path, keep_steps=True)


def _clear(path: str, keep_steps: bool) -> None:
    """Remove what runs on output ``path`` left: temporary files of killed writers always
    (the step table's too),
    the committed steps (``.partial``, parts, state) unless ``keep_steps``.  Only the holder
    of the output's lock calls this."""
    folder, name = os.path.split(os.path.abspath(path))
    table = os.path.basename(csv_path(path))
    pattern = re.compile(
        rf"({re.escape(name)}(\.partial|\.state(\.\d+of\d+)?\.npz)?|{re.escape(table)})\.\d+\.tmp"
    )
    for entry in os.listdir(folder):
        if pattern.fullmatch(entry):
            with suppress(FileNotFoundError):
                os.remove(os.path.join(folder, entry))
    if keep_steps:
        parts = parts_path(path)
        for entry in os.listdir(parts) if os.path.isdir(parts) else ():
            if entry.endswith(".tmp"):
                with suppress(FileNotFoundError):
                    os.remove(os.path.join(parts, entry))
        return
    discard(path)  # the record first
    remove_states(path, keep=0)
    parts = parts_path(path)
    if os.path.isdir(parts) and not os.path.islink(parts):
        shutil.rmtree(parts, ignore_errors=True)
    else:  # a plain file of that name, which no run writes
        with suppress(FileNotFoundError):
            os.remove(parts)


def _make_folder(folder: str) -> None:
    """Make the parts' ``folder`` unless it is there (a plain file of its name is removed)."""
    if os.path.lexists(folder) and not os.path.isdir(folder):
        os.remove(folder)
    os.makedirs(folder, exist_ok=True)
