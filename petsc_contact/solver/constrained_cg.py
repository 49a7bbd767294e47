"""Constrained conjugate gradients for bound-constrained quadratics, on arrays.

The package's own solver, written once against arrays of any :class:`~petsc_contact.devices.
device.Device`: the PETSc path runs it inside TAO on its Vecs' arrays
(:mod:`petsc_contact.backend.cg`), the GPU path on CuPy arrays (:mod:`petsc_contact.solver.
driver`).  It minimises a convex quadratic ``f(x)`` with ``lower <= x <= upper`` using only
an objective/gradient callback, the Hessian and a preconditioner: an active-set conjugate
gradient in the spirit of Polonsky & Keer (Wear 231, 206 (1999)).

- The *free set* is ``F = {x > lower} U {grad f < 0}``: variables off their bound, and
  variables on it whose gradient pulls them off (for the contact gap: open pixels, and
  contact pixels in tension).
- The search direction is the conjugate (preconditioned) projected gradient on ``F``.  The
  recurrence restarts when variables join ``F`` and more than 1% of the bound count change;
  when variables only leave ``F`` (new contact), or a few flicker at the contact edges, the
  old direction is restricted to the new ``F`` and the recurrence goes on (as Polonsky and
  Keer do when the contact set shrinks).
- The step is the exact minimiser of the quadratic along the direction,
  ``alpha = (r.d)/(d.Hd)`` (``r.d = r.z`` while ``F`` is unchanged), followed by the
  projection onto the bounds.  No objective values and no line search are used, so there is
  no floor from rounding the energy.
- A step that would put more than ``max(8 m, 64, m_e)`` new variables on their lower
  bound (``m`` already there; ``m_e`` the ``expected_bound_count`` of a
  :class:`ContactPreconditioner`) is shortened to the point where that many have reached it.
  From first touch the exact step would otherwise press most of the surface into contact
  (2 million of 4 million pixels at ``p0 = 1e-3 E*``) and the surplus leaves it only slowly.
  Once the preconditioner holds a coarse space of the contact set (its ``two_level``), the
  factor is 2 instead of 8: the set has settled once, and a step that triples it takes
  iterations to undo (a cold step at 4096^2 and ``p0 = 1e-3 E*``: 41 iterations instead of
  48; docs/performance.md).
- The gradient is updated by ``g += alpha H d`` while no variable is clipped, and
  re-evaluated through the callback after a projection, periodically, and before
  convergence is declared, so the reported residual is never an accumulated one.  A
  :class:`SplitHessian` (the package's FFT operators) is applied in two halves, and the
  second only when ``H d`` is used: a projected step needs ``d.Hd`` but not ``H d``.  A
  preconditioner that knows the Hessian's image of its output (:class:`ExactImage`: the
  exact Schur form, ``H z = r + lambda``) gives ``H d = H z + beta H d_old`` without any
  transform.
- The element-wise work runs in the device's fused passes (:mod:`petsc_contact.devices.
  compiled` on the CPU).

The preconditioner is restricted to ``F`` (``z = P_F M P_F r``); the package gives it the
Fourier compliance, the inverse of the periodic stiffness, which makes the iteration count
almost independent of the grid.  A :class:`ContactPreconditioner` is told every new free set
before it is applied; when :meth:`~ContactPreconditioner.adapt` returns ``True`` the operator
depends on the set (the exact Schur form for small contact sets) and the recurrence restarts.
Without a preconditioner this is Polonsky and Keer's unpreconditioned method (``M = I``).

Every iteration reports the objective, the norm of the projected gradient ``r = P_F g``
(the natural residual) and the last step's length to a :class:`Convergence`, which says
whether to stop and why, in TAO's names: on the PETSc path TAO's own test (every TAO tolerance,
its monitors, a user's test), on the array path :class:`ToleranceTest` (``gatol``, ``grtol``
and ``max_it`` as TAO defines them).  A verdict of convergence is confirmed on an exactly
evaluated gradient.  A direction of non-positive curvature with no bound ahead gives
``DIVERGED_USER`` (the quadratic is unbounded below).  When the recurrence meets
the tolerance but the exactly evaluated residual stays above it, twice in a row without
falling below 0.9 times its best, the iterate stands at the floor that double precision
leaves: the solve stops with ``CONVERGED_STEPTOL`` and the residual it reached, which the
package's verification then accepts (within 10 times the tolerance) or flags.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from ..conventions.grid import Grid

REFRESH_EVERY = 50
# STALLS confirmations in a row whose exact residual is not below STALL_RATIO times the best
# before it: the iteration stands at the rounding floor
STALL_RATIO, STALLS = 0.9, 2
GROWTH = 8  # a step may put at most max(GROWTH m, MIN_GROWTH, EXPECTED_GROWTH m_e)
TWO_LEVEL_GROWTH = 2  # GROWTH once the preconditioner holds a coarse space of the set
MIN_GROWTH = 64  # new variables on the bound
EXPECTED_GROWTH = 1
CONTINUE_FRACTION = 0.01  # free-set changes up to this fraction of m keep the recurrence

# the reasons a solve ends with (TAO's names)
GATOL, GRTOL, STEPTOL = "CONVERGED_GATOL", "CONVERGED_GRTOL", "CONVERGED_STEPTOL"
MAXITS, USER = "DIVERGED_MAXITS", "DIVERGED_USER"
MONITOR = "monitor"  # the monitor stopped the solve (the caller keeps its own reason)

Array = Any  # an array of the solve's device (numpy.ndarray or cupy.ndarray)


@runtime_checkable
class SplitHessian(Protocol):
    """A Hessian that multiplies in two halves (the package's FFT operators)."""

    def begin_mult(self, x: Array) -> float:
        """Transform and multiply ``x``; return this rank's part of ``x.Hx``."""
        ...

    def end_mult(self, out: Array) -> Array:
        """Transform back into ``out``: ``H x``."""
        ...


@runtime_checkable
class ContactPreconditioner(Protocol):
    """A preconditioner that follows the bound set (the package's own)."""

    expected_bound_count: int  # the bound set the problem expects: a scale for the growth limit

    @property
    def two_level(self) -> bool:
        """Whether a coarse space of a settled bound set is in use (a tighter growth limit)."""
        ...

    def adapt(self, bound_count: int, free: Array) -> bool:
        """Follow a new free set; ``True`` when the operator now depends on it (restart)."""
        ...


@runtime_checkable
class ExactImage(Protocol):
    """A preconditioner that knows the Hessian's image of its output in some forms (the
    package's exact Schur form: ``H z = r + lambda``), so that the step needs no transform."""

    def hessian_image(self, g: Array, out: Array, beta: float) -> bool:
        """``out <- beta out + H z`` for ``z`` its last application, to ``r = P_F g`` (the
        gradient ``g`` restricted to the free set it was told last), when known exactly;
        ``False`` (``out`` untouched) otherwise."""
        ...


@runtime_checkable
class Convergence(Protocol):
    """Where each iteration is reported and judged (TAO's monitors and convergence test)."""

    def check(self, iteration: int, f: float, residual: float, step: float) -> str | None:
        """Report an iteration (objective ``f``, natural residual, the last step's length);
        the reason to stop (TAO's name, or :data:`MONITOR` when a monitor stopped the solve),
        or ``None`` to go on."""
        ...


@dataclass
class ToleranceTest:
    """TAO's default test of ``gatol``, ``grtol`` and ``max_it``, without PETSc.

    ``||r|| <= gatol`` (``CONVERGED_GATOL``), ``||r|| <= grtol |f|`` (``CONVERGED_GRTOL``),
    ``max_it`` iterations (``DIVERGED_MAXITS``), in TAO's order;
    ``monitor(iteration, f, ||r||)`` is told every iteration first, and stops the solve when
    it returns ``True``.
    """

    gatol: float
    grtol: float
    max_it: int
    monitor: Callable[[int, float, float], bool] | None = None

    def check(self, iteration: int, f: float, residual: float, step: float) -> str | None:
        if self.monitor is not None and self.monitor(iteration, f, residual):
            return MONITOR
        if residual <= self.gatol:
            return GATOL
        if f != 0 and abs(residual / f) <= self.grtol:
            return GRTOL
        return MAXITS if iteration >= self.max_it else None


@dataclass(frozen=True)
class Reductions:
    """Sums and minima over every rank of scalars (``float`` each; one rank: themselves)."""

    sum: Callable[..., np.ndarray]
    min: Callable[[float], float]

    @classmethod
    def over(cls, grid: Grid) -> Reductions:
        """Over the ranks of ``grid``'s communicator (:meth:`~petsc_contact.conventions.grid.
        Grid.sum`, :meth:`~petsc_contact.conventions.grid.Grid.min`): :data:`ONE_RANK` on one."""
        return ONE_RANK if grid.comm.size == 1 else cls(sum=grid.sum, min=grid.min)


ONE_RANK = Reductions(sum=lambda *v: np.array([float(x) for x in v]), min=float)


def compact_bound(values: Array) -> Array | float:
    """A bound array, or its value when it is the same everywhere (saves a memory pass)."""
    if values.size and float(values.min()) == float(values.max()):
        return float(values[0])
    return values


def growth_fraction(
    x: Array,
    d: Array,
    alpha: float,
    lower: Array | float,
    limit: int,
    allsum: Any,
    work: tuple[Array, Array],
) -> float:
    """Fraction of the step ``alpha d`` (just taken to ``x``) at which ``limit`` variables
    reach ``lower``.

    A variable that ended below its bound reached it at the fraction
    ``1 - (x - lower)/(alpha d)``.  Those that started on it (fraction 0, a
    preconditioned direction may point into the bound) are clipped at any fraction and
    do not count.  The fraction is found by bisection on the global count, so it is
    the same on every rank, over each rank's ``limit`` smallest fractions only (the
    global ``limit`` smallest are among them, and so is the answer).  ``work`` is two
    arrays like ``x`` to compute in (overwritten), the fractions of the variables that do
    not count set to infinity there instead of gathering the others: from first touch
    nearly every variable ends below its bound, and fresh field-sized temporaries cost more
    than the arithmetic (the first call of a 2048^2 solve: 0.19 s with them).
    """
    reach, scaled = work
    with np.errstate(divide="ignore", invalid="ignore"):  # d = 0 where x is not below
        np.multiply(d, alpha, out=scaled)
        np.subtract(x, lower, out=reach)
        np.divide(reach, scaled, out=reach)
        np.subtract(1.0, reach, out=reach)
        keep = np.greater(reach, 1e-9)  # not: rounding of a start on the bound
    keep &= x < lower
    np.copyto(reach, np.inf, where=np.logical_not(keep, out=keep))  # never counted
    if reach.size > limit:
        reach.partition(limit - 1)
        reach = reach[:limit]
    low, high = 0.0, 1.0
    for _ in range(40):
        mid = 0.5 * (low + high)
        (count,) = allsum(np.count_nonzero(reach <= mid))
        if count < limit:
            low = mid
        else:
            high = mid
    return high


def distance_to_bound(
    x: Array, d: Array, lower: Array | float, upper: Array | float, reduce: Reductions
) -> float:
    """Largest step along ``d`` that stays feasible (``inf`` if no bound is ahead)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        down = float(np.where(d < 0, (lower - x) / d, np.inf).min()) if x.size else np.inf
        up = float(np.where(d > 0, (upper - x) / d, np.inf).min()) if x.size else np.inf
    return reduce.min(min(down, up))


@dataclass
class Outcome:
    """How a solve ended: the reason (TAO's name, or :data:`MONITOR`), its iterations and
    the natural residual ``||P_F g||`` of the last iterate."""

    reason: str
    iterations: int
    residual: float


_GO, _RETEST, _STOP = 0, 1, 2  # what an iteration's stage lets the loop do next


class ConstrainedCG:
    """One solve of the constrained CG (module docstring) on ``x``, in place.

    Parameters
    ----------
    x
        The start point, overwritten by the solution (flat array of the device).
    lower, upper
        The bounds: floats, or arrays like ``x`` (:func:`compact_bound`).
    gradient
        ``gradient(x, g) -> f``: the objective at ``x`` (relative to any fixed reference) and
        its gradient into ``g``.
    hessian
        A :class:`SplitHessian`, or ``mult(d, out)`` for any other Hessian.
    preconditioner
        ``apply(r, z)``: ``z <- M r``, or ``None`` for ``M = I``; called in place (``z`` is
        ``r``: the residual is not kept, a field less).
    contact
        The preconditioner's :class:`ContactPreconditioner`, if it follows the bound set.
    convergence
        Told every iteration; says when to stop (:class:`Convergence`).
    passes
        The device's element-wise passes (:class:`~petsc_contact.devices.passes.ArrayPasses`).
    vector
        ``vector()`` returns a new work vector like ``x``.
    reduce
        Sums and minima over every rank.
    size
        The global number of unknowns.
    """

    def __init__(
        self,
        x: Array,
        lower: Array | float,
        upper: Array | float,
        gradient: Callable[[Array, Array], float],
        hessian: SplitHessian | Callable[[Array, Array], Any],
        preconditioner: Callable[[Array, Array], Any] | None,
        contact: ContactPreconditioner | None,
        convergence: Convergence,
        passes: Any,
        vector: Callable[[], Array],
        reduce: Reductions = ONE_RANK,
        size: int | None = None,
    ) -> None:
        self.xa, self.lower, self.upper = x, lower, upper
        self.gradient, self.passes, self.reduce = gradient, passes, reduce
        self.convergence = convergence
        self.split: SplitHessian | None = None
        self.mult: Callable[[Array, Array], Any] | None = None
        if isinstance(hessian, SplitHessian):
            self.split = hessian
        else:
            self.mult = hessian
        self.preconditioner, self.contact = preconditioner, contact
        self.image = contact if isinstance(contact, ExactImage) else None
        self.beta, self.image_valid = 0.0, False  # d = z + beta d_old; whether w = H d
        # the residual r = P_F g is not kept: it is written where z is made from it
        self.g, self.d, self.w, self.z = (vector() for _ in range(4))
        expected = contact.expected_bound_count if contact is not None else 0
        self.min_limit = max(MIN_GROWTH, EXPECTED_GROWTH * expected)
        self.global_size = x.size if size is None else size
        self.free = np.zeros_like(x, dtype=bool)
        self.pending_changed = self.pending_joined = 0.0  # set changes no direction saw yet
        self.rz_old = self.rd = 0.0
        self.step_length = 0.0  # the last step's multiple of its direction (TAO's "step")
        self.since_refresh = 0
        self.confirming, self.confirmed, self.stalls = False, np.inf, 0  # see _test
        self.reason = ""
        self.residual = np.inf  # the last iteration's ||r||: the iterate's (tested at each)
        self.d[...] = 0.0
        self.f = self._evaluate()

    def allsum(self, *values: float) -> np.ndarray:
        return self.reduce.sum(*values)

    def _evaluate(self) -> float:
        return float(self.gradient(self.xa, self.g))

    def _refresh(self) -> None:
        self.f, self.since_refresh = self._evaluate(), 0

    def _stop(self, reason: str) -> int:
        self.reason = reason
        return _STOP

    def run(self) -> Outcome:
        """Iterate until a stopping rule holds; ``x`` holds the last iterate."""
        it = 0
        while True:
            # free set F = {x > lower} U {g < 0} (minus {x >= upper, g < 0}); z <- r = P_F g
            rr, changed, joined, n_free = self.allsum(
                *self.passes.free_set(self.xa, self.g, self.lower, self.upper, self.free, self.z)
            )
            self.pending_changed += changed
            self.pending_joined += joined
            stage = self._test(it, rr)
            if stage == _GO:
                it += 1
                bound_count = int(self.global_size - n_free)
                stage = self._direction(rr, bound_count)
                if stage == _GO:
                    stage = self._step(bound_count)
            if stage == _STOP:
                return Outcome(self.reason, it, self.residual)

    def _test(self, it: int, rr: float) -> int:
        """Report the iteration; stop where the convergence test says so (a verdict of
        convergence confirmed on an exactly evaluated gradient)."""
        rnorm = self.residual = float(np.sqrt(rr))
        verdict = self.convergence.check(it, self.f, rnorm, self.step_length)
        if verdict == MONITOR:
            return self._stop(MONITOR)
        converged = verdict is not None and verdict.startswith("CONVERGED")
        if self.confirming:  # the exactly evaluated residual after the recurrence's
            self.confirming = False
            stalled = rnorm > STALL_RATIO * self.confirmed and not converged
            self.stalls = self.stalls + 1 if stalled else 0
            if self.stalls >= STALLS:
                # the recurrence keeps meeting the tolerance and the exact residual does not
                # move: the iterate has stopped at the rounding floor (reason STEPTOL; the
                # caller's verification judges the residual it reached)
                return self._stop(STEPTOL)
            self.confirmed = min(self.confirmed, rnorm)
        if converged and self.since_refresh > 0:  # confirm on an exactly evaluated gradient
            self._refresh()
            self.confirming = True
            return _RETEST
        return _GO if verdict is None else self._stop(verdict)

    def _direction(self, rr: float, bound_count: int) -> int:
        """The preconditioner follows a changed set; ``z = P_F M r`` in place of ``r``
        (``z``'s buffer holds ``r = P_F g``), then the direction ``d <- z + beta d``, kept in
        ``z``'s buffer and swapped with ``d``'s (one memory pass; no copy after a restart).
        Sets :attr:`rd`, ``r.d``.  ``r`` is not kept: its products with vectors that vanish
        off the free set are taken with ``g``."""
        changed, joined = self.pending_changed, self.pending_joined
        self.pending_changed = self.pending_joined = 0.0
        contact, free, g, passes = self.contact, self.free, self.g, self.passes
        exact = bool(changed) and contact is not None and contact.adapt(bound_count, free)
        if self.preconditioner is not None:
            self.preconditioner(self.z, self.z)
            (rz,) = self.allsum(passes.restrict_dot(self.z, free, g))
        else:
            rz = rr
        restart = changed > 0
        if changed and self.rz_old > 0 and not exact:
            restart = joined > 0 and changed > CONTINUE_FRACTION * bound_count
        if not rz > 0:  # rounding, or a preconditioner that is not positive definite
            if self.since_refresh == 0:
                return self._stop(USER)
            self._refresh()  # re-evaluate, then test convergence again
            self.pending_changed = self.pending_joined = float(self.global_size)  # restart
            self.rz_old = 0.0
            return _RETEST
        rd, beta = rz, 0.0  # r.d: r is orthogonal to the previous direction while F is unchanged
        if not restart:
            beta = rz / self.rz_old
            if changed:  # z's buffer holds the new direction, with d restricted to F
                (rd,) = self.allsum(passes.extend_direction(self.z, self.d, free, beta, g))
                self.image_valid = False  # H of the restricted old direction is not known
                if not rd > 0:  # no longer a descent direction: restart
                    passes.extend_direction(self.z, self.d, free, -beta, g)
                    rd, beta = rz, 0.0
            else:
                passes.axpy(beta, self.d, self.z)
        self.rz_old, self.rd, self.beta = rz, rd, beta
        self.d, self.z = self.z, self.d
        return _GO

    def _step(self, bound_count: int) -> int:
        """The exact step along ``-d``, shortened by the growth limit, then projected."""
        xa, d, lower, upper, passes = self.xa, self.d, self.lower, self.upper, self.passes
        pending = False  # the split Hessian's second half is owed
        if self._image():  # w = H d without a transform
            (dw,) = self.allsum(float(np.dot(d, self.w)))
        elif self.split is not None:  # d.Hd now, Hd only if no variable is clipped
            (dw,) = self.allsum(self.split.begin_mult(d))
            pending, self.image_valid = True, False
        else:
            assert self.mult is not None
            self.mult(d, self.w)
            (dw,) = self.allsum(float(np.dot(d, self.w)))
            self.image_valid = True
        alpha = -self.rd / dw if dw > 0 else -np.inf  # the exact step along -d
        if not np.isfinite(alpha):
            alpha = -distance_to_bound(xa, -d, lower, upper, self.reduce)
            if not np.isfinite(alpha):
                return self._stop(USER)
        below, above = self.allsum(*passes.advance(xa, d, alpha, lower, upper))
        settled = self.contact is not None and self.contact.two_level
        limit = int(max((TWO_LEVEL_GROWTH if settled else GROWTH) * bound_count, self.min_limit))
        if below > limit:
            work = (self.z, self.w)  # the old direction, and H d: the gradient is evaluated
            self.image_valid = False
            fraction = growth_fraction(xa, d, alpha, lower, limit, self.allsum, work)
            passes.axpy((fraction - 1.0) * alpha, d, xa)
            alpha *= fraction
        self.step_length = abs(alpha)
        if below or above or self.since_refresh >= REFRESH_EVERY:
            passes.clip(xa, lower, upper)
            self._refresh()
        else:
            self.f += alpha * self.rd + 0.5 * alpha * alpha * dw
            if pending:
                assert self.split is not None
                self.split.end_mult(self.w)
                self.image_valid = True
            passes.axpy(alpha, self.w, self.g)
            self.since_refresh += 1
        return _GO

    def _image(self) -> bool:
        """``w <- H d = H z + beta H d_old`` from the preconditioner's exact image of ``z``
        (:class:`ExactImage`), when it has one and ``w`` holds ``H d_old``."""
        if self.image is None or not (self.beta == 0.0 or self.image_valid):
            return False
        self.image_valid = self.image.hessian_image(self.g, self.w, self.beta)
        return self.image_valid
