"""The ``.partial`` file: what a writer has finished, committed whole, read back and checked.

A writer with output ``OUT.h5`` (a run, each of a study's pieces, a comparison) keeps what
it has finished in ``OUT.h5.partial`` until ``OUT.h5`` is written: the record (its
``parameters``, the ``created`` stamp, the map's ``heights_sha256``, ``complete`` false) and
what is finished (a run's step table and its parts' SHA-256, ``parts``; a comparison's
group per solver).  :func:`commit` replaces it whole each time something is finished: it is
written to a temporary name and renamed over the last one
(:func:`~petsc_contact.io.atomic.atomic_h5`), so whatever instant the writer dies at, the
file is the last commit or the one before, never a torn one.  It is the commit point:
something is finished when it is in this file.

Every reader of a ``.partial`` goes through this module (:func:`opened`,
:func:`read_committed`, :func:`read_attributes`, :func:`committed_steps`,
:func:`leftover_table`), and so does every check that what a file kept is this run's
(:func:`check_same_run`, :func:`check_same_input`, :func:`check_nothing_lost`).
"""

from __future__ import annotations

import json
import os
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..conventions.warnings import ResumeWarning, user_level
from ..substrates.layer import DEFAULT_POISSON
from .atomic import _reason, atomic_h5
from .names import partial_path
from .schema import COORDINATES, h5_dtype, write_attributes

RESUME_FREE = ("resume", "overwrite", "quiet", "stop_after", "device")
"""The options a resume may change: none changes the result (a device, its rounding only:
a run paused on a GPU goes on on the CPU; the ``resumed`` list records each part's)."""


RECORDED_SINCE = {
    "base": "bonded",
    "cut_from": 1,
    "flat_stiffness": "grid",
    "footprint": "square",
    "options_prefix": "",
    "override_metadata": False,
    "poisson": DEFAULT_POISSON,
    "skip_memory_check": False,
    "thickness": None,
}
"""Parameters that files of earlier versions do not record, each with the value every run of
those versions had (each option came with that behaviour as its default): a file without one
is compared as if it recorded that value, so a study or a resume goes on across an upgrade,
and a run that sets another value is still refused."""


def commit(path: str, attributes: dict[str, Any], write: Callable[[Any], None]) -> None:
    """Replace output ``path``'s ``.partial`` whole by one holding ``attributes``
    (:func:`~petsc_contact.io.schema.write_attributes`) and what ``write(f)`` adds to the
    new file ``f``: the commit point.  A failure to write is a
    :class:`~petsc_contact.io.atomic.StorageError` that leaves the last commit in place."""
    with atomic_h5(partial_path(path)) as f:
        write_attributes(f, attributes)
        write(f)


def discard(path: str) -> None:
    """Remove output ``path``'s ``.partial`` (there may be none)."""
    with suppress(FileNotFoundError):
        os.remove(partial_path(path))


@contextmanager
def opened(path: str, locking: bool = True) -> Iterator[Any]:
    """The run file ``path`` (a ``.partial``, or a complete output of the same record), open
    for reading; without HDF5's file ``locking`` where a writer may be committing it (a
    commit renames a new file over it, never writes into the one read)."""
    import h5py

    with h5py.File(path, "r", locking=locking) as f:
        yield f


def read_attributes(path: str) -> dict[str, Any]:
    """The attributes of the run file ``path`` (a ``.partial`` or a complete output)."""
    with opened(path) as f:
        return dict(f.attrs.items())


@dataclass
class Committed:
    """What a run file (a ``.partial``, or a complete output) records: its attributes and
    its step table (each per-step dataset, as a list)."""

    attributes: dict[str, Any]
    table: dict[str, list[Any]]

    @property
    def parameters(self) -> dict[str, Any]:
        """The run's parameters (``KeyError`` or ``ValueError`` when it records none)."""
        return dict(json.loads(self.attributes["parameters"]))

    @property
    def digest(self) -> Any:
        """The SHA-256 of the run's map (``None`` where it records none)."""
        return self.attributes.get("heights_sha256")

    @property
    def parts(self) -> dict[str, str]:
        """The SHA-256 of each part at its commit (none in earlier versions' files)."""
        return dict(json.loads(self.attributes.get("parts", "{}")))

    @property
    def steps(self) -> int:
        """The steps its table holds."""
        return len(self.table.get("converged", []))


def read_committed(path: str) -> Committed:
    """The attributes and step table of the run file ``path`` (``OSError`` or ``KeyError``
    when it cannot be read)."""
    with opened(path) as f:
        return Committed(dict(f.attrs.items()), read_table(f))


def step_columns(table: dict[str, list[Any]]) -> dict[str, np.ndarray]:
    """The step table's columns as arrays of their HDF5 dtypes, ``step`` (1, 2, ...) first."""
    count = len(next(iter(table.values()), []))  # the steps committed with this table
    columns = {"step": np.arange(1, count + 1)}
    for key, column in table.items():
        columns[key] = np.array(column, dtype=h5_dtype(column[0]) if column else np.float64)
    return columns


def write_steps(f: Any, table: dict[str, list[Any]]) -> None:
    """The step table of a ``.partial``: bare contiguous datasets, one per column, without
    the units, descriptions and dimension scales that the complete output labels them with
    (:func:`~petsc_contact.io.assemble.write_table`): each commit writes the table whole,
    and those labels made most of its cost."""
    for key, values in step_columns(table).items():
        f.create_dataset(key, data=values)


def read_table(f: Any) -> dict[str, list[Any]]:
    """The per-step datasets of a run's open HDF5 file ``f``, as lists: a ``.partial``'s
    bare columns (:func:`write_steps`) or the labelled ones of a complete output or of an
    earlier version's ``.partial`` alike."""
    return {
        k: list(_values(f[k]))
        for k in f
        if k not in COORDINATES and f[k].ndim >= 1 and f[k].shape[0] == f["step"].shape[0]
    }


def _values(dataset: Any) -> np.ndarray:
    values = dataset[...]
    if values.dtype.kind == "O":
        return np.array([v.decode() if isinstance(v, bytes) else v for v in values], dtype=object)
    return values


def committed_steps(partial: str, locking: bool = True) -> int:
    """The finished steps an unfinished file holds (an ``OSError`` when it cannot be read);
    ``locking`` as :func:`opened`'s."""
    with opened(partial, locking) as f:
        return int(f["converged"].shape[0]) if "converged" in f else 0


def leftover_table(path: str) -> dict[str, list[Any]] | None:
    """The step table of ``path + '.partial'`` when it is what the writer of the complete
    ``path`` left behind (the same ``created`` stamp and steps), else ``None``."""
    try:
        with opened(path) as done, opened(partial_path(path)) as left:
            if done.attrs.get("created") != left.attrs.get("created") or not done.attrs.get(
                "complete"
            ):
                return None
            table = read_table(left)
            return table if (len(table["converged"]),) == done["converged"].shape else None
    except (OSError, KeyError):
        return None


def check_nothing_lost(path: str) -> None:
    """``ValueError`` when a new run on output ``path`` would delete finished steps: those an
    interrupted run kept in ``path + '.partial'`` (``--resume`` continues it, ``--overwrite``
    deletes them), or a ``.partial`` that cannot be read.  The ``.partial`` of a finished run
    left beside its complete ``path`` holds nothing that is not in ``path``."""
    partial = partial_path(path)
    if not os.path.exists(partial) or leftover_table(path) is not None:
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
