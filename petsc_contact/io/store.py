"""Durable run files: one writer per output, every finished step on disk whatever happens.

While a run with output ``OUT.h5`` is under way, rank 0 keeps beside it:

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
    compressed once, as the final file holds them.  The commit records each part's SHA-256
    (the ``.partial``'s attribute ``parts``); a part is used only when its bytes match it.
``OUT.h5.state.npz``
    the solution the next step starts from (``after_step`` says which step it ends), written
    after the commit; a resume that finds it missing, damaged or stale starts the next step
    from first touch (the same result to the solver's tolerance, at a different cost).

When the run ends, every part is checked against its checksum, ``OUT.h5`` is assembled
from them (the fields' compressed chunks copied as they are), written to a temporary name and
renamed into place, then its step table ``OUT.csv`` is written, and the rest is removed.  An
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
from contextlib import suppress
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..physics.continuation import Held
from .atomic import StorageError, _reason, atomic_h5, check_room, on_root, replaced, storage
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
from .parts import PartsCheck, _steps, check_parts, part_problem
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
    from ..conventions.grid import Grid

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
    state: np.ndarray | None = None
    state_problem: str = ""  # why the state could not be used ("" when it can)
    held: Held | None = None  # what the sweep held beside the state (whole fields)
    parts: dict[str, str] = field(default_factory=dict)  # the parts' SHA-256 at their commit
    rewrite_maps: bool = False  # heights.h5 is missing or damaged: the run writes it again

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


def read_resume(path: str, parameters: dict[str, Any]) -> Finished:
    """The finished steps of an interrupted run ``path + '.partial'``, its scalars, and the
    state to go on from.

    Returns ``Finished(0)`` when there is nothing to resume.  Raises ``ValueError`` when the
    partial file belongs to a different run (its ``parameters`` differ, apart from
    :data:`RESUME_FREE`), so a resume never mixes two runs, or when it
    cannot be read (damaged by something else than a run: the run itself replaces it whole).
    """
    import h5py

    partial = partial_path(path)
    if not os.path.exists(partial):
        return Finished(0)
    try:
        with h5py.File(partial, "r") as f:
            theirs = json.loads(f.attrs["parameters"])
            parts = json.loads(f.attrs.get("parts", "{}"))  # none in earlier versions' files
            table = _read_table(f)
            steps = len(table.get("converged", []))
    except (OSError, KeyError, ValueError) as exc:
        raise ValueError(
            f"cannot resume '{partial}': it is damaged ({_reason(exc)}); --overwrite starts afresh"
        ) from None
    check_same_run(partial, theirs, parameters)
    state, held, problem = _saved_state(path, steps)
    return Finished(steps, table, state, problem, held, parts)


def _read_table(f: Any) -> dict[str, list[Any]]:
    """The per-step datasets of a run's open HDF5 file ``f``, as lists."""
    return {
        k: list(_values(f[k]))
        for k in f
        if k not in COORDINATES and f[k].ndim >= 1 and f[k].shape[0] == f["step"].shape[0]
    }


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


RESUME_FREE = ("resume", "overwrite", "quiet", "stop_after", "device")
"""The options a resume may change: none changes the result (a device, its rounding only:
a run paused on a GPU goes on on the CPU; the ``resumed`` list records each part's)."""


def check_same_run(partial: str, theirs: dict[str, Any], mine: dict[str, Any]) -> None:
    """``ValueError`` unless an unfinished file's ``parameters`` are this run's (apart from
    :data:`RESUME_FREE`): a resume never mixes two runs."""
    a = json.loads(json.dumps({k: v for k, v in mine.items() if k not in RESUME_FREE}))
    b = {k: v for k, v in theirs.items() if k not in RESUME_FREE}
    changed = sorted(k for k in set(a) | set(b) if not _same(a.get(k), b.get(k)))
    if changed:
        raise ValueError(
            f"cannot resume '{partial}': it was run with different parameters "
            f"({', '.join(changed)})"
        )


def _values(dataset: Any) -> np.ndarray:
    values = dataset[...]
    if values.dtype.kind == "O":
        return np.array([v.decode() if isinstance(v, bytes) else v for v in values], dtype=object)
    return values


def _saved_state(path: str, steps: int) -> tuple[np.ndarray | None, Held | None, str]:
    """The state after step ``steps`` and what the sweep held beside it (``None`` in a state
    file of an earlier version), or ``None`` and why not."""
    where = state_path(path)
    if not steps:
        return None, None, ""
    if not os.path.exists(where):
        return None, None, f"{where} is missing"
    try:
        with np.load(where) as saved:
            after, state = int(saved["after_step"]), saved["state"]
            held = None
            if "held" in saved:
                count = sum(name.startswith("held_field_") for name in saved.files)
                fields = tuple(saved[f"held_field_{i}"] for i in range(count))
                held = Held(saved["held"], fields)
    except Exception as exc:  # a truncated or foreign file: any reader failure
        return None, None, f"{where} is damaged ({_reason(exc)})"
    if after + 1 != steps:
        return None, None, f"{where} is of step {after + 1}, not {steps}"
    return state, held, ""


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

    Rank 0 writes; the other ranks join the gathers of fields and state, and every rank
    raises the same :class:`StorageError` when rank 0 cannot write.

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
        full = _gathered(grid, heights, filled)  # collective
        store.attributes = {**attributes, "created": _now(), "complete": False}

        def begin() -> None:
            _clear(path, keep_steps=False)
            os.makedirs(store.parts)
            try:
                if store.maps:
                    store._write_part(HEIGHTS_PART, full, chunked=False)
                store._commit()
            except BaseException:
                _clear(path, keep_steps=False)  # nothing was finished: nothing is left
                raise

        store._on_root(begin)
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
        store.maps = heights is not None or filled is not None or HEIGHTS_PART in finished.parts
        full = _gathered(grid, heights, filled) if finished.rewrite_maps else {}  # collective
        if store.root:
            with h5py.File(store.partial, "r") as f:
                store.attributes = {k: v for k, v in f.attrs.items() if k != "parts"}
            store.table = {k: list(v) for k, v in finished.table.items()}
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
            if full:
                store._write_part(HEIGHTS_PART, full, chunked=False)
            store._commit()

        store._on_root(begin)
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
        (collective)."""
        gathered: dict[str, Any] = (
            {k: self.grid.gather(fields[k]) for k in self.fields} if fields else {}
        )
        full_state = self.grid.gather(state) if state is not None else None
        kept: dict[str, Any] = {}
        if held is not None:
            kept["held"] = np.asarray(held.scalars, dtype=float)
            for i, slab in enumerate(held.fields):
                kept[f"held_field_{i}"] = self.grid.gather(slab)
        step = self.steps + 1

        def commit() -> None:
            if gathered:
                self._write_part(step_part(step), gathered, chunked=True)
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
            self.steps = step
            if full_state is not None:
                where = state_path(self.path)
                with storage(where), replaced(where) as tmp, open(tmp, "wb") as f:
                    np.savez(f, **kept, state=full_state, after_step=step - 1)

        self._on_root(commit)
        self.steps = step

    def finish(self) -> None:
        """Assemble ``OUT.h5`` (complete), rename it into place, remove the rest (collective)."""

        def assemble() -> None:
            import h5py

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
                    with h5py.File(os.path.join(self.parts, HEIGHTS_PART), "r") as part:
                        for name in part:  # the heights, and a measured map's filled mask
                            f.copy(part[name], name)
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
        """Write part ``name``; its checksum goes into the next commit."""
        with atomic_h5(os.path.join(self.parts, name), digests=self.digests) as f:
            for key, value in arrays.items():
                if chunked:
                    d = f.create_dataset(key, data=value[None], **_field_layout(value.shape))
                else:
                    d = f.create_dataset(key, data=value)
                describe(d, self._entry(key))

    def _copy_field(self, f: Any, name: str) -> None:
        """Stack every step's ``name`` into ``f``, copying its compressed chunks as they are."""
        import h5py

        nx, ny = self.grid.shape
        dtype = bool if name == "contact" else np.float64
        out = f.create_dataset(
            name, shape=(self.steps, nx, ny), maxshape=(None, nx, ny), dtype=dtype,
            **_field_layout((nx, ny)),
        )  # fmt: skip
        describe(out, self._entry(name))
        for k in range(self.steps):  # every part checked already (_check_parts)
            with h5py.File(os.path.join(self.parts, step_part(k + 1)), "r") as part:
                source = part[name].id
                for i in range(source.get_num_chunks()):
                    info = source.get_chunk_info(i)
                    mask, data = source.read_direct_chunk(info.chunk_offset)
                    out.id.write_direct_chunk((k, *info.chunk_offset[1:]), data, mask)


def _gathered(grid: Grid, heights: np.ndarray | None, filled: np.ndarray | None) -> dict[str, Any]:
    """The maps a run stores, whole on rank 0 (``None`` elsewhere; collective)."""
    maps = {"heights": heights, "filled": filled}
    return {k: grid.gather(v) for k, v in maps.items() if v is not None}


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


def _clear(path: str, keep_steps: bool) -> None:
    """Remove what runs on output ``path`` left: temporary files of killed writers always
    (the step table's too),
    the committed steps (``.partial``, parts, state) unless ``keep_steps``.  Only the holder
    of the output's lock calls this."""
    folder, name = os.path.split(os.path.abspath(path))
    table = os.path.basename(csv_path(path))
    pattern = re.compile(
        rf"({re.escape(name)}(\.partial|\.state\.npz)?|{re.escape(table)})\.\d+\.tmp"
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
    for leftover in (partial_path(path), state_path(path)):  # the record first
        with suppress(FileNotFoundError):
            os.remove(leftover)
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
