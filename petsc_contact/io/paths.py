"""Checks of the files a command reads and writes, before anything is computed or written.

An output must be a regular file or a new name, in no clash with another output or an input
(``--output`` naming ``/dev/null``, a folder, a FIFO or the heights file itself would replace
or corrupt it); an input must be a regular, readable, non-empty file.  Each check raises
``ValueError`` with one line that names the option and says what the path is.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Iterable

Named = tuple[str, str | None]  # (option, path): ("--output", "out.h5"); None: not given


def kind(path: str) -> str | None:
    """What ``path`` is when it is not a regular file (``a folder``, ``a device``, ``a FIFO``,
    ``a socket``), following links; ``None`` for a regular file or a name not in use."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return None
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    return "a FIFO" if stat.S_ISFIFO(mode) else "a socket"


def same_file(a: str, b: str) -> bool:
    """Whether ``a`` and ``b`` are one file: a hard link, a symbolic link, ``./x`` and ``x``
    (by device and inode when both exist, else by their resolved names)."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.realpath(a) == os.path.realpath(b)


def check_input(path: str, option: str) -> None:
    """``ValueError`` unless ``path`` is a regular, readable, non-empty file
    (``FileNotFoundError`` when it does not exist)."""
    if not path:
        raise ValueError(f"{option} names no file (it is empty)")
    if not os.path.exists(path):
        raise FileNotFoundError(f"{option} '{path}' does not exist")
    what = kind(path)
    if what is not None:
        raise ValueError(f"{option} '{path}' is {what}, not a regular file")
    if not os.access(path, os.R_OK):
        raise ValueError(f"{option} '{path}' is not readable")
    if os.path.getsize(path) == 0:
        raise ValueError(f"{option} '{path}' is empty")


def check_output(path: str, inputs: Iterable[Named] = (), option: str = "--output") -> None:
    """``ValueError`` unless ``path`` can be written as a regular file without replacing an
    input: not empty, not a folder, a device, a FIFO or a socket, and not the same file as
    any of ``inputs`` (``(option, path)`` pairs; a ``None`` path is skipped)."""
    if not path:
        raise ValueError(f"give an output file name ({option} is empty)")
    what = kind(path) or ("a folder" if path.endswith(("/", os.sep)) else None)  # x.h5/
    if what is not None:
        raise ValueError(f"{option} '{path}' is {what}, not a regular file")
    for name, given in inputs:
        if given and same_file(path, given):
            raise ValueError(f"{option} '{path}' is the same file as {name} '{given}'")


def check_outputs(outputs: Iterable[Named], inputs: Iterable[Named] = ()) -> None:
    """:func:`check_output` for each of ``outputs`` (``(option, path)`` pairs, derived names
    such as ``OUT.csv`` among them), and ``ValueError`` if two of them are one file."""
    given = [(name, path) for name, path in outputs if path is not None]
    sources = list(inputs)
    for i, (name, path) in enumerate(given):
        check_output(path, sources, name)
        for other, earlier in given[:i]:
            if same_file(path, earlier):
                raise ValueError(f"{name} '{path}' is the same file as {other} '{earlier}'")
