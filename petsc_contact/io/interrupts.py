"""Signals that end a run: ``SIGTERM`` and ``SIGINT`` remembered as well as raised.

A signal handled by :func:`interrupt` is remembered, so that one whose ``KeyboardInterrupt``
Python drops (raised inside a finaliser) still ends the run at the next
:func:`check_interrupt`.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

_SIGNALLED: list[int] = []  # the signals :func:`interrupt` received


def interrupt(signum: int, frame: Any) -> None:
    """A handler of ``SIGTERM`` and ``SIGINT``: remember the signal, raise ``KeyboardInterrupt``.

    Python prints and drops an exception raised inside a finaliser (``Exception ignored
    in ...``); :func:`check_interrupt` raises it again at the next point that matters."""
    _SIGNALLED.append(signum)
    raise KeyboardInterrupt


def check_interrupt() -> None:
    """Raise ``KeyboardInterrupt`` when :func:`interrupt` was called, even where its own
    exception was dropped."""
    if _SIGNALLED:
        raise KeyboardInterrupt


def forget_interrupts() -> None:
    """Forget the signals received (a process that runs several commands, between them)."""
    _SIGNALLED.clear()


@contextmanager
def interruptible() -> Iterator[None]:
    """Within the block, ``SIGTERM`` and ``SIGINT`` are handled by :func:`interrupt` where
    their handlers are Python's defaults (``SIGTERM`` would end the process at once), so
    that a library call ends as a run does on the command line: its work kept, an exception
    raised.  The handlers, and the signals they remembered, are restored when the block ends; a
    handler of the caller's own, and a thread other than the main one, are left alone."""
    defaults = {signal.SIGTERM: signal.SIG_DFL, signal.SIGINT: signal.default_int_handler}
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = {signum: signal.getsignal(signum) for signum in defaults}
    taken = [signum for signum, handler in before.items() if handler == defaults[signum]]
    remembered = len(_SIGNALLED)
    for signum in taken:
        signal.signal(signum, interrupt)
    try:
        yield
    finally:
        for signum in taken:
            signal.signal(signum, before[signum])
        # what the block's own handlers remembered; a caller's handler keeps what it did
        _SIGNALLED[remembered:] = [s for s in _SIGNALLED[remembered:] if s not in taken]
