"""Signals that end a run: ``SIGTERM`` and ``SIGINT`` remembered as well as raised.

A signal handled by :func:`interrupt` is remembered, so that one whose ``KeyboardInterrupt``
Python drops (raised inside a finaliser) still ends the run at the next
:func:`check_interrupt`.
"""

from __future__ import annotations

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
