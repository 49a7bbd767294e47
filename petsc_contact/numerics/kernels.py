"""Compiling the package's numba kernels once, before any step: the ``cpu`` device's
whole-field passes (:mod:`~petsc_contact.devices.compiled`) and the coarse matrix's sums
over aggregates (:mod:`~petsc_contact.numerics.aggregates`).

They are compiled into numba's cache (beside the package in ``__pycache__``, or in
``NUMBA_CACHE_DIR``): by the set-up, ``python -m petsc_contact.numerics.kernels``, or else
when a problem is set up (:func:`compile_kernels`, which says so in one line while it
compiles), never inside a step's timer.
"""

from __future__ import annotations

import sys
import time
import warnings
from collections.abc import Callable

from numba.core import event

from ..devices import compiled
from . import aggregates

PASSES = (  # the numba passes that lived here, now the cpu device's (devices.compiled)
    "free_set", "restrict_dot", "restrict", "fill_outside", "extend_direction", "advance",
    "changed_count", "axpy", "clip", "scale_spectrum", "add_dot", "specimen_calls",
)  # fmt: skip

COMPILE_SECONDS = 5  # about how long compiling every kernel takes (4.7 s on 2 shared cores)
COLD_CACHE = f"compiling the numba kernels once (about {COMPILE_SECONDS} s)..."


def __getattr__(name: str) -> Callable[..., object]:
    """A numba pass by its old name here (:data:`PASSES`), deprecated (a
    ``DeprecationWarning``): it is the ``cpu`` device's, :mod:`~petsc_contact.devices.compiled`
    (until 0.3.0)."""
    if name not in PASSES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    warnings.warn(
        f"{__name__}.{name} is deprecated: import petsc_contact.devices.compiled.{name} "
        "(removed in 0.3.0)",
        DeprecationWarning,
        stacklevel=2,
    )
    return getattr(compiled, name)


class _ColdCache(event.Listener):
    """Says :data:`COLD_CACHE` on stderr once, when numba starts compiling a kernel (one
    loaded from the cache is not compiled, and says nothing)."""

    def __init__(self, announce: bool) -> None:
        self.announce = announce
        self.compiled = False

    def on_start(self, ev: event.Event) -> None:
        if self.announce and not self.compiled:
            print(COLD_CACHE, file=sys.stderr, flush=True)
        self.compiled = True

    def on_end(self, ev: event.Event) -> None:
        """Nothing to do: the line is said when compiling starts."""


_done = False  # whether compile_kernels has run in this process


def compile_kernels(announce: bool = True) -> bool:
    """Compile every numba kernel of the package (or load it from numba's cache) for every
    type the package passes it, once per process: before a step, so that no step's
    ``solve_time`` holds a compilation.

    Parameters
    ----------
    announce
        Say :data:`COLD_CACHE` on stderr when something is compiled (a cold cache); ``False``
        on all MPI ranks but the first.

    Returns
    -------
    bool
        Whether anything was compiled (``False`` on a warm cache, and once done).
    """
    global _done
    if _done:
        return False
    watch = _ColdCache(announce)
    with event.install_listener("numba:compile", watch):
        for kernel, args in compiled.specimen_calls() + aggregates.specimen_calls():
            kernel(*args)
    _done = True
    return watch.compiled


def main() -> None:
    """``python -m petsc_contact.numerics.kernels`` (run by the set-up): compile every kernel
    into numba's cache and say so in one line."""
    start = time.perf_counter()
    fresh = compile_kernels(announce=False)
    count = len({kernel for kernel, _ in compiled.specimen_calls() + aggregates.specimen_calls()})
    done = "compiled" if fresh else "loaded from the cache"
    print(f"numba kernels {done} ({count} kernels, {time.perf_counter() - start:.1f} s)")


if __name__ == "__main__":
    main()
