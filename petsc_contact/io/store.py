"""Durable run files: one writer per output, every finished step on disk whatever happens.

While a run with output ``OUT.h5`` is under way, its ranks keep beside it (the record and
the table on rank 0; every array in row slabs, each rank writing its own rows to its own
files, :mod:`~petsc_contact.io.parts`: no rank ever holds a whole field):

``OUT.h5.lock``
    held (``flock``) by the running process from before it touches anything to its end, so
    that a second run on the same output is refused at once.  The kernel drops the lock when
    the process dies, however it dies; a lock file left behind is free.
``OUT.h5.partial``
    an HDF5 file with the run record and the scalars of every finished step, written whole
    to a temporary name and renamed over the last one after each step.  A rename is atomic,
    so whatever instant the process dies at, this file is the last step's or the one before,
    never a torn one.  It is the commit point: a step is finished when it is in this file.
``OUT.h5.parts/``
    the bulky arrays, one HDF5 file each, each written to a temporary name and renamed before
    the step is committed: ``heights.h5``, and ``step-000001.h5``, ... with a step's fields,
    compressed once, as the final file holds them (on ``P`` ranks, ``P`` slabs of each).  The
    commit records each file's SHA-256 (the ``.partial``'s attribute ``parts``); a part is
    used only when the bytes of every slab match it.
``OUT.h5.state.npz``
    the solution the next step starts from (``after_step`` says which step it ends), written
    after the commit (on ``P`` ranks, ``P`` slabs); a resume that finds it missing, damaged or
    stale starts the next step from first touch (the same result to the solver's tolerance,
    at a different cost).  A resume on any rank count reads each rank's rows only, and each
    rank checks only the slabs that hold them (the ranks agree on the verdict).

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
:mod:`~petsc_contact.io.parts` (the parts' checksums) and
:mod:`~petsc_contact.io.interrupts` (signals that end a run); their names stay importable
from here.
"""

from __future__ import annotations

import errno
import json
import os
import re
import shutil
import warnings
import zipfile
from contextlib import suppress
from dataclasses import dataclass, field
from datetime import datetime
from typing import TYPE_CHECKING, Any

import numpy as np

from ..conventions.grid import block_rows
from ..conventions.warnings import ReplacedOutput, ResumeWarning, option, user_level
from ..physics.continuation import Held
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
from .parts import (
    PartsCheck,
    SlabRows,
    _steps,
    check_parts,
    mapped,
    part_problem,
    slab_name,
    slab_of,
    slab_rows,
    slabs,
)
from .provenance import source_commit
from .schema import (
    COORDINATES,
    GEOMETRIES,
    MISSING,
    SECOND_DIMENSION,
    Entry,
    describe,
    h5_dtype,
    in_unit,
    write_attributes,
)

if TYPE_CHECKING:
    from ..conventions.grid import Grid, RowSource

__all__ = [  # the names of the modules this one was split into stay importable from it
    "FIELD_CHUNK",
    "HEIGHTS_PART",
    "LOCK",
    "PARTIAL",
    "PARTS",
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

FIELD_CHUNK = 256  # fields are stored in (1, 256, 256) chunks, gzip level 4 with shuffle


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
    import h5py

    partial = partial_path(path)
    if not os.path.exists(partial):
        return Finished(0)
    try:
        with h5py.File(partial, "r") as f:
            theirs = json.loads(f.attrs["parameters"])
            recorded = f.attrs.get("heights_sha256")
            parts = json.loads(f.attrs.get("parts", "{}"))  # none in earlier versions' files
            table = _read_table(f)
            steps = len(table.get("converged", []))
    except (OSError, KeyError, ValueError) as exc:
        raise ValueError(
            f"cannot resume '{partial}': it is damaged ({_reason(exc)}); --overwrite starts afresh"
        ) from None
    check_same_run(partial, theirs, parameters)
    check_same_input(partial, recorded, digest)
    state, held, problem = _saved_state(path, steps, grid)
    return Finished(steps, table, state, problem, held, parts)


def read_complete(path: str, parameters: dict[str, Any], digest: str | None = None) -> Finished:
    """A complete output ``path`` of this run, with no ``.partial`` beside it, as finished
    steps that need no computing (``whole``); ``Finished(0)`` when there is no such file.
    ``ValueError`` when it is a complete file of another run (``parameters`` differ, apart from
    :data:`RESUME_FREE`, or its map is not the one of digest ``digest``:
    :func:`check_same_input`): a resume never replaces another run's results."""
    import h5py

    if os.path.exists(partial_path(path)) or not os.path.isfile(path):
        return Finished(0)
    try:
        with h5py.File(path, "r") as f:
            if not f.attrs.get("complete"):
                return Finished(0)
            theirs = json.loads(f.attrs["parameters"])
            recorded = f.attrs.get("heights_sha256")
            table = _read_table(f)
    except (OSError, KeyError, ValueError):
        return Finished(0)  # not a results file: the run writes one (as without --resume)
    try:
        check_same_run(path, theirs, parameters)
    except ValueError as exc:
        raise ValueError(f"{exc}; --overwrite replaces it") from None
    check_same_input(path, recorded, digest)
    return Finished(len(table.get("converged", [])), table, whole=True)


def _read_table(f: Any) -> dict[str, list[Any]]:
    """The per-step datasets of a run's open HDF5 file ``f``, as lists."""
    return {
        k: list(_values(f[k]))
        for k in f
        if k not in COORDINATES and f[k].ndim >= 1 and f[k].shape[0] == f["step"].shape[0]
    }


def created_stamp() -> str:
    """A run file's ``created`` stamp: the local time to the microsecond, with its offset
    from UTC (ISO 8601).  It tells a run's files from another's (a leftover ``.partial`` of
    the complete file, a seed file replaced), so two runs on one output within a second
    must not share it."""
    return datetime.now().astimezone().strftime("%Y-%m-%dT%H:%M:%S.%f%z")


def committed_steps(partial: str) -> int:
    """The finished steps an unfinished file holds (an ``OSError`` when it cannot be read)."""
    import h5py

    with h5py.File(partial, "r") as f:
        return int(f["converged"].shape[0]) if "converged" in f else 0


def check_nothing_lost(path: str) -> None:
    """``ValueError`` when a new run on output ``path`` would delete finished steps: those an
    interrupted run kept in ``path + '.partial'`` (``--resume`` continues it, ``--overwrite``
    deletes them), or a ``.partial`` that cannot be read.  The ``.partial`` of a finished run
    left beside its complete ``path`` holds nothing that is not in ``path``."""
    partial = partial_path(path)
    if not os.path.exists(partial) or _leftover_table(path) is not None:
        return
    try:
        steps = committed_steps(partial)
    except OSError as exc:
        raise ValueError(
            f"'{partial}' is damaged ({_reason(exc)}): --overwrite starts afresh (deleting it)"
        ) from None
    if steps:
        raise ValueError(
            f"'{partial}' holds {steps} finished step(s) of an interrupted run: --resume "
            "continues it, --overwrite starts afresh (deleting them)"
        )


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


RESUME_FREE = ("resume", "overwrite", "quiet", "stop_after", "device")
"""The options a resume may change: none changes the result (a device, its rounding only:
a run paused on a GPU goes on on the CPU; the ``resumed`` list records each part's)."""


RECORDED_SINCE = {
    "cut_from": 1,
    "flat_stiffness": "grid",
    "footprint": "square",
    "options_prefix": "",
    "override_metadata": False,
    "skip_memory_check": False,
}
"""Parameters that files of earlier versions do not record, each with the value every run of
those versions had (each option came with that behaviour as its default): a file without one
is compared as if it recorded that value, so a study or a resume goes on across an upgrade,
and a run that sets another value is still refused."""


def check_same_run(partial: str, theirs: dict[str, Any], mine: dict[str, Any]) -> None:
    """``ValueError`` unless an unfinished file's ``parameters`` are this run's (apart from
    :data:`RESUME_FREE`; one that predates :data:`RECORDED_SINCE`'s has their values): a
    resume never mixes two runs."""
    a = json.loads(json.dumps({k: v for k, v in mine.items() if k not in RESUME_FREE}))
    earlier = {k: v for k, v in RECORDED_SINCE.items() if k in a}  # where theirs lacks them
    b = {k: v for k, v in (earlier | theirs).items() if k not in RESUME_FREE}
    changed = sorted(k for k in set(a) | set(b) if not _same(a.get(k), b.get(k)))
    if changed:
        raise ValueError(
            f"cannot resume '{partial}': it was run with different parameters "
            f"({', '.join(changed)})"
        )


def check_same_input(path: str, recorded: Any, digest: str | None) -> None:
    """``ValueError`` (one line, naming ``--overwrite``) unless the map of the run that file
    ``path`` holds, whose SHA-256 it records (``recorded``, its ``heights_sha256``), is the one
    of digest ``digest`` (:func:`~petsc_contact.io.provenance.input_digest`; ``None`` for a
    generated surface, which its parameters describe): a resume never mixes two maps.  A file
    that records no digest of its map (an array's, before this was recorded) is joined with
    a :class:`ResumeWarning` saying that the map is not compared."""
    if digest is None or recorded == digest:
        return
    if not recorded:
        warnings.warn(
            f"'{path}' records no digest of its height map: that the map is the same is not "
            "checked",
            ResumeWarning,
            stacklevel=user_level(),
        )
        return
    raise ValueError(
        f"cannot resume '{path}': its height map has changed since it was run (SHA-256 "
        f"{str(recorded)[:12]}... then, {digest[:12]}... now); --overwrite starts afresh"
    )


def _values(dataset: Any) -> np.ndarray:
    values = dataset[...]
    if values.dtype.kind == "O":
        return np.array([v.decode() if isinstance(v, bytes) else v for v in values], dtype=object)
    return values


def _saved_state(path: str, steps: int, grid: Grid) -> tuple[RowSource | None, Held | None, str]:
    """The state after step ``steps`` and what the sweep held beside it (``None`` in a state
    file of an earlier version), as row sources whose rows are read when a rank of ``grid``
    asks for them, or ``None`` and why not.  Of the sets of slabs left by runs on different
    rank counts (a run killed before it removed the older set), the newest sound one; every
    rank of ``grid`` goes through the sets rank 0 found and reaches the same verdict on each
    (collective)."""
    where = state_path(path)
    if not steps:
        return None, None, ""
    comm = grid.comm
    sets = comm.bcast(_state_sets(where) if comm.rank == 0 else None, root=0)
    problem = f"{where} is missing"
    for i, files in enumerate(sets):
        try:
            after, slabs_of = _read_slabs(files, grid)
        except _Damaged as exc:
            problem = str(exc) if i == 0 else problem
            continue
        if after + 1 == steps:
            rows = grid.shape[0]
            state = SlabRows(slabs_of.pop("state"), rows)
            held = None
            if "held" in slabs_of:
                scalars = slabs_of.pop("held")[0][1]
                fields: tuple[Any, ...] = tuple(
                    SlabRows(slabs_of[f"held_field_{k}"], rows) for k in range(len(slabs_of))
                )  # row sources: each rank reads its rows of each (grid.scatter)
                held = Held(np.asarray(scalars), fields)
            return state, held, ""
        problem = f"{files[0]} is of step {after + 1}, not {steps}" if i == 0 else problem
    return None, None, problem


class _Damaged(Exception):
    """A state slab that cannot be used: missing, truncated, foreign or failing its CRC."""


def _state_sets(where: str) -> list[list[str]]:
    """The files of every set of state slabs beside ``where`` (``OUT.h5.state.npz``), one
    list per rank count, in rank order, the newest set first."""
    folder, name = os.path.split(where)
    times: dict[int, int] = {}  # each rank count's newest slab
    for entry in os.listdir(folder or "."):
        found = slab_of(name, entry)
        if found is not None:
            time = os.stat(os.path.join(folder, entry)).st_mtime_ns
            times[found[1]] = max(times.get(found[1], 0), time)
    newest = sorted(times, key=lambda size: -times[size])
    return [[os.path.join(folder, slab_name(name, r, p)) for r in range(p)] for p in newest]


def _read_slabs(
    files: list[str], grid: Grid
) -> tuple[int, dict[str, list[tuple[int, np.ndarray]]]]:
    """The step a set of state slabs ends and, of the slabs that hold this rank's rows of
    ``grid``, each array as ``(first row, array)``, memory-mapped (``held``'s whole, it is
    small).  A rank opens only those slabs (a rank without rows, the first), checks each
    member's CRC, streamed, and the ranks agree (collective): every rank raises the same
    :class:`_Damaged`, naming the first slab of the set that any rank could not use."""
    total, mine = grid.shape[0], grid.rows
    spans = [block_rows(total, len(files), k) for k in range(len(files))]  # their rows
    needed = [k for k, r in enumerate(spans) if r.start < mine.stop and r.stop > mine.start]
    problem: tuple[int, str] | None = None
    afters: set[int] = set()
    arrays: dict[str, list[tuple[int, np.ndarray]]] = {}
    for k in needed or [0]:
        try:
            after, members = _read_slab(files[k], spans[k].stop - spans[k].start, (k, len(files)))
        except _Damaged as exc:
            problem = (k, str(exc))
            break
        afters.add(after)
        for member, array in members.items():
            arrays.setdefault(member, []).append((spans[k].start, array))
    said = grid.comm.gather((problem, afters), root=0)
    verdict = None if said is None else _verdict(files, said)  # on rank 0
    verdict = grid.comm.bcast(verdict, root=0)
    if isinstance(verdict, str):
        raise _Damaged(verdict)
    return verdict, arrays


def _verdict(files: list[str], said: list[tuple[tuple[int, str] | None, set[int]]]) -> int | str:
    """The step the set of state slabs ``files`` ends, or what is wrong with it: its first
    slab that a rank found wrong (``said``, each rank's first problem and the steps its slabs
    end), or its slabs ending different steps."""
    problems = sorted(problem for problem, _ in said if problem is not None)
    if problems:
        return problems[0][1]
    afters = set().union(*(after for _, after in said))
    if len(afters) != 1:
        return f"{files[0]} and its other slabs end different steps"
    return afters.pop()


def _read_slab(where: str, rows: int, slab: tuple[int, int]) -> tuple[int, dict[str, np.ndarray]]:
    """The step the state slab ``where`` ends and its arrays, memory-mapped (``held``'s
    whole); every member's CRC checked, streamed.  :class:`_Damaged` when it is missing or
    cannot be used, its state has not ``rows`` rows, or it was written by another rank than
    ``slab`` (``(rank, size)``: the slabs swapped or renamed; a slab of an earlier version
    records none)."""
    if not os.path.exists(where):
        raise _Damaged(f"{where} is missing")
    try:
        with zipfile.ZipFile(where) as archive:
            bad = archive.testzip()
        if bad is not None:
            raise ValueError(f"{bad} fails its CRC")
        with np.load(where) as saved:
            after = int(saved["after_step"])
            writer = tuple(int(v) for v in saved["slab"]) if "slab" in saved.files else slab
            names = [m for m in saved.files if m not in ("after_step", "slab")]
            members = {"held": saved["held"]} if "held" in names else {}
        if writer != slab:
            raise ValueError(
                f"it holds the rows of rank {writer[0]} of {writer[1]}, not of rank {slab[0]} "
                "(swapped or renamed)"
            )
        members.update({m: mapped(where, m) for m in names if m != "held"})
        if len(members["state"]) != rows:
            raise ValueError(f"its state has {len(members['state'])} rows, not {rows}")
    except Exception as exc:  # a truncated or foreign file: any reader failure
        raise _Damaged(f"{where} is damaged ({_reason(exc)})") from None
    return after, members


def _same(a: Any, b: Any) -> bool:
    """Equal parameters; floats to 1e-9 relative (derived loads carry FFT rounding)."""
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) or isinstance(b, float):
        try:
            return bool(np.isclose(float(a), float(b), rtol=1e-9, atol=0.0))
        except (TypeError, ValueError):
            return False
    return a == b


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
        import h5py

        store = cls(path, grid, fields)
        store.steps = finished.steps
        store.digests = dict(finished.parts)
        stored = any(slab_of(HEIGHTS_PART, p) is not None for p in finished.parts)
        store.maps = heights is not None or filled is not None or stored
        if store.root:
            with h5py.File(store.partial, "r") as f:
                store.attributes = {k: v for k, v in f.attrs.items() if k != "parts"}
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

        def commit() -> None:
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

        self._on_root(commit)
        self.steps = step
        if state is not None:
            self._write_state(state, held, step)

    def _write_state(self, state: np.ndarray, held: Held | None, step: int) -> None:
        """Every rank saves its rows of the state after ``step`` and of the fields ``held``
        beside it (its slab of ``OUT.h5.state.npz``); after the first, the slabs another rank
        count left are removed (collective)."""
        comm = self.grid.comm
        kept: dict[str, Any] = {}
        if held is not None:
            kept["held"] = np.asarray(held.scalars, dtype=float)
            kept.update({f"held_field_{i}": slab for i, slab in enumerate(held.fields)})
        where = slab_name(state_path(self.path), comm.rank, comm.size)
        writer = np.array([comm.rank, comm.size])  # a swapped slab is known by it

        def save() -> None:
            with storage(where), replaced(where) as tmp, open(tmp, "wb") as f:
                np.savez(f, **kept, state=state, after_step=step - 1, slab=writer)

        on_every(comm, save)
        if self.fresh_state:
            self._on_root(lambda: _remove_states(self.path, keep=comm.size))
            self.fresh_state = False

    def finish(self) -> None:
        """Assemble ``OUT.h5`` (complete), rename it into place, remove the rest (collective)."""

        def assemble() -> None:
            self._check_parts()
            parts = [os.path.join(self.parts, p) for p in os.listdir(self.parts)]
            needed = sum(os.path.getsize(p) for p in [self.partial, *parts])
            check_room(os.path.dirname(os.path.abspath(self.path)), needed, self.path)
            table = csv_path(self.path)
            with storage(table), suppress(FileNotFoundError):
                os.remove(table)  # an earlier run's, never left beside this run's OUT.h5
            with atomic_h5(self.path, large=True) as f:
                write_attributes(f, {**self.attributes, "complete": True})
                self._write_table(f)
                if self.maps:
                    self._copy_maps(f)
                for name in self.fields:
                    self._copy_field(f, name)
                self._label_maps(f)
            self.assembled = True
            write_csv(table, self.table, self.steps)
            _clear(self.path, keep_steps=False)

        self._on_root(assemble)
        self.grid.comm.Barrier()

    def _check_parts(self) -> None:
        """:class:`StorageError` unless every part the run stores is there, as committed."""
        checks = [(HEIGHTS_PART, "writes it again")] if self.maps else []
        for k in range(1, self.steps + 1) if self.fields else ():
            checks.append((step_part(k), f"computes {_steps(k, self.steps)} again"))
        for name, redo in checks:
            wrong = part_problem(self.parts, name, self.digests)
            if wrong:
                raise StorageError(
                    errno.EIO, f"cannot assemble {self.path}: {wrong}; --resume {redo}"
                )

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

    def _entry(self, name: str) -> Entry:
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
        with atomic_h5(self.partial) as f:
            write_attributes(f, {**self.attributes, "parts": self.digests})
            self._write_table(f)

    def _write_table(self, f: Any) -> None:
        """The scalars of every step, on the dimension ``step`` (1, 2, ...)."""
        count = len(next(iter(self.table.values()), []))  # the steps committed with this table
        # contiguous columns (the table is rewritten whole at every commit): a chunked column's
        # index and 8 KB chunk made a study piece's file 300 KB instead of 80 KB
        step = f.create_dataset("step", data=np.arange(1, count + 1))
        describe(step, self._entry("step"))
        step.make_scale("step")
        for key, column in self.table.items():
            dtype = h5_dtype(column[0]) if column else np.float64
            values = np.array(column, dtype=dtype)
            d = f.create_dataset(key, data=values)
            describe(d, self._entry(key))
            d.dims[0].attach_scale(step)
            if values.ndim == 2:  # a per-step array: its second axis is a named dimension
                d.dims[1].attach_scale(self._scale(f, SECOND_DIMENSION[key], values.shape[1]))

    def _scale(self, f: Any, name: str, size: int) -> Any:
        """The dimension scale ``name`` (bins counted from 0; patch bins by their smallest
        size), made once."""
        if name not in f:
            values = 2 ** np.arange(size) if name == "patch_bin" else np.arange(size)
            scale = f.create_dataset(name, data=values)
            describe(scale, self._entry(name))
            scale.make_scale(name)
        return f[name]

    def _label_maps(self, f: Any) -> None:
        """The maps' dimensions ``x`` and ``y`` (pixel centres) and ``step``, as dimension
        scales, so that xarray and netCDF tools read labelled arrays."""
        maps = [name for name in ("heights", "filled") if name in f]
        if not maps and not self.fields:
            return
        scales = {}
        for name, values in zip(("x", "y"), self.grid.positions(), strict=True):
            scales[name] = f.create_dataset(name, data=values)
            describe(scales[name], self._entry(name))
            scales[name].make_scale(name)
        for map_name in maps:
            for axis, name in enumerate("xy"):
                f[map_name].dims[axis].attach_scale(scales[name])
        for field_name in self.fields:
            for axis, scale in enumerate((f["step"], scales["x"], scales["y"])):
                f[field_name].dims[axis].attach_scale(scale)

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
                        d = f.create_dataset(key, data=value[None], **_field_layout(value.shape))
                    else:
                        d = f.create_dataset(key, data=value)
                    describe(d, self._entry(key))

        on_every(comm, write)
        for digests in comm.gather(mine, root=0) or ():
            self.digests.update(digests)

    def _copy_maps(self, f: Any) -> None:
        """The heights, and a measured map's filled mask, into ``f``: the one part copied as
        it is, or its slabs' rows a band at a time."""
        import h5py

        files = slabs(HEIGHTS_PART, self.digests)
        for slab in files:
            rows = slab_rows(HEIGHTS_PART, slab, self.grid.shape[0])
            with h5py.File(os.path.join(self.parts, slab), "r") as part:
                for name in part:
                    if len(files) == 1:
                        f.copy(part[name], name)
                        continue
                    if name not in f:
                        out = f.create_dataset(name, self.grid.shape, dtype=part[name].dtype)
                        out.attrs.update(part[name].attrs)
                    for a, b in _bands(rows):
                        f[name][a:b] = part[name][a - rows.start : b - rows.start]

    def _copy_field(self, f: Any, name: str) -> None:
        """Stack every step's ``name`` into ``f``, slab by slab: their compressed chunks
        copied as they are where the slab's rows are whole chunks of ``f``'s (always on one
        rank), else a band of rows at a time."""
        import h5py

        nx, ny = self.grid.shape
        dtype = bool if name == "contact" else np.float64
        out = f.create_dataset(
            name, shape=(self.steps, nx, ny), maxshape=(None, nx, ny), dtype=dtype,
            **_field_layout((nx, ny)),
        )  # fmt: skip
        describe(out, self._entry(name))
        for k in range(self.steps):  # every part checked already (_check_parts)
            for slab in slabs(step_part(k + 1), self.digests):
                rows = slab_rows(step_part(k + 1), slab, nx)
                with h5py.File(os.path.join(self.parts, slab), "r") as part:
                    source = part[name]
                    if not _whole_chunks(source.chunks, out.chunks, rows, nx):
                        for a, b in _bands(rows):
                            out[k, a:b] = source[0, a - rows.start : b - rows.start]
                        continue
                    for i in range(source.id.get_num_chunks()):
                        info = source.id.get_chunk_info(i)
                        mask, data = source.id.read_direct_chunk(info.chunk_offset)
                        first, column = info.chunk_offset[1:]
                        out.id.write_direct_chunk((k, rows.start + first, column), data, mask)


def _whole_chunks(chunks: tuple[int, ...], into: tuple[int, ...], rows: slice, nx: int) -> bool:
    """Whether a slab of ``rows`` stored in ``chunks`` is whole chunks of a field stored in
    ``into``: the same chunks, starting on one, ending on one or on the grid's last row."""
    size = into[1]
    ends = rows.stop == nx or rows.stop % size == 0
    return tuple(chunks) == tuple(into) and rows.start % size == 0 and ends


def _bands(rows: slice) -> list[tuple[int, int]]:
    """``rows`` cut on the field chunks' row boundaries: the bands the assembly moves."""
    cuts = range((rows.start // FIELD_CHUNK + 1) * FIELD_CHUNK, rows.stop, FIELD_CHUNK)
    edges = [rows.start, *cuts, rows.stop]
    return list(zip(edges[:-1], edges[1:], strict=True))


def _maps(heights: np.ndarray | None, filled: np.ndarray | None) -> dict[str, np.ndarray]:
    """The maps a run stores (local slabs): its heights and a measured map's filled mask."""
    return {k: v for k, v in {"heights": heights, "filled": filled}.items() if v is not None}


def _field_layout(shape: tuple[int, ...]) -> dict[str, Any]:
    nx, ny = shape
    return {
        "chunks": (1, min(nx, FIELD_CHUNK), min(ny, FIELD_CHUNK)),
        "compression": "gzip",
        "compression_opts": 4,
        "shuffle": True,
    }


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
        table = _leftover_table(path)
        if table is not None:
            write_csv(csv_path(path), table, len(table["converged"]))
            _clear(path, keep_steps=False)


def _leftover_table(path: str) -> dict[str, list[Any]] | None:
    """The step table of ``path + '.partial'`` when it is what the writer of the complete
    ``path`` left behind (the same ``created`` stamp and steps), else ``None``."""
    import h5py

    try:
        with h5py.File(path, "r") as done, h5py.File(partial_path(path), "r") as left:
            if done.attrs.get("created") != left.attrs.get("created") or not done.attrs.get(
                "complete"
            ):
                return None
            table = _read_table(left)
            return table if (len(table["converged"]),) == done["converged"].shape else None
    except (OSError, KeyError):
        return None


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
    with suppress(FileNotFoundError):
        os.remove(partial_path(path))  # the record first
    _remove_states(path, keep=0)
    parts = parts_path(path)
    if os.path.isdir(parts) and not os.path.islink(parts):
        shutil.rmtree(parts, ignore_errors=True)
    else:  # a plain file of that name, which no run writes
        with suppress(FileNotFoundError):
            os.remove(parts)


def _remove_states(path: str, keep: int) -> None:
    """Remove the state slabs of output ``path`` but those written on ``keep`` ranks."""
    folder, name = os.path.split(os.path.abspath(state_path(path)))
    for entry in os.listdir(folder):
        found = slab_of(name, entry)
        if found is not None and found[1] != keep:
            with suppress(FileNotFoundError):
                os.remove(os.path.join(folder, entry))


def _make_folder(folder: str) -> None:
    """Make the parts' ``folder`` unless it is there (a plain file of its name is removed)."""
    if os.path.lexists(folder) and not os.path.isdir(folder):
        os.remove(folder)
    os.makedirs(folder, exist_ok=True)
