"""Constrained conjugate gradients for bound-constrained quadratics, as TAO Python types.

Select them like any TAO type::

    -tao_type python -tao_python_type petsc_contact.cg.PreconditionedCG   (the default)
    -tao_type python -tao_python_type petsc_contact.cg.PolonskyKeer

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
  bound (``m`` already there; ``m_e`` the preconditioner context's ``expected_bound_count``,
  if it has one) is shortened to the point where that many have reached it.
  From first touch the exact step would otherwise press most of the surface into contact
  (2 million of 4 million pixels at ``p0 = 1e-3 E*``) and the surplus leaves it only slowly.
- The gradient is updated by ``g += alpha H d`` while no variable is clipped, and
  re-evaluated through TAO's callback after a projection, periodically, and before
  convergence is declared, so the reported residual is never an accumulated one.  A Hessian
  whose Python context has ``begin_mult(d) -> d.Hd`` (this rank's part) and
  ``end_mult(out)`` (the package's FFT operators, :mod:`petsc_contact.operator`) is applied
  in those two halves, and the second only when ``H d`` is used: a projected step needs
  ``d.Hd`` but not ``H d``.  Any other Hessian is multiplied and dotted.
- The element-wise work runs in fused single-pass loops (:mod:`petsc_contact.kernels`).

:class:`PreconditionedCG` applies a preconditioner restricted to ``F`` (``z = P_F M P_F r``);
the package gives it the Fourier compliance, the inverse of the periodic stiffness, which
makes the iteration count almost independent of the grid.  A preconditioner whose context
has ``adapt(bound_count, free)`` is told every new free set before it is applied; when that
returns ``True`` the operator depends on the set (the package's exact Schur form for small
contact sets, :mod:`petsc_contact.schur`) and the recurrence restarts.
:class:`PolonskyKeer` is the unpreconditioned method (``M = I``).

Convergence follows TAO's tolerances on the projected gradient ``r = P_F g``:
``||r|| <= gatol`` or ``||r|| <= grtol ||r_0||`` (reason ``CONVERGED_GATOL``/``GRTOL``);
``-tao_max_it`` gives ``DIVERGED_MAXITS``; a direction of non-positive curvature with no bound
ahead gives ``DIVERGED_USER`` (the quadratic is unbounded below).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.linalg import blas

from . import kernels
from .kernels import Bound

REFRESH_EVERY = 50
GROWTH = 8  # a step may put at most max(GROWTH m, MIN_GROWTH, EXPECTED_GROWTH m_e)
MIN_GROWTH = 64  # new variables on the bound
EXPECTED_GROWTH = 1
CONTINUE_FRACTION = 0.01  # free-set changes up to this fraction of m keep the recurrence


def _bound(values: np.ndarray) -> np.ndarray | float:
    """A bound array, or its value when it is the same everywhere (saves a memory pass)."""
    if values.size and values.min() == values.max():
        return float(values[0])
    return values


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
        from petsc4py import PETSc

        reasons = PETSc.TAO.Reason
        comm = tao.getComm().tompi4py()
        x = tao.getSolution()
        lower_vec, upper_vec = tao.getVariableBounds()
        hessian = tao.getHessian()[0]
        gatol, grtol, _ = tao.getTolerances()
        max_it = tao.getMaximumIterations()
        g_vec, d_vec, w_vec, r_vec, z_vec = (x.duplicate() for _ in range(5))
        xa, g, d, w = x.array, g_vec.array, d_vec.array, w_vec.array
        r, z = r_vec.array, z_vec.array
        lower, upper = _bound(lower_vec.array_r), _bound(upper_vec.array_r)

        def allsum(*values: float) -> np.ndarray:
            v = np.array(values, dtype=float)
            return comm.allreduce(v) if comm.size > 1 else v

        def evaluate() -> float:
            return tao.computeObjectiveGradient(x, g_vec)

        context = (
            self.preconditioner.getPythonContext()
            if hasattr(self.preconditioner, "getPythonContext")
            else self.preconditioner
        )
        adapt = getattr(context, "adapt", None)
        split = hessian.getPythonContext() if hessian.getType() == "python" else None
        if not hasattr(split, "begin_mult"):  # a Hessian that can only multiply
            split = None
        min_limit = max(MIN_GROWTH, EXPECTED_GROWTH * getattr(context, "expected_bound_count", 0))
        global_size = x.getSize()
        f = evaluate()
        free = np.zeros(xa.shape, dtype=bool)
        pending_changed = pending_joined = 0.0  # set changes not yet seen by a direction
        rz_old = 0.0
        rnorm0 = None
        since_refresh = 0
        d[...] = 0.0
        it = 0
        while True:
            # free set F = {x > lower} U {g < 0} (minus {x >= upper, g < 0}); r = P_F g
            rr, changed, joined, n_free = allsum(*kernels.free_set(xa, g, lower, upper, free, r))
            pending_changed += changed
            pending_joined += joined
            rnorm = float(np.sqrt(rr))
            if rnorm0 is None:
                rnorm0 = rnorm
            tao.setIterationNumber(it)
            tao.monitor(its=it, f=f, res=rnorm, cnorm=0.0, step=0.0)
            if tao.getConvergedReason() != 0:  # a monitor stopped the solve
                break
            if rnorm <= gatol or rnorm <= grtol * rnorm0:
                if since_refresh > 0:  # confirm on an exactly evaluated gradient
                    f, since_refresh = evaluate(), 0
                    continue
                tao.setConvergedReason(
                    reasons.CONVERGED_GATOL if rnorm <= gatol else reasons.CONVERGED_GRTOL
                )
                break
            if it >= max_it:
                tao.setConvergedReason(reasons.DIVERGED_MAXITS)
                break
            it += 1
            # the preconditioner follows a changed set; preconditioned residual z = P_F M r,
            # then the direction d <- z + beta d, kept in z's buffer and swapped with d's
            # (one memory pass; no copy after a restart)
            changed, joined = pending_changed, pending_joined
            pending_changed = pending_joined = 0.0
            bound_count = int(global_size - n_free)
            exact = bool(changed) and adapt is not None and adapt(bound_count, free)
            if self.preconditioner is not None:
                self.preconditioner.apply(r_vec, z_vec)
                (rz,) = allsum(kernels.restrict_dot(z, free, r))
            else:
                z[...] = r
                rz = rr
            restart = changed > 0
            if changed and rz_old > 0 and not exact:
                restart = joined > 0 and changed > CONTINUE_FRACTION * bound_count
            if not rz > 0:  # rounding, or a preconditioner that is not positive definite
                if since_refresh == 0:
                    tao.setConvergedReason(reasons.DIVERGED_USER)
                    break
                f, since_refresh = evaluate(), 0  # re-evaluate, then test convergence again
                pending_changed = pending_joined = float(global_size)  # restart afresh
                rz_old = 0.0
                continue
            rd = rz  # r.d: r is orthogonal to the previous direction while F is unchanged
            if not restart:
                beta = rz / rz_old
                if changed:  # z's buffer holds the new direction, with d restricted to F
                    (rd,) = allsum(kernels.extend_direction(z, d, free, beta, r))
                    if not rd > 0:  # no longer a descent direction: restart
                        kernels.extend_direction(z, d, free, -beta, r)
                        rd = rz
                else:
                    blas.daxpy(d, z, a=beta)
            rz_old = rz
            d_vec, z_vec, d, z = z_vec, d_vec, z, d
            if split is not None:  # d.Hd now, Hd only if no variable is clipped
                (dw,) = allsum(split.begin_mult(d))
            else:
                hessian.mult(d_vec, w_vec)
                (dw,) = allsum(np.dot(d, w))
            alpha = -rd / dw if dw > 0 else -np.inf  # the exact step along -d
            if not np.isfinite(alpha):
                alpha = -self._distance_to_bound(xa, -d, lower, upper, comm)
                if not np.isfinite(alpha):
                    tao.setConvergedReason(reasons.DIVERGED_USER)
                    break
            below, above = allsum(*kernels.advance(xa, d, alpha, lower, upper))
            limit = int(max(GROWTH * bound_count, min_limit))
            if below > limit:
                fraction = self._growth_fraction(xa, d, alpha, lower, limit, allsum)
                blas.daxpy(d, xa, a=(fraction - 1.0) * alpha)
                alpha *= fraction
            if below or above or since_refresh >= REFRESH_EVERY:
                kernels.clip(xa, lower, upper)
                f, since_refresh = evaluate(), 0
            else:
                f += alpha * rd + 0.5 * alpha * alpha * dw
                if split is not None:
                    split.end_mult(w)
                blas.daxpy(w, g, a=alpha)
                since_refresh += 1
        for v in (g_vec, d_vec, w_vec, r_vec, z_vec):
            v.destroy()

    @staticmethod
    def _growth_fraction(
        x: np.ndarray,
        d: np.ndarray,
        alpha: float,
        lower: np.ndarray | float,
        limit: int,
        allsum: Any,
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

    @staticmethod
    def _distance_to_bound(
        x: np.ndarray, d: np.ndarray, lower: Bound, upper: Bound, comm: Any
    ) -> float:
        """Largest step along ``d`` that stays feasible (``inf`` if no bound is ahead)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            down = np.where(d < 0, (lower - x) / d, np.inf).min(initial=np.inf)
            up = np.where(d > 0, (upper - x) / d, np.inf).min(initial=np.inf)
        local = float(min(down, up))
        if comm.size == 1:
            return local
        from mpi4py import MPI

        return float(comm.allreduce(local, op=MPI.MIN))


class PreconditionedCG(PolonskyKeer):
    """:class:`PolonskyKeer` with the preconditioner restricted to the free set."""

    use_preconditioner = True
