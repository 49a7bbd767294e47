"""The exclusive right to write an output for a whole run: ``OUT.h5.lock``, held with
``flock`` from before anything of the output is touched to the run's end."""

from __future__ import annotations

import errno
import os
import socket
import time
from contextlib import suppress

from .atomic import StorageError, storage
from .names import LOCK


class OutputBusy(ValueError):
    """Another run is writing the same output: ``output``, and ``holder``, the holder's own
    words (process, host, since when)."""

    def __init__(self, output: str, holder: str) -> None:
        super().__init__(
            f"'{output}' is being written by another run ({holder}): wait for it to end, or "
            "choose another --output"
        )
        self.output, self.holder = output, holder

    def __reduce__(self) -> tuple[type[OutputBusy], tuple[str, str]]:  # sent between ranks
        return OutputBusy, (self.output, self.holder)


def check_writable(path: str, what: str = "output") -> None:
    """Raise :class:`StorageError` with a one-line reason unless ``path`` can be created
    (``ValueError`` for an empty name); ``what`` names the file in it (``--plot's``)."""
    if not path:
        raise ValueError("give an output file name (--output is empty)")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise StorageError(errno.ENOENT, f"{what} folder '{folder}' does not exist")
    if not os.access(folder, os.W_OK):
        raise StorageError(errno.EACCES, f"{what} folder '{folder}' is not writable")
    if os.path.isdir(path):
        raise StorageError(errno.EISDIR, f"{what} path '{path}' is a folder")


class OutputLock:
    """The exclusive right to write an output, held for a whole run (``path + '.lock'``).

    Taken before anything of the output is touched; :class:`OutputBusy` names the holder when
    another process has it.  Only rank 0 of a run takes it.
    """

    def __init__(self, path: str) -> None:
        self.output = path
        self.path = path + LOCK
        self.fd: int | None = None

    def acquire(self) -> None:
        import fcntl

        while True:
            with storage(self.path):
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.read(fd, 512).decode(errors="replace").strip() or "starting"
                os.close(fd)
                raise OutputBusy(self.output, holder) from None
            try:  # the file we locked may have been removed by the holder we waited for
                mine = os.fstat(fd).st_ino == os.stat(self.path).st_ino
            except FileNotFoundError:
                mine = False
            if mine:
                break
            os.close(fd)
        try:
            with storage(self.path):
                os.ftruncate(fd, 0)
                os.write(
                    fd, f"pid {os.getpid()} on {socket.gethostname()}, since {_now()}".encode()
                )
        except StorageError:  # a full disk: nothing is left behind
            with suppress(OSError):
                os.remove(self.path)
            os.close(fd)
            raise
        self.fd = fd

    def release(self) -> None:
        if self.fd is not None:
            with suppress(OSError):
                os.remove(self.path)
            os.close(self.fd)
            self.fd = None

    def __enter__(self) -> OutputLock:
        self.acquire()
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


def _now() -> str:
    """The local time, to the second, with its offset from UTC (ISO 8601)."""
    return time.strftime("%Y-%m-%dT%H:%M:%S%z")
