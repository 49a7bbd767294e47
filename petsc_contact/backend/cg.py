"""Constrained conjugate gradients for bound-constrained quadratics, as TAO Python types.

Select them like any TAO type::

    -tao_type python -tao_python_type petsc_contact.backend.cg.PreconditionedCG   (the default)
    -tao_type python -tao_python_type petsc_contact.backend.cg.PolonskyKeer

Both minimise a convex quadratic ``f(x)`` with ``x >= lower`` (upper bounds are honoured
too) using only TAO's objective/gradient callback and the Hessian ``Mat``: an active-set
conjugate gradient in the spirit of Polonsky & Keer (Wear 231, 206 (1999)).

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
  projection onto the bounds.  No objective
  values and no line search are used, so there is no floor from rounding the energy.
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
  re-evaluated through TAO's callback after a projection, periodically, and before
  convergence is declared, so the reported residual is never an accumulated one.  A Hessian
  whose Python context is a :class:`SplitHessian` (the package's FFT operators,
  :mod:`petsc_contact.backend.operator`) is applied
  in those two halves, and the second only when ``H d`` is used: a projected step needs
  ``d.Hd`` but not ``H d``.  Any other Hessian is multiplied and dotted.
- The element-wise work runs in fused single-pass loops (:mod:`petsc_contact.numerics.kernels`).

:class:`PreconditionedCG` applies a preconditioner restricted to ``F`` (``z = P_F M P_F r``);
the package gives it the Fourier compliance, the inverse of the periodic stiffness, which
makes the iteration count almost independent of the grid.  A preconditioner whose context
is a :class:`ContactPreconditioner` is told every new free set before it is applied; when
:meth:`~ContactPreconditioner.adapt` returns ``True`` the operator depends on the set (the
package's exact Schur form for small contact sets, :mod:`petsc_contact.numerics.schur`) and the
recurrence restarts.
:class:`PolonskyKeer` is the unpreconditioned method (``M = I``).

Convergence follows TAO's tolerances on the projected gradient ``r = P_F g``:
``||r|| <= gatol`` or ``||r|| <= grtol ||r_0||`` (reason ``CONVERGED_GATOL``/``GRTOL``);
``-tao_max_it`` gives ``DIVERGED_MAXITS``; a direction of non-positive curvature with no bound
ahead gives ``DIVERGED_USER`` (the quadratic is unbounded below).  When the recurrence meets
the tolerance but the exactly evaluated residual stays above it, twice in a row without
falling below 0.9 times its best, the iterate stands at the floor that double precision
leaves: the solve stops with ``CONVERGED_STEPTOL`` and the residual it reached, which the
package's verification then accepts (within 10 times the tolerance) or flags.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np
from scipy.linalg import blas

from ..numerics import kernels
from ..numerics.kernels import Bound

REFRESH_EVERY = 50
# STALLS confirmations in a row whose exact residual is not below STALL_RATIO times the best
# before it: the iteration stands at the rounding floor
STALL_RATIO, STALLS = 0.9, 2
GROWTH = 8  # a step may put at most max(GROWTH m, MIN_GROWTH, EXPECTED_GROWTH m_e)
TWO_LEVEL_GROWTH = 2  # GROWTH once the preconditioner holds a coarse space of the set
MIN_GROWTH = 64  # new variables on the bound
EXPECTED_GROWTH = 1
CONTINUE_FRACTION = 0.01  # free-set changes up to this fraction of m keep the recurrence


@runtime_checkable
class SplitHessian(Protocol):
    """A Hessian context that multiplies in two halves (the package's FFT operators)."""

    def begin_mult(self, x: np.ndarray) -> float:
        """Transform and multiply ``x``; return this rank's part of ``x.Hx``."""
        ...

    def end_mult(self, out: np.ndarray) -> np.ndarray:
        """Transform back into ``out``: ``H x``."""
        ...


@runtime_checkable
class ContactPreconditioner(Protocol):
    """A preconditioner context that follows the bound set (the package's own)."""

    expected_bound_count: int  # the bound set the problem expects: a scale for the growth limit

    @property
    def two_level(self) -> bool:
        """Whether a coarse space of a settled bound set is in use (a tighter growth limit)."""
        ...

    def adapt(self, bound_count: int, free: np.ndarray) -> bool:
        """Follow a new free set; ``True`` when the operator now depends on it (restart)."""
        ...


def compact_bound(values: np.ndarray) -> np.ndarray | float:
    """A bound array, or its value when it is the same everywhere (saves a memory pass)."""
    if values.size and values.min() == values.max():
        return float(values[0])
    return values


def growth_fraction(
    x: np.ndarray, d: np.ndarray, alpha: float, lower: np.ndarray | float, limit: int, allsum: Any
) -> float:
    """Fraction of the step ``alpha d`` (just taken to ``x``) at which ``limit`` variables
    reach ``lower``.

    A variable that ended below its bound reached it at the fraction
    ``1 - (x - lower)/(alpha d)``.  Those that started on it (fraction 0, a
    preconditioned direction may point into the bound) are clipped at any fraction and
    do not count.  The fraction is found by bisection on the global count, so it is
    the same on every rank, over each rank's ``limit`` smallest fractions only (the
    global ``limit`` smallest are among them, and so is the answer).
    """
    below = x < lower
    lo = lower[below] if isinstance(lower, np.ndarray) else lower
    reach = 1.0 - (x[below] - lo) / (alpha * d[below])
    reach = reach[reach > 1e-9]  # below: rounding of a start on the bound
    if reach.size > limit:
        reach = np.partition(reach, limit - 1)[:limit]
    low, high = 0.0, 1.0
    for _ in range(40):
        mid = 0.5 * (low + high)
        (count,) = allsum(np.count_nonzero(reach <= mid))
        if count < limit:
            low = mid
        else:
            high = mid
    return high


def distance_to_bound(x: np.ndarray, d: np.ndarray, lower: Bound, upper: Bound, comm: Any) -> float:
    """Largest step along ``d`` that stays feasible (``inf`` if no bound is ahead)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        down = np.where(d < 0, (lower - x) / d, np.inf).min(initial=np.inf)
        up = np.where(d > 0, (upper - x) / d, np.inf).min(initial=np.inf)
    local = float(min(down, up))
    if comm.size == 1:
        return local
    from mpi4py import MPI

    return float(comm.allreduce(local, op=MPI.MIN))


_GO, _RETEST, _STOP = 0, 1, 2  # what an iteration's stage lets the loop do next


class _Run:
    """One ``TaoSolve`` of :class:`PolonskyKeer`: its work vectors and its iteration state.

    Each iteration has three stages: the free set and the convergence test
    (:meth:`_test`), the preconditioned conjugate direction (:meth:`_direction`) and the
    projected step (:meth:`_step`).  A stage may end the solve (``_STOP``, with TAO's reason
    set) or ask for the test to be repeated on an exactly evaluated gradient (``_RETEST``).
    """

    def __init__(self, preconditioner: Any, tao: Any) -> None:
        from petsc4py import PETSc

        self.tao, self.reasons = tao, PETSc.TAO.Reason
        comm = tao.getComm()  # mpi4py's for the sums of several ranks only (the mpi extra)
        self.comm = comm.tompi4py() if comm.size > 1 else comm
        self.x = tao.getSolution()
        lower_vec, upper_vec = tao.getVariableBounds()
        self.hessian = tao.getHessian()[0]
        self.gatol, self.grtol, _ = tao.getTolerances()
        self.max_it = tao.getMaximumIterations()
        self.g_vec, self.d_vec, self.w_vec, self.r_vec, self.z_vec = (
            self.x.duplicate() for _ in range(5)
        )
        self.xa, self.g, self.w = self.x.array, self.g_vec.array, self.w_vec.array
        self.d, self.r, self.z = self.d_vec.array, self.r_vec.array, self.z_vec.array
        self.lower, self.upper = compact_bound(lower_vec.array_r), compact_bound(upper_vec.array_r)
        self.preconditioner = preconditioner
        context = (
            preconditioner.getPythonContext()
            if isinstance(preconditioner, PETSc.PC)
            else preconditioner
        )
        self.contact = context if isinstance(context, ContactPreconditioner) else None
        split = self.hessian.getPythonContext() if self.hessian.getType() == "python" else None
        # a Hessian that can only multiply is multiplied and dotted
        self.split = split if isinstance(split, SplitHessian) else None
        expected = self.contact.expected_bound_count if self.contact is not None else 0
        self.min_limit = max(MIN_GROWTH, EXPECTED_GROWTH * expected)
        self.global_size = self.x.getSize()
        self.free = np.zeros(self.xa.shape, dtype=bool)
        self.pending_changed = self.pending_joined = 0.0  # set changes no direction saw yet
        self.rz_old = self.rd = 0.0
        self.rnorm0: float | None = None
        self.since_refresh = 0
        self.confirming, self.confirmed, self.stalls = False, np.inf, 0  # see _test
        self.d[...] = 0.0
        self.f = self._evaluate()

    def allsum(self, *values: float) -> np.ndarray:
        v = np.array(values, dtype=float)
        return self.comm.allreduce(v) if self.comm.size > 1 else v

    def _evaluate(self) -> float:
        return float(self.tao.computeObjectiveGradient(self.x, self.g_vec))

    def _refresh(self) -> None:
        self.f, self.since_refresh = self._evaluate(), 0

    def _stop(self, reason: int) -> int:
        self.tao.setConvergedReason(reason)
        return _STOP

    def iterate(self) -> None:
        it = 0
        while True:
            # free set F = {x > lower} U {g < 0} (minus {x >= upper, g < 0}); r = P_F g
            rr, changed, joined, n_free = self.allsum(
                *kernels.free_set(self.xa, self.g, self.lower, self.upper, self.free, self.r)
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
                return

    def _test(self, it: int, rr: float) -> int:
        """Monitor, and stop at convergence or the iteration limit."""
        tao, reasons = self.tao, self.reasons
        rnorm = float(np.sqrt(rr))
        if self.rnorm0 is None:
            self.rnorm0 = rnorm
        tao.setIterationNumber(it)
        tao.monitor(its=it, f=self.f, res=rnorm, cnorm=0.0, step=0.0)
        if tao.getConvergedReason() != 0:  # a monitor stopped the solve
            return _STOP
        if self.confirming:  # the exactly evaluated residual after the recurrence's
            self.confirming = False
            stalled = rnorm > STALL_RATIO * self.confirmed and not self._met(rnorm)
            self.stalls = self.stalls + 1 if stalled else 0
            if self.stalls >= STALLS:
                # the recurrence keeps meeting the tolerance and the exact residual does not
                # move: the iterate has stopped at the rounding floor (reason STEPTOL; the
                # caller's verification judges the residual it reached)
                return self._stop(reasons.CONVERGED_STEPTOL)
            self.confirmed = min(self.confirmed, rnorm)
        if self._met(rnorm):
            if self.since_refresh > 0:  # confirm on an exactly evaluated gradient
                self._refresh()
                self.confirming = True
                return _RETEST
            gatol_met = rnorm <= self.gatol
            return self._stop(reasons.CONVERGED_GATOL if gatol_met else reasons.CONVERGED_GRTOL)
        if it >= self.max_it:
            return self._stop(reasons.DIVERGED_MAXITS)
        return _GO

    def _met(self, rnorm: float) -> bool:
        return rnorm <= self.gatol or rnorm <= self.grtol * (self.rnorm0 or 0.0)

    def _direction(self, rr: float, bound_count: int) -> int:
        """The preconditioner follows a changed set; ``z = P_F M r``, then the direction
        ``d <- z + beta d``, kept in ``z``'s buffer and swapped with ``d``'s (one memory
        pass; no copy after a restart).  Sets :attr:`rd`, ``r.d``."""
        changed, joined = self.pending_changed, self.pending_joined
        self.pending_changed = self.pending_joined = 0.0
        contact, free, r = self.contact, self.free, self.r
        exact = bool(changed) and contact is not None and contact.adapt(bound_count, free)
        if self.preconditioner is not None:
            self.preconditioner.apply(self.r_vec, self.z_vec)
            (rz,) = self.allsum(kernels.restrict_dot(self.z, free, r))
        else:
            self.z[...] = r
            rz = rr
        restart = changed > 0
        if changed and self.rz_old > 0 and not exact:
            restart = joined > 0 and changed > CONTINUE_FRACTION * bound_count
        if not rz > 0:  # rounding, or a preconditioner that is not positive definite
            if self.since_refresh == 0:
                return self._stop(self.reasons.DIVERGED_USER)
            self._refresh()  # re-evaluate, then test convergence again
            self.pending_changed = self.pending_joined = float(self.global_size)  # restart
            self.rz_old = 0.0
            return _RETEST
        rd = rz  # r.d: r is orthogonal to the previous direction while F is unchanged
        if not restart:
            beta = rz / self.rz_old
            if changed:  # z's buffer holds the new direction, with d restricted to F
                (rd,) = self.allsum(kernels.extend_direction(self.z, self.d, free, beta, r))
                if not rd > 0:  # no longer a descent direction: restart
                    kernels.extend_direction(self.z, self.d, free, -beta, r)
                    rd = rz
            else:
                blas.daxpy(self.d, self.z, a=beta)
        self.rz_old, self.rd = rz, rd
        self.d_vec, self.z_vec, self.d, self.z = self.z_vec, self.d_vec, self.z, self.d
        return _GO

    def _step(self, bound_count: int) -> int:
        """The exact step along ``-d``, shortened by the growth limit, then projected."""
        xa, d, lower, upper = self.xa, self.d, self.lower, self.upper
        if self.split is not None:  # d.Hd now, Hd only if no variable is clipped
            (dw,) = self.allsum(self.split.begin_mult(d))
        else:
            self.hessian.mult(self.d_vec, self.w_vec)
            (dw,) = self.allsum(np.dot(d, self.w))
        alpha = -self.rd / dw if dw > 0 else -np.inf  # the exact step along -d
        if not np.isfinite(alpha):
            alpha = -distance_to_bound(xa, -d, lower, upper, self.comm)
            if not np.isfinite(alpha):
                return self._stop(self.reasons.DIVERGED_USER)
        below, above = self.allsum(*kernels.advance(xa, d, alpha, lower, upper))
        settled = self.contact is not None and self.contact.two_level
        limit = int(max((TWO_LEVEL_GROWTH if settled else GROWTH) * bound_count, self.min_limit))
        if below > limit:
            fraction = growth_fraction(xa, d, alpha, lower, limit, self.allsum)
            blas.daxpy(d, xa, a=(fraction - 1.0) * alpha)
            alpha *= fraction
        if below or above or self.since_refresh >= REFRESH_EVERY:
            kernels.clip(xa, lower, upper)
            self._refresh()
        else:
            self.f += alpha * self.rd + 0.5 * alpha * alpha * dw
            if self.split is not None:
                self.split.end_mult(self.w)
            blas.daxpy(self.w, self.g, a=alpha)
            self.since_refresh += 1
        return _GO

    def close(self) -> None:
        for v in (self.g_vec, self.d_vec, self.w_vec, self.r_vec, self.z_vec):
            v.destroy()


class PolonskyKeer:
    """Active-set conjugate gradient for ``min f(x), lower <= x <= upper`` (no preconditioner).

    Attributes
    ----------
    preconditioner
        A PETSc ``PC`` (or any object with ``apply(x, y)`` on Vecs) approximating the inverse
        Hessian, or ``None``.
    """

    use_preconditioner = False

    def __init__(self) -> None:
        self.preconditioner: Any = None

    def set_preconditioner(self, pc: Any) -> None:
        """Use ``pc.apply(r, z)`` as the preconditioner (ignored by :class:`PolonskyKeer`)."""
        if self.use_preconditioner:
            self.preconditioner = pc

    def view(self, tao: Any, viewer: Any) -> None:
        pc = "Fourier/user preconditioner" if self.preconditioner is not None else "none"
        viewer.printfASCII(f"  {type(self).__name__}: active-set CG, preconditioner {pc}\n")

    def solve(self, tao: Any) -> None:
        """Run the iteration on ``tao``'s solution vector (TAO's ``TaoSolve``)."""
        run = _Run(self.preconditioner, tao)
        try:
            run.iterate()
        finally:
            run.close()


class PreconditionedCG(PolonskyKeer):
    """:class:`PolonskyKeer` with the preconditioner restricted to the free set."""

    use_preconditioner = True
