"""Writes that never leave a torn file: a file is written under a temporary name and renamed
into place when whole, and every failure to write is one :class:`StorageError` naming the
file and the system's reason.  :func:`on_root` runs a write on rank 0 and raises its
failure on every rank; :func:`on_every` runs each rank's own write and raises any rank's
failure on every rank."""

from __future__ import annotations

import errno
import hashlib
import os
import re
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from typing import Any


class StorageError(OSError):
    """Results could not be written (disk full, read-only, an I/O error)."""


def _reason(exc: BaseException) -> str:
    """A write failure in words, with the system's reason when HDF5 buries it in its text."""
    code = getattr(exc, "errno", None)
    if not code:
        found = re.search(r"errno = (\d+)", str(exc))
        code = int(found.group(1)) if found else None
    text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    return os.strerror(code) if code else text


@contextmanager
def storage(what: str) -> Iterator[None]:
    """Raise any write failure inside the block as :class:`StorageError` naming ``what``."""
    try:
        yield
    except StorageError:
        raise
    except (OSError, RuntimeError) as exc:
        code = getattr(exc, "errno", None) or errno.EIO
        raise StorageError(code, f"cannot write {what}: {_reason(exc)}") from None


@contextmanager
def replaced(path: str) -> Iterator[str]:
    """A temporary name to write ``path`` under; renamed over ``path`` when the block ends
    without an error, removed when it fails."""
    temporary = f"{path}.{os.getpid()}.tmp"
    try:
        yield temporary
        os.replace(temporary, path)
    except BaseException:
        with suppress(OSError):
            os.remove(temporary)
        raise


@contextmanager
def atomic_h5(
    path: str, large: bool = False, digests: dict[str, str] | None = None
) -> Iterator[Any]:
    """An HDF5 file written whole under a temporary name and renamed to ``path`` only when
    complete; a failure to write raises :class:`StorageError` and leaves ``path`` as it was.

    The file is made in memory and its bytes written by Python, so that a full disk fails
    in Python's ``write``, never inside HDF5 (whose objects, left half-closed by a failed
    write, crash the process when HDF5 closes them at exit).  A ``large`` file (a run's
    assembled output) is written by HDF5 itself, after a check that the disk has room for
    it (:func:`check_room`).  ``digests``, when given, gains the SHA-256 of the bytes written
    under the file's name (not for a ``large`` file)."""
    import io

    import h5py

    if large:
        with storage(path), replaced(path) as temporary, h5py.File(temporary, "w") as f:
            yield f
        return
    image = io.BytesIO()
    with h5py.File(image, "w") as f:
        yield f
    data = image.getbuffer()
    with storage(path), replaced(path) as temporary, open(temporary, "wb") as out:
        out.write(data)
    if digests is not None:
        digests[os.path.basename(path)] = hashlib.sha256(data).hexdigest()


def check_room(folder: str, needed: int, what: str) -> None:
    """:class:`StorageError` (no space) unless ``folder``'s disk has ``needed`` bytes free,
    with a margin of a tenth."""
    stats = os.statvfs(folder)
    free = stats.f_bavail * stats.f_frsize
    if free < 1.1 * needed:
        raise StorageError(
            errno.ENOSPC,
            f"cannot write {what}: {os.strerror(errno.ENOSPC)} ({needed / 2**20:.3g} MiB "
            f"needed, {free / 2**20:.3g} MiB free)",
        )


def on_root(comm: Any, work: Any) -> None:
    """Run ``work`` on rank 0 of ``comm``; when it fails, every rank raises (the others a
    :class:`StorageError`, or a ``RuntimeError`` naming rank 0's failure), so that no rank
    waits for one that has stopped."""
    failure: BaseException | None = None
    if comm.rank == 0:
        try:
            work()
        except Exception as exc:
            failure = exc
    if comm.size > 1:
        said = comm.bcast(None if failure is None else _portable(failure, 0), root=0)
        if said is not None and failure is None:
            failure = said
    if failure is not None:
        raise failure


def on_every(comm: Any, work: Any) -> None:
    """Run ``work`` on every rank of ``comm`` (each writing its own file); when it fails on
    any rank, every rank raises the failure of the first that failed (collective)."""
    failure: BaseException | None = None
    try:
        work()
    except Exception as exc:
        failure = exc
    if comm.size > 1:
        said = comm.allgather(None if failure is None else _portable(failure, comm.rank))
        first = next((s for s in said if s is not None), None)
        if failure is None:
            failure = first
    if failure is not None:
        raise failure


def _portable(exc: BaseException, rank: int) -> BaseException:
    """An exception every rank can raise (pickled through MPI)."""
    if isinstance(exc, StorageError):
        return StorageError(exc.errno, exc.strerror or str(exc))
    return RuntimeError(f"rank {rank} failed to write results: {type(exc).__name__}: {exc}")
