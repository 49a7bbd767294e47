"""The package's constrained CG as TAO Python types (the PETSc edge of
:mod:`petsc_contact.solver.constrained_cg`).

Select them like any TAO type::

    -tao_type python -tao_python_type petsc_contact.backend.cg.PreconditionedCG   (the default)
    -tao_type python -tao_python_type petsc_contact.backend.cg.PolonskyKeer

The algorithm (an active-set conjugate gradient for ``min f(x), lower <= x <= upper``) lives
in :class:`~petsc_contact.solver.constrained_cg.ConstrainedCG` and works on arrays; here TAO
gives it its Vecs' arrays, its objective/gradient callback and its Hessian ``Mat``, and judges
it as it judges its own types: every iteration reports the objective, the natural residual (the
projected gradient's norm, TAO's ``gnorm``) and the step length to TAO's monitors
(``-tao_monitor``, ``tao.setMonitor``) and runs TAO's convergence test (:func:`check_converged`:
every TAO tolerance, ``-tao_max_it``, ``-tao_max_funcs``, a user's ``tao.setConvergenceTest``).
``-tao_view`` describes the solver, its preconditioner and its tolerances.
A Hessian whose Python context is a :class:`~petsc_contact.solver.constrained_cg.SplitHessian` (the
package's FFT operators) is applied in two halves; any other is multiplied and dotted.
:class:`PreconditionedCG` applies a ``PC`` (the Fourier compliance the package gives it)
restricted to the free set; a ``PC`` whose context is a
:class:`~petsc_contact.solver.constrained_cg.ContactPreconditioner` follows the free set.
:class:`PolonskyKeer` is the unpreconditioned method (``M = I``).  The work Vecs are kept
from one solve to the next and destroyed with the TAO.
"""

from __future__ import annotations

import ctypes
from functools import cache
from typing import Any

import numpy as np

from ..devices.device import CPU
from ..solver.constrained_cg import (
    MONITOR,
    ONE_RANK,
    ConstrainedCG,
    ContactPreconditioner,
    Reductions,
    SplitHessian,
    compact_bound,
)
from . import _petsc
from .operator import ShellInterface

__all__ = ["ContactPreconditioner", "PolonskyKeer", "PreconditionedCG", "SplitHessian"]
__all__ += ["check_converged", "compact_bound"]


class _VecArrays:
    """The arrays of a solve's Vecs, each remembering its Vec (the ``PC`` and ``Mat`` take
    Vecs).  The work Vecs are made for a solve and destroyed after it (:meth:`close`): the
    exact stiffness solved after it, and a sweep's fields, take their place."""

    def __init__(self) -> None:
        self.work: list[tuple[Any, Any]] = []  # (Vec, its array): the ids stay unique
        self.vecs: dict[int, Any] = {}
        self.template: Any = None

    def begin(self, x: Any) -> Any:
        """Start a solve on the solution ``x``: its array."""
        self.template, solution = x, x.array
        self.vecs = {id(solution): x}
        return solution

    def new(self) -> Any:
        """A work vector's array, of a new Vec like the solution's."""
        vec = self.template.duplicate()
        array = vec.array
        self.work.append((vec, array))
        self.vecs[id(array)] = vec
        return array

    def vec(self, array: Any) -> Any:
        return self.vecs[id(array)]

    def close(self) -> None:
        """Destroy the work Vecs (no array of theirs may be used after)."""
        for vec, _ in self.work:
            vec.destroy()
        self.work, self.vecs, self.template = [], {}, None


def _read_only(values: Any) -> np.ndarray:
    """A flat read-only view of an array (a copy only if it is not contiguous)."""
    view = np.ascontiguousarray(values, dtype=float).reshape(-1).view()
    view.setflags(write=False)
    return view


@cache
def _default_test() -> Any:
    lib = ctypes.CDLL(_petsc.library_path())
    lib.TaoDefaultConvergenceTest.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
    lib.TaoDefaultConvergenceTest.restype = ctypes.c_int
    return lib.TaoDefaultConvergenceTest


def check_converged(tao: Any) -> int:
    """Run TAO's convergence test on its current iteration, as its own types do; its reason.

    petsc4py 3.18 has no ``TAO.checkConverged`` and ``libpetsc`` no call of the test a TAO
    holds, so this runs what ``TaoSolve`` would: TAO's default test
    (``TaoDefaultConvergenceTest``: ``-tao_gatol``, ``-tao_grtol``, ``-tao_gttol``,
    ``-tao_fmin``, ``-tao_max_funcs``, ``-tao_steptol``, ``-tao_max_it``, on what
    ``tao.monitor`` last reported), then a test given with ``tao.setConvergenceTest``, whose
    answer means what it means to petsc4py: ``None`` no verdict, ``True`` or ``1``
    ``CONVERGED_USER``, ``False`` or ``-1`` ``DIVERGED_USER``, or a reason.
    """
    code = _default_test()(ctypes.c_void_p(tao.handle), None)
    if code != 0:
        raise RuntimeError(f"TaoDefaultConvergenceTest failed (PETSc error {code})")
    user = tao.getConvergenceTest()
    if user is not None:
        converged, args, kargs = user
        reason = converged(tao, *args, **kargs)
        reasons = type(tao).Reason
        if reason is False or reason == -1:
            tao.setConvergedReason(reasons.DIVERGED_USER)
        elif reason is True or reason == 1:
            tao.setConvergedReason(reasons.CONVERGED_USER)
        elif reason is not None:
            tao.setConvergedReason(reason)
    return int(tao.getConvergedReason())


class TaoConvergence:
    """The :class:`~petsc_contact.solver.constrained_cg.Convergence` of a solve inside TAO:
    each iteration goes to TAO's monitors and convergence test (:func:`check_converged`)."""

    def __init__(self, tao: Any) -> None:
        self.tao = tao
        reasons = type(tao).Reason
        self.names = {getattr(reasons, k): k for k in dir(reasons) if k.isupper()}

    def check(self, iteration: int, f: float, residual: float, step: float) -> str | None:
        tao = self.tao
        tao.setConvergedReason(0)  # a verdict the solver has gone on from (a confirmation)
        tao.setIterationNumber(iteration)
        tao.monitor(its=iteration, f=f, res=residual, cnorm=0.0, step=step)
        if tao.getConvergedReason() != 0:
            return MONITOR  # a monitor stopped the solve
        reason = check_converged(tao)
        return None if reason == 0 else self.names.get(reason, str(reason))


def _reductions(petsc_comm: Any) -> Reductions:
    """Sums and minima over the ranks of TAO's communicator (mpi4py only for several)."""
    if petsc_comm.getSize() == 1:
        return ONE_RANK
    from mpi4py import MPI

    comm = petsc_comm.tompi4py()

    def allsum(*values: float) -> np.ndarray:
        return comm.allreduce(np.array([float(v) for v in values]))

    return Reductions(sum=allsum, min=lambda v: float(comm.allreduce(v, op=MPI.MIN)))


def _in_place(pc: Any, context: Any, arrays: _VecArrays) -> Any:
    """``apply(r, z)`` of a preconditioner for a ``z`` that may be ``r`` (the constrained CG
    preconditions in place): the package's operators (a ``PC`` whose Python context is a
    :class:`~petsc_contact.backend.operator.ShellInterface`) apply on the arrays; any other
    ``PC`` on a copy of ``r`` (PETSc refuses a ``PCApply`` from a Vec into itself)."""
    if isinstance(context, ShellInterface):
        return context.apply_array

    def precondition(r: Any, z: Any) -> None:
        copy = arrays.vec(r).copy()
        try:
            pc.apply(copy, arrays.vec(z))
        finally:
            copy.destroy()

    return precondition


def _context(pc: Any) -> Any:
    """A preconditioner's Python context (a ``PC`` of type ``python``), or the object itself."""
    from petsc4py import PETSc

    if isinstance(pc, PETSc.PC) and pc.getType() == "python":
        return pc.getPythonContext()
    return pc


class PolonskyKeer:
    """Active-set conjugate gradient for ``min f(x), lower <= x <= upper`` (no preconditioner).

    Attributes
    ----------
    preconditioner
        A PETSc ``PC`` (or any object with ``apply(x, y)`` on Vecs) approximating the inverse
        Hessian, or ``None``; a Python ``PC`` of the package's operators is applied on the
        arrays, in place (:func:`_in_place`).
    """

    use_preconditioner = False

    def __init__(self) -> None:
        self.preconditioner: Any = None
        self.arrays = _VecArrays()
        self.bounds: tuple[Any, Any] | None = None  # given by set_bounds, else TAO's Vecs

    def set_bounds(self, lower: Any, upper: Any) -> None:
        """Take the next solves' bounds as they are, a float or a local array each (the
        package's :class:`~petsc_contact.backend.solve.BoundSolver` then makes no bound Vecs:
        two fields less); without it they are read from TAO's ``getVariableBounds``."""
        self.bounds = (lower, upper)

    def _bounds(self, tao: Any) -> tuple[Any, Any]:
        """The solve's bounds, each a float or a flat read-only array (:func:`compact_bound`;
        read-only as a Vec's ``array_r`` is, the type the kernels were compiled for)."""
        if self.bounds is None:
            lower_vec, upper_vec = tao.getVariableBounds()
            return compact_bound(lower_vec.array_r), compact_bound(upper_vec.array_r)
        return tuple(  # type: ignore[return-value]
            float(b) if np.ndim(b) == 0 else compact_bound(_read_only(b)) for b in self.bounds
        )

    def set_preconditioner(self, pc: Any) -> None:
        """Use ``pc.apply(r, z)`` as the preconditioner (ignored by :class:`PolonskyKeer`)."""
        if self.use_preconditioner:
            self.preconditioner = pc

    def view(self, tao: Any, viewer: Any) -> None:
        """``-tao_view``: the solver, its preconditioner and the tolerances it stops at."""
        gatol, grtol, gttol = tao.getTolerances()
        lines = [
            f"{type(self).__name__}: the package's active-set conjugate gradient",
            f"  preconditioner: {self._preconditioner_name()}",
            f"  stops by TAO's convergence test: gatol={gatol:g}, grtol={grtol:g}, "
            f"gttol={gttol:g}, max_it={tao.getMaximumIterations()}, "
            f"max_funcs={tao.getMaximumFunctionEvaluations()}",
        ]
        for line in lines:
            viewer.printfASCII(f"  {line}\n")

    def _preconditioner_name(self) -> str:
        if self.preconditioner is None:
            return "none"
        context = _context(self.preconditioner)
        return f"{type(context).__name__}, restricted to the free set"

    def destroy(self, tao: Any) -> None:
        """Destroy the kept work Vecs with the TAO."""
        self.arrays.close()

    def solve(self, tao: Any) -> None:
        """Run :class:`~petsc_contact.solver.constrained_cg.ConstrainedCG` on ``tao``'s solution
        vector (TAO's ``TaoSolve``)."""
        from petsc4py import PETSc

        x = tao.getSolution()
        arrays = self.arrays
        xa = arrays.begin(x)
        lower, upper = self._bounds(tao)
        hessian = tao.getHessian()[0]
        pc = self.preconditioner
        context = _context(pc)
        split = hessian.getPythonContext() if hessian.getType() == "python" else None

        def gradient(x_array: Any, g: Any) -> float:
            return float(tao.computeObjectiveGradient(arrays.vec(x_array), arrays.vec(g)))

        def mult(d: Any, out: Any) -> None:
            hessian.mult(arrays.vec(d), arrays.vec(out))

        cg = ConstrainedCG(
            xa,
            lower,
            upper,
            gradient,
            split if isinstance(split, SplitHessian) else mult,
            None if pc is None else _in_place(pc, context, arrays),
            context if isinstance(context, ContactPreconditioner) else None,
            TaoConvergence(tao),
            CPU.passes,
            arrays.new,
            _reductions(tao.getComm()),
            x.getSize(),
        )
        try:
            outcome = cg.run()
        finally:
            arrays.close()
        if outcome.reason != MONITOR:
            tao.setConvergedReason(getattr(PETSc.TAO.Reason, outcome.reason))


class PreconditionedCG(PolonskyKeer):
    """:class:`PolonskyKeer` with the preconditioner restricted to the free set."""

    use_preconditioner = True
