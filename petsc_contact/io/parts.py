"""The checksums of a run's parts (``OUT.h5.parts/``): what an interrupted run's parts can
still give, checked against the SHA-256 each commit recorded; and the row slabs they come in.

A run on ``P > 1`` ranks writes every array as ``P`` slabs, each rank its own rows
(:func:`~petsc_contact.conventions.grid.block_rows`) in its own file: part ``step-000001.h5``
is ``step-000001.0of4.h5`` to ``step-000001.3of4.h5`` (:func:`slab_name`), each with its own
SHA-256, and the resume state ``OUT.h5.state.npz`` is ``OUT.h5.state.0of4.npz`` to
``OUT.h5.state.3of4.npz``.  A one-rank run writes the one file of the plain name.  A part is
sound when every slab its commit recorded is there with its bytes (:func:`part_problem`); a
saved state is read a rank's rows at a time (:class:`SlabRows`), on any rank count."""

from __future__ import annotations

import os
import re
import struct
import zipfile
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..conventions.grid import block_rows
from .atomic import _reason
from .names import HEIGHTS_PART, parts_path, step_part
from .provenance import file_digest

if TYPE_CHECKING:
    from .store import Finished


@dataclass
class PartsCheck:
    """What the part files of an interrupted run can give (:func:`check_parts`)."""

    steps: int  # the finished steps whose parts are sound: the steps after are computed again
    maps: bool  # heights.h5 is missing or damaged: it is written again
    problem: str = ""  # what is wrong and what is done about it, in words ("" when nothing)


def check_parts(path: str, finished: Finished, maps: bool, fields: bool) -> PartsCheck:
    """Check the parts of an interrupted run on output ``path`` against the checksums their
    commits recorded: ``heights.h5`` where the run stores ``maps``, each finished step's
    where it stores ``fields`` (up to the first that is missing or damaged); nothing when no
    step is finished (the run starts afresh).

    A part of a ``.partial`` of an earlier version, which records no checksums, is accepted
    when every dataset in it can be read."""
    folder, digests, steps = parts_path(path), finished.parts, finished.steps
    if not steps:  # the run starts afresh
        return PartsCheck(0, False)
    said = []
    heights = part_problem(folder, HEIGHTS_PART, digests) if maps else ""
    if heights:
        said.append(f"{heights}: it is written again from the run's heights")
    for k in range(1, finished.steps + 1) if fields else ():
        wrong = part_problem(folder, step_part(k), digests)
        if wrong:
            said.append(f"{wrong}: computing {_steps(k, steps)} again")
            steps = k - 1
            break
    return PartsCheck(steps, bool(heights), "; ".join(said))


def _steps(first: int, last: int) -> str:
    """``step 4`` or ``steps 2 to 4``."""
    return f"step {first}" if first == last else f"steps {first} to {last}"


def slab_name(name: str, rank: int, size: int) -> str:
    """The file of rank ``rank``'s slab of ``name`` on ``size`` ranks: ``name`` itself on
    one rank, else ``stem.RofP.ext`` (``step-000001.2of4.h5``)."""
    if size == 1:
        return name
    stem, ext = os.path.splitext(name)
    return f"{stem}.{rank}of{size}{ext}"


def slab_of(name: str, slab: str) -> tuple[int, int] | None:
    """``(rank, size)`` when file ``slab`` is a slab of ``name`` (``(0, 1)`` for ``name``
    itself), else ``None``."""
    if slab == name:
        return 0, 1
    stem, ext = os.path.splitext(name)
    found = re.fullmatch(rf"{re.escape(stem)}\.(\d+)of(\d+){re.escape(ext)}", slab)
    return (int(found.group(1)), int(found.group(2))) if found else None


def slabs(name: str, digests: dict[str, str]) -> list[str]:
    """The files part ``name`` was committed as (by ``digests``), its slabs in rank order;
    ``[name]`` when its commit recorded none (an earlier version's part, or one never
    committed)."""
    found = sorted((where, file) for file in digests if (where := slab_of(name, file)) is not None)
    if not found:
        return [name]
    size = found[0][0][1]
    return [slab_name(name, rank, size) for rank in range(size)]  # a missing one is reported


def slab_rows(name: str, slab: str, rows: int) -> slice:
    """The global rows (of ``rows``) that file ``slab`` of part ``name`` holds."""
    rank, size = slab_of(name, slab) or (0, 1)
    return block_rows(rows, size, rank)


def part_problem(folder: str, name: str, digests: dict[str, str]) -> str:
    """What is wrong with part ``name`` of ``folder`` ("" when nothing): one of its slabs
    (:func:`slabs`) missing, unreadable, or its bytes are not those its commit recorded in
    ``digests`` (damaged, or another step's).  Without a recorded checksum every dataset in
    it must be readable."""
    for slab in slabs(name, digests):
        wrong = _slab_problem(folder, slab, digests)
        if wrong:
            return wrong
    return ""


def _slab_problem(folder: str, name: str, digests: dict[str, str]) -> str:
    """What is wrong with the file ``name`` of ``folder`` ("" when nothing)."""
    path = os.path.join(folder, name)
    if not os.path.isfile(path):
        return f"{path} is missing"
    try:
        if name not in digests:
            _read_whole(path)
        elif file_digest(path) != digests[name]:
            return f"{path} does not match the checksum its commit recorded (damaged or replaced)"
    except Exception as exc:  # a truncated or foreign file: any reader failure
        return f"{path} cannot be read ({_reason(exc)})"
    return ""


def _read_whole(path: str) -> None:
    """Read every dataset of an HDF5 file: an error when one cannot be read."""
    import h5py

    with h5py.File(path, "r") as f:
        for name in f:
            np.asarray(f[name])


class SlabRows:
    """A field of a saved state, held in row slabs of uncompressed ``.npz`` files and read a
    rank's rows at a time (a :class:`~petsc_contact.conventions.grid.RowSource`): nothing is
    read until rows are asked for, and then only those rows, from the slabs that hold them.

    Parameters
    ----------
    slabs
        The first global row and the array, memory-mapped (:func:`mapped`), of each slab this
        rank may read: those that hold its rows.
    rows
        The global field's rows.
    """

    def __init__(self, slabs: list[tuple[int, np.ndarray]], rows: int) -> None:
        self.slabs = slabs
        self.shape: tuple[int, ...] = (rows, *slabs[0][1].shape[1:])

    def __getitem__(self, rows: slice) -> np.ndarray:
        start, stop, _ = rows.indices(self.shape[0])
        pieces = [
            array[max(start - first, 0) : min(stop - first, len(array))]
            for first, array in self.slabs
            if first < stop and first + len(array) > start
        ]
        return np.concatenate(pieces) if pieces else np.empty((0, *self.shape[1:]))


LOCAL_HEADER = b"PK\x03\x04"  # a zip member's local header: 30 bytes, its name, its extra


def mapped(where: str, member: str) -> np.ndarray:
    """Array ``member`` of the ``.npz`` file ``where`` (written by ``np.savez``, its members
    stored uncompressed), memory-mapped: its rows are read from disk when sliced.  An
    ``OSError`` or ``ValueError`` when it is not there as such."""
    with zipfile.ZipFile(where) as archive:
        info = archive.getinfo(f"{member}.npy")
    if info.compress_type != zipfile.ZIP_STORED:
        raise ValueError(f"{member} is compressed in {where}")
    with open(where, "rb") as f:
        f.seek(info.header_offset)
        header = f.read(30)
        if header[:4] != LOCAL_HEADER:
            raise ValueError(f"no zip header for {member} in {where}")
        name, extra = struct.unpack("<HH", header[26:30])
        f.seek(info.header_offset + 30 + name + extra)
        version = np.lib.format.read_magic(f)
        read = np.lib.format.read_array_header_1_0
        if version != (1, 0):
            read = np.lib.format.read_array_header_2_0
        shape, fortran, dtype = read(f)
        offset = f.tell()
    if fortran:
        raise ValueError(f"{member} of {where} is not a C-ordered array")
    return np.memmap(where, dtype=dtype, mode="r", offset=offset, shape=shape)
