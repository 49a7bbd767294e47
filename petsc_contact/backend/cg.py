"""The package's constrained CG as TAO Python types (the PETSc edge of
:mod:`petsc_contact.solver.cg`).

Select them like any TAO type::

    -tao_type python -tao_python_type petsc_contact.backend.cg.PreconditionedCG   (the default)
    -tao_type python -tao_python_type petsc_contact.backend.cg.PolonskyKeer

The algorithm (an active-set conjugate gradient for ``min f(x), lower <= x <= upper``) lives
in :class:`~petsc_contact.solver.cg.ConstrainedCG` and works on arrays; here TAO gives it its
Vecs' arrays, its objective/gradient callback, its Hessian ``Mat``, its tolerances
(``-tao_gatol``, ``-tao_grtol``, ``-tao_max_it``) and its monitors, and receives its reason.
A Hessian whose Python context is a :class:`~petsc_contact.solver.cg.SplitHessian` (the
package's FFT operators) is applied in two halves; any other is multiplied and dotted.
:class:`PreconditionedCG` applies a ``PC`` (the Fourier compliance the package gives it)
restricted to the free set; a ``PC`` whose context is a
:class:`~petsc_contact.solver.cg.ContactPreconditioner` follows the free set.
:class:`PolonskyKeer` is the unpreconditioned method (``M = I``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..numerics.device import CPU
from ..solver.cg import (
    MONITOR,
    ONE_RANK,
    ConstrainedCG,
    ContactPreconditioner,
    Reductions,
    SplitHessian,
    Tolerances,
    compact_bound,
)

__all__ = ["ContactPreconditioner", "PolonskyKeer", "PreconditionedCG", "SplitHessian"]
__all__ += ["compact_bound"]


class _VecArrays:
    """Work vectors as arrays, each remembering its Vec (the ``PC`` and ``Mat`` take Vecs)."""

    def __init__(self, template: Any) -> None:
        self.template = template
        self.vecs: dict[int, Any] = {}
        self.arrays: list[Any] = []  # kept alive while their ids are keys

    def add(self, vec: Any) -> Any:
        array = vec.array
        self.vecs[id(array)] = vec
        self.arrays.append(array)
        return array

    def new(self) -> Any:
        return self.add(self.template.duplicate())

    def vec(self, array: Any) -> Any:
        return self.vecs[id(array)]

    def close(self, keep: Any) -> None:
        for vec in self.vecs.values():
            if vec is not keep:
                vec.destroy()


def _reductions(petsc_comm: Any) -> Reductions:
    """Sums and minima over the ranks of TAO's communicator (mpi4py only for several)."""
    if petsc_comm.getSize() == 1:
        return ONE_RANK
    from mpi4py import MPI

    comm = petsc_comm.tompi4py()

    def allsum(*values: float) -> np.ndarray:
        return comm.allreduce(np.array([float(v) for v in values]))

    return Reductions(sum=allsum, min=lambda v: float(comm.allreduce(v, op=MPI.MIN)))


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
        """Run :class:`~petsc_contact.solver.cg.ConstrainedCG` on ``tao``'s solution vector
        (TAO's ``TaoSolve``)."""
        from petsc4py import PETSc

        x = tao.getSolution()
        arrays = _VecArrays(x)
        xa = arrays.add(x)
        lower_vec, upper_vec = tao.getVariableBounds()
        hessian = tao.getHessian()[0]
        gatol, grtol, _ = tao.getTolerances()
        pc = self.preconditioner
        context = pc.getPythonContext() if isinstance(pc, PETSc.PC) else pc
        split = hessian.getPythonContext() if hessian.getType() == "python" else None

        def gradient(x_array: Any, g: Any) -> float:
            return float(tao.computeObjectiveGradient(arrays.vec(x_array), arrays.vec(g)))

        def mult(d: Any, out: Any) -> None:
            hessian.mult(arrays.vec(d), arrays.vec(out))

        def precondition(r: Any, z: Any) -> None:
            pc.apply(arrays.vec(r), arrays.vec(z))

        def monitor(it: int, f: float, rnorm: float) -> bool:
            tao.setIterationNumber(it)
            tao.monitor(its=it, f=f, res=rnorm, cnorm=0.0, step=0.0)
            return bool(tao.getConvergedReason() != 0)  # a monitor stopped the solve

        try:
            cg = ConstrainedCG(
                xa,
                compact_bound(lower_vec.array_r),
                compact_bound(upper_vec.array_r),
                gradient,
                split if isinstance(split, SplitHessian) else mult,
                precondition if pc is not None else None,
                context if isinstance(context, ContactPreconditioner) else None,
                Tolerances(gatol, grtol, tao.getMaximumIterations()),
                monitor,
                CPU.passes,
                arrays.new,
                _reductions(tao.getComm()),
                x.getSize(),
            )
            outcome = cg.run()
        finally:
            arrays.close(keep=x)
        if outcome.reason != MONITOR:
            tao.setConvergedReason(getattr(PETSc.TAO.Reason, outcome.reason))


class PreconditionedCG(PolonskyKeer):
    """:class:`PolonskyKeer` with the preconditioner restricted to the free set."""

    use_preconditioner = True
