"""The ``cpu`` device's whole-field passes: fused element-wise passes of the constrained CG
and of the spectral operators (numba).

Every function here does in one pass over memory what numpy does in several: the CG's
vector work is memory-bound, so the number of passes is its cost (docs/solvers.md).
Bounds are given as a float (the same everywhere) or an array of the vector's length.
Sums are reassociated (``fastmath`` reassociation and contraction only: infinite bounds and
NaNs keep their IEEE meaning), so they differ from numpy's in rounding only.

They are compiled once into numba's cache, with the coarse matrix's sums
(:mod:`~petsc_contact.numerics.aggregates`), by
:func:`~petsc_contact.numerics.kernels.compile_kernels` (at set-up, ``python -m
petsc_contact.numerics.kernels``, or when a problem is set up), never inside a step's timer.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numba import njit, types
from numba.extending import overload
from scipy.linalg import blas

FAST = {"reassoc", "contract"}
Bound = float | np.ndarray  # a bound the same everywhere, or one per entry


def _at(bound, i):  # compiled code uses the overload
    raise NotImplementedError


@overload(_at)
def _at_impl(bound, i):
    """``bound[i]`` for an array bound, ``bound`` for a float one (chosen when compiling).

    Left unannotated: with annotations, numba 0.56 rejected the overload ("Typing and
    implementation arguments differ in argument names").
    """
    if isinstance(bound, types.Array):
        return lambda bound, i: bound[i]
    return lambda bound, i: bound


@njit(cache=True, fastmath=FAST, nogil=True)
def free_set(
    x: np.ndarray, g: np.ndarray, lower: Bound, upper: Bound, free: np.ndarray, r: np.ndarray
) -> tuple[float, int, int, int]:
    """Update the free set and the projected gradient.

    ``free <- (x > lower | g < 0) & ~(x >= upper & g < 0)`` and ``r <- g`` on it, ``0``
    elsewhere.  Returns ``(r.r, changed, joined, free count)``, where ``changed`` counts the
    entries whose ``free`` flag changed and ``joined`` those that became free.
    """
    rr = 0.0
    changed = 0
    joined = 0
    count = 0
    for i in range(x.size):
        pull = g[i] < 0.0
        f = (x[i] > _at(lower, i) or pull) and not (x[i] >= _at(upper, i) and pull)
        old = free[i]
        changed += f != old
        joined += f and not old
        count += f
        free[i] = f
        v = g[i] if f else 0.0
        r[i] = v
        rr += v * v
    return rr, changed, joined, count


@njit(cache=True, fastmath=FAST, nogil=True)
def restrict_dot(z: np.ndarray, free: np.ndarray, r: np.ndarray) -> float:
    """``z <- z`` on the free set, ``0`` elsewhere; returns ``r.z``."""
    rz = 0.0
    for i in range(z.size):
        v = z[i] if free[i] else 0.0
        z[i] = v
        rz += r[i] * v
    return rz


@njit(cache=True, fastmath=FAST, nogil=True)
def restrict(out: np.ndarray, x: np.ndarray, free: np.ndarray) -> None:
    """``out <- x`` on the free set, ``0`` elsewhere (``out`` may be ``x``)."""
    for i in range(out.size):
        out[i] = x[i] if free[i] else 0.0


@njit(cache=True, fastmath=FAST, nogil=True)
def fill_outside(out: np.ndarray, x: np.ndarray, inside: np.ndarray) -> None:
    """``out <- x`` off ``inside`` (``out`` kept on it)."""
    for i in range(out.size):
        if not inside[i]:
            out[i] = x[i]


@njit(cache=True, fastmath=FAST, nogil=True)
def extend_direction(
    z: np.ndarray, d: np.ndarray, free: np.ndarray, beta: float, r: np.ndarray
) -> float:
    """``z <- z + beta d`` with ``d`` restricted to the free set; returns ``r.z``."""
    rz = 0.0
    for i in range(z.size):
        v = z[i] + (beta * d[i] if free[i] else 0.0)
        z[i] = v
        rz += r[i] * v
    return rz


@njit(cache=True, fastmath=FAST, nogil=True)
def advance(
    x: np.ndarray, d: np.ndarray, alpha: float, lower: Bound, upper: Bound
) -> tuple[int, int]:
    """``x <- x + alpha d``; how many entries fell below ``lower`` and rose above ``upper``."""
    below = 0
    above = 0
    for i in range(x.size):
        v = x[i] + alpha * d[i]
        x[i] = v
        below += v < _at(lower, i)
        above += v > _at(upper, i)
    return below, above


@njit(cache=True, nogil=True)
def changed_count(before: np.ndarray, now: np.ndarray) -> int:
    """How many entries of two boolean masks differ."""
    count = 0
    for i in range(before.size):
        count += before[i] != now[i]
    return count


def axpy(a: float, x: np.ndarray, y: np.ndarray) -> None:
    """``y <- y + a x`` (BLAS)."""
    blas.daxpy(x, y, a=a)


@njit(cache=True, fastmath=FAST, nogil=True)
def clip(x: np.ndarray, lower: Bound, upper: Bound) -> None:
    """``x <- min(max(x, lower), upper)``."""
    for i in range(x.size):
        x[i] = min(max(x[i], _at(lower, i)), _at(upper, i))


@njit(cache=True, fastmath=FAST, nogil=True)
def scale_spectrum(
    values: np.ndarray, multiplier: np.ndarray, single: np.ndarray, factor: float
) -> float:
    """:func:`scale_entries` with each real entry held twice, in the layout of the
    spectrum's float view: the operators' layout before they kept each entry once (half the
    memory), kept for the deprecated name ``numerics.kernels.scale_spectrum`` until 0.3.0."""
    once = 0.0
    for m in single:
        a = values[2 * m]
        b = values[2 * m + 1]
        once += multiplier[2 * m] * factor * (a * a + b * b)
    total = 0.0
    for j in range(values.size):
        a = values[j]
        k = multiplier[j] * factor
        total += k * a * a
        values[j] = a * k
    return 2.0 * total - once


@njit(cache=True, fastmath=FAST, nogil=True)
def scale_entries(
    values: np.ndarray, multiplier: np.ndarray, single: np.ndarray, factor: float
) -> float:
    """Multiply a spectrum by a real multiplier times ``factor``; return ``sum(w k |s|^2)``
    before it (``k`` the multiplier's entry times ``factor``, formed here: an operator that
    is another's times a scalar keeps no multiplier of its own).

    ``values`` is the float view of the (contiguous, complex) spectrum block, ``multiplier``
    holds one real entry per complex one (``multiplier[i]`` scales ``values[2i]`` and
    ``values[2i + 1]``), and ``single`` the complex indices of the entries of multiplicity
    ``w = 1`` (:func:`~petsc_contact.devices.fft.single_entries`; all others have ``w =
    2``).  With a normalised kernel the sum over all ranks is the quadratic form ``x.Kx``
    of the transformed field (Parseval).
    """
    once = 0.0
    for m in single:
        a = values[2 * m]
        b = values[2 * m + 1]
        once += multiplier[m] * factor * (a * a + b * b)
    total = 0.0
    for i in range(multiplier.size):
        k = multiplier[i] * factor
        a = values[2 * i]
        b = values[2 * i + 1]
        total += k * (a * a + b * b)
        values[2 * i] = a * k
        values[2 * i + 1] = b * k
    return 2.0 * total - once


@njit(cache=True, fastmath=FAST, nogil=True)
def add_dot(y: np.ndarray, base: np.ndarray, d: np.ndarray) -> float:
    """``y <- y + base``; returns ``d.base``."""
    total = 0.0
    for i in range(y.size):
        b = base[i]
        y[i] += b
        total += d[i] * b
    return total


def specimen_calls() -> list[tuple[Callable[..., object], tuple[object, ...]]]:
    """Each kernel of this module with tiny arguments of every type the package passes it, so
    that compiling these compiles what any run calls
    (:func:`~petsc_contact.numerics.kernels.compile_kernels`).

    Vectors are float64, writable or read-only (a PETSc ``Vec.array_r``: the input of the
    held-set stiffness solve and of
    :class:`~petsc_contact.backend.solve.FreeSetPreconditioner`); a lower bound is a float
    (``0``), an upper one a float (``inf``) or a read-only array (the punch's disk
    footprint); masks are bool arrays.
    """

    def vector() -> np.ndarray:
        return np.zeros(2)

    read_only, mask = np.zeros(2), np.zeros(2, dtype=bool)
    read_only.setflags(write=False)
    calls: list[tuple[Callable[..., object], tuple[object, ...]]] = []
    for upper in (np.inf, read_only):
        calls += [(advance, (vector(), vector(), 1.0, 0.0, upper)), (clip, (vector(), 0.0, upper))]
        for x in (vector(), read_only):  # the CG's own vectors; TAO's, in a preconditioner
            calls.append((free_set, (x, x, 0.0, upper, mask, vector())))
    return calls + [
        (restrict_dot, (vector(), mask, vector())),
        (restrict, (vector(), vector(), mask)),
        (restrict, (vector(), read_only, mask)),
        (fill_outside, (vector(), read_only, mask)),
        (extend_direction, (vector(), vector(), mask, 1.0, vector())),
        (changed_count, (mask, mask)),
        (scale_spectrum, (vector(), vector(), np.zeros(1, dtype=np.int64), 1.0)),
        (scale_entries, (vector(), np.zeros(1), np.zeros(1, dtype=np.int64), 1.0)),
        (add_dot, (vector(), vector(), vector())),
    ]
