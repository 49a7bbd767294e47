"""The TAO driver: a bound-constrained minimisation on the grid's PETSc Vecs.

The solver type and every tolerance come from the PETSc options database (``-tao_type``,
``-tao_gatol``, ``-tao_max_it``, ``-options_file``, ...); the package only sets defaults
before ``setFromOptions``, so options always win.

The default is ``-tao_type python`` with the package's Fourier-preconditioned active-set
conjugate gradient (:class:`petsc_contact.backend.cg.PreconditionedCG`, the fastest robust choice
measured, docs/solvers.md); any other Python type is chosen with ``-tao_python_type``.
A Python type that has ``set_preconditioner`` receives the Fourier preconditioner.

Quasi-Newton types of the BQNK family (``bqnls``, ``bqnkls``, ``bqnktr``, ``bqnktl``) get
the Fourier compliance as the initial inverse Hessian ``J0`` of their LMVM matrix.
petsc4py 3.18 does not wrap ``TaoGetLMVMMatrix``/``MatLMVMSetJ0PC``, so this goes through
ctypes on the same ``libpetsc`` that petsc4py uses; ``-petsc_contact_no_j0`` turns it off.

``blmvm`` and ``bncg`` get it as their initial Hessian ``H0`` (``TaoLMVMSetH0``,
``TaoBNCGSetH0``), restricted to TAO's current free set and following it like the default
solver's (:class:`FreeSetPreconditioner`): an LMVM matrix without history whose ``J0`` is that
preconditioner.  BNCG applies ``H0`` only through an LMVM matrix of its own, whose default type
(``lmvmdiagbroyden``) never does, so ``-tao_bncg_mat_type`` defaults to ``lmvmbfgs`` for it.
``-petsc_contact_no_j0`` turns these off as well.

Newton types whose KSP solves on the free variables (``tron``, ``bnls``, ``bntr``, ``bntl``)
get the Fourier preconditioner as the Hessian's preconditioning matrix with ``PCMAT``: TAO
restricts it to the free set like the Hessian, so the KSP is preconditioned by
``P_F K^-1 P_F``.  ``-petsc_contact_no_ksp_pc`` (or any ``-tao_*pc_type``) turns it off.

A :class:`BoundSolver` makes its TAO at its first solve and keeps it, with its Hessian, Vecs
and initial matrices, for every later one (a sweep's steps): each solve sets the new start,
bounds and tolerance floor.  Each solve's answer is its solution Vec's own array, handed out
(the next solve gets a new one); the package's own solver takes the bounds as they are (a
float, or an array), so that no bound Vecs are made for it (TAO's types get two).  It reads
its options with an options prefix (``a_``: ``-a_tao_type``, ``-a_petsc_contact_no_j0``; by
default the prefix of the :func:`~petsc_contact.backend._petsc.scoped_options` block it is
made in), so that solvers side by side take different options.
"""

from __future__ import annotations

import ctypes
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from ..conventions.grid import Grid
from ..devices import compiled
from ..io.progress import IterationReport
from ..solver.report import DEFAULT_GATOL, DEFAULT_MAX_IT, SolveInfo
from . import _petsc
from .cg import ContactPreconditioner, compact_bound
from .operator import DiagonalShift, SpectralOperator, shell_matrix

BOUND_TYPES = (
    "tron",
    "bqnls",
    "blmvm",
    "bncg",
    "gpcg",
    "bnls",
    "bntr",
    "bntl",
    "bqnkls",
    "bqnktr",
    "bqnktl",
    "bqpip",
    "python",
)
J0_TYPES = ("bqnls", "bqnkls", "bqnktr", "bqnktl")
H0_TYPES = ("blmvm", "bncg")  # given the restricted compliance as their H0
BNCG_MATRIX = "lmvmbfgs"  # BNCG's scaling matrix: one that applies H0 (docs/solvers.md)
KSP_TYPES = ("tron", "gpcg", "bnls", "bntr", "bntl", "bqpip")
KSP_PC_TYPES = ("tron", "bnls", "bntr", "bntl")  # preconditioned through the Hessian's Pmat
SHIFT_TYPES = ("bqpip",)  # shift the Hessian's diagonal (MatDiagonalSet) between its solves
DEFAULT_TYPE = "python"
DEFAULT_PYTHON_TYPE = "petsc_contact.backend.cg.PreconditionedCG"

ObjGrad = Callable[[np.ndarray, np.ndarray], float]
Monitor = IterationReport  # (iteration, f, gnorm); truthy stops the solve


@runtime_checkable
class TakesPreconditioner(Protocol):
    """A Python TAO type that is given the Fourier preconditioner (a ``PC``) before it runs."""

    def set_preconditioner(self, pc: Any) -> None: ...


@runtime_checkable
class TakesBounds(Protocol):
    """A Python TAO type that is given each solve's bounds as they are (a float or a local
    array each) before it runs: the solver then makes no bound Vecs (two fields less)."""

    def set_bounds(self, lower: Any, upper: Any) -> None: ...


def _reason_names(petsc: Any) -> dict[int, str]:
    reasons = petsc.TAO.Reason
    return {getattr(reasons, k): k for k in dir(reasons) if k.isupper()}


PACKAGE_SOLVERS = {DEFAULT_PYTHON_TYPE: "cg", "petsc_contact.backend.cg.PolonskyKeer": "pk"}
"""The package's Python TAO types by their names: those ``compare`` and ``options/NAME.opts``
give them, and runs record as ``tao_type``."""


def _type_name(tao: Any, context: Any) -> str:
    """What a step records as its ``tao_type``: TAO's type (``bncg``), the name of one of the
    package's solvers (:data:`PACKAGE_SOLVERS`: ``cg``, ``pk``), or the class of another Python
    type (``python:MyCG``)."""
    if context is None:
        return tao.getType()
    kind = type(context)
    return PACKAGE_SOLVERS.get(f"{kind.__module__}.{kind.__qualname__}", f"python:{kind.__name__}")


def _libpetsc() -> ctypes.CDLL:
    lib = ctypes.CDLL(_petsc.library_path())
    for name in ("TaoGetLMVMMatrix", "MatLMVMSetJ0PC", "TaoBNCGSetH0"):
        getattr(lib, name).argtypes = [ctypes.c_void_p, ctypes.c_void_p]
        getattr(lib, name).restype = ctypes.c_int
    lib.MatLMVMSetHistorySize.argtypes = [ctypes.c_void_p, ctypes.c_int]
    lib.MatLMVMSetHistorySize.restype = ctypes.c_int
    lib.MatLMVMAllocate.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p]
    lib.MatLMVMAllocate.restype = ctypes.c_int
    return lib


def _check(code: int, name: str) -> None:
    if code != 0:
        raise RuntimeError(f"{name} failed (PETSc error {code})")


def attach_lmvm_j0(tao: Any, pc: Any) -> None:
    """Make ``pc`` the initial inverse Hessian of a BQNK-type TAO's LMVM matrix."""
    lib = _libpetsc()
    lmvm = ctypes.c_void_p()
    _check(
        lib.TaoGetLMVMMatrix(ctypes.c_void_p(tao.handle), ctypes.byref(lmvm)), "TaoGetLMVMMatrix"
    )
    _check(lib.MatLMVMSetJ0PC(lmvm, ctypes.c_void_p(pc.handle)), "MatLMVMSetJ0PC")


def initial_matrix(petsc: Any, pc: Any, template: Any) -> Any:
    """An LMVM matrix without history whose inverse is ``pc``: the ``H0`` of ``blmvm`` and
    ``bncg``.  Its ``MatSolve`` applies ``pc`` (``MatLMVMSetJ0PC``); LMVM matrices update an
    LMVM ``J0`` with their own pairs, which a history of zero discards."""
    lib = _libpetsc()
    h0 = petsc.Mat().create(comm=template.getComm())
    h0.setSizes((template.getSizes(), template.getSizes()))  # square, rows as the Vec
    h0.setType("lmvmbfgs")
    handle = ctypes.c_void_p(h0.handle)
    _check(lib.MatLMVMSetHistorySize(handle, 0), "MatLMVMSetHistorySize")
    h0.setUp()
    vec = ctypes.c_void_p(template.handle)
    _check(lib.MatLMVMAllocate(handle, vec, vec), "MatLMVMAllocate")
    _check(lib.MatLMVMSetJ0PC(handle, ctypes.c_void_p(pc.handle)), "MatLMVMSetJ0PC")
    return h0


def attach_h0(tao: Any, tao_type: str, h0: Any) -> None:
    """Give ``blmvm`` or ``bncg`` the initial matrix ``h0`` (before ``TaoSetUp``)."""
    if tao_type == "blmvm":
        tao.setLMVMH0(h0)
    else:  # petsc4py 3.18 does not wrap TaoBNCGSetH0; libpetsc exports it
        _check(
            _libpetsc().TaoBNCGSetH0(ctypes.c_void_p(tao.handle), ctypes.c_void_p(h0.handle)),
            "TaoBNCGSetH0",
        )


class FreeSetPreconditioner:
    """A PC context: the package's preconditioner on TAO's current free set, ``P_F M P_F``.

    ``F = {x > lower} U {g < 0}`` (less ``{x >= upper, g < 0}``) from TAO's solution and the
    gradient Vec the objective was last evaluated into, read at the moment of the application
    (BLMVM and BNCG evaluate into one Vec, the unprojected gradient, and restore it with the
    solution after a failed line search; ``TaoGetGradient`` may hold the projected step
    instead), so the compliance never spreads the
    contact pressures of the bound pixels over the open ones.  BLMVM applies its ``H0`` to
    the unprojected gradient: with the whole compliance its first quasi-Newton step goes to the
    unconstrained minimiser, far through the bound, and its line searches fail (docs/solvers.md).
    A preconditioner that follows the contact set
    (:class:`~petsc_contact.backend.cg.ContactPreconditioner`: the exact Schur and two-level
    forms of the default solver) is adapted whenever the set has changed.

    Parameters
    ----------
    op
        The preconditioner's operator (``apply_array``).
    tao
        The TAO whose solution defines ``F`` with the gradient.
    gradient
        ``gradient[0]`` is the Vec the objective was last evaluated into.
    lower, upper
        The bounds' Vecs.
    """

    def __init__(self, op: Any, tao: Any, gradient: list[Any], lower: Any, upper: Any) -> None:
        self.op = op
        self.tao = tao
        self.gradient = gradient
        comm = tao.getComm()  # mpi4py's for the sums of several ranks only (the mpi extra)
        self.comm = comm.tompi4py() if comm.size > 1 else comm
        self.contact = op if isinstance(op, ContactPreconditioner) else None
        self.bounds = (lower, upper)
        self.load_bounds()
        self.size = lower.getSize()
        self.free = np.zeros(lower.getLocalSize(), dtype=bool)
        self.work = np.empty(lower.getLocalSize())

    def load_bounds(self) -> None:
        """Read the bounds' Vecs again (a new solve's)."""
        lower, upper = self.bounds
        self.lower, self.upper = compact_bound(lower.array_r), compact_bound(upper.array_r)

    def apply(self, pc: Any, x: Any, y: Any) -> None:
        solution = self.tao.getSolution().array_r
        gradient = self.gradient[0].array_r
        with y as out:  # out is scratch until the operator writes it
            counts = compiled.free_set(solution, gradient, self.lower, self.upper, self.free, out)
            changed, n_free = counts[1], counts[3]
            if self.comm.size > 1:
                changed, n_free = self.comm.allreduce(np.array([changed, n_free]))
            if changed and self.contact is not None:
                self.contact.adapt(int(self.size - n_free), self.free)
            compiled.restrict(self.work, x.array_r, self.free)
            self.op.apply_array(self.work, out)
            compiled.restrict(out, out, self.free)

    applyTranspose = apply


def requested_type(petsc: Any, prefix: str | None = None) -> str:
    """The TAO type the options database asks for with ``prefix`` (default: the options
    block's, :func:`~petsc_contact.backend._petsc.options`), ``DEFAULT_TYPE`` if none."""
    opts = _petsc.options(prefix)
    return opts.getString("tao_type", DEFAULT_TYPE) if opts.hasName("tao_type") else DEFAULT_TYPE


def check_tao_type(petsc: Any, prefix: str | None = None) -> str:
    """Raise ``ValueError`` unless ``-tao_type`` names a bound-constrained TAO type."""
    t = requested_type(petsc, prefix)
    if t in PACKAGE_SOLVERS.values():
        raise ValueError(
            f"-tao_type {t} does not choose the package's {t} solver (TAO's own cg ignores the "
            f"bounds): give -options_file options/{t}.opts (cg is also the default, with no "
            "-tao_type)"
        )
    if t not in BOUND_TYPES:
        raise ValueError(
            f"unknown or unbounded TAO type '{t}'; choose one of: " + ", ".join(BOUND_TYPES)
        )
    return t


@dataclass
class _Solve:
    """One solve's callbacks and what TAO's callbacks count of it."""

    objgrad: ObjGrad
    monitor: Monitor | None
    evaluations: int = 0
    norms: list[float] = field(default_factory=list)  # the first iteration's gradient norm


class BoundSolver:
    """Minimise a convex quadratic with ``x >= lower`` by TAO on the grid's row-slab Vecs.

    The TAO is made at the first :meth:`solve` and kept for the later ones until
    :meth:`close`.

    Parameters
    ----------
    grid
        Layout of the unknowns.
    hessian
        Fourier operator giving the exact Hessian (shell ``Mat``).
    preconditioner
        Fourier operator approximating the inverse Hessian (LMVM ``J0``), or ``None``.
    options_prefix
        The prefix of this solver's options (``a_`` reads ``-a_tao_type``); default: the
        prefix of the options block it is made in (:func:`~petsc_contact.backend._petsc.
        scoped_options`).
    """

    def __init__(
        self,
        grid: Grid,
        hessian: SpectralOperator,
        preconditioner: SpectralOperator | None,
        options_prefix: str | None = None,
    ) -> None:
        self.petsc = petsc = _petsc.petsc()
        self.grid = grid
        self.hessian_op = hessian
        self.preconditioner_op = preconditioner
        given = _petsc.options_prefix() if options_prefix is None else options_prefix
        self.prefix = _petsc.check_prefix(given)
        opts = _petsc.options(self.prefix)
        self.tao_type = check_tao_type(petsc, self.prefix)
        shifted = self.tao_type in SHIFT_TYPES
        self.hessian = shell_matrix(petsc, DiagonalShift(hessian) if shifted else hessian)
        self.x: Any = None  # the solution Vec, on an array handed out as the answer
        self.answer: np.ndarray | None = None  # that array, while the Vec still holds it
        self._solution()
        self.lower: Any = None  # the bound Vecs, made for a TAO type that reads them
        self.upper: Any = None
        self.bounds: tuple[Any, Any] = (0.0, petsc.INFINITY)  # the solve's, as given
        self.pc = None
        self.pmat = None
        if (
            preconditioner is not None
            and self.tao_type in KSP_PC_TYPES
            and not opts.getBool("petsc_contact_no_ksp_pc", False)
        ):
            self.pmat = shell_matrix(petsc, preconditioner)
        use_j0 = not opts.getBool("petsc_contact_no_j0", False)
        self.use_h0 = preconditioner is not None and self.tao_type in H0_TYPES and use_j0
        wants_pc = (self.tao_type in J0_TYPES and use_j0) or self.tao_type == "python"
        if preconditioner is not None and wants_pc:
            self.pc = petsc.PC().createPython(preconditioner, comm=_petsc.petsc_comm(grid.comm))
            self.pc.setOperators(self.hessian)
            self.pc.setUp()
        self._reasons = _reason_names(petsc)
        self.tao: Any = None  # made at the first solve (_create), kept until close
        self.requested_gatol = DEFAULT_GATOL  # -tao_gatol, read when the TAO is made
        self.gradient: list[Any] = []  # the Vec the objective was last evaluated into
        self.initial: list[Any] = []  # the H0 of blmvm/bncg and its PC
        self.free_set: FreeSetPreconditioner | None = None
        self.current: _Solve | None = None

    def solve(
        self,
        objgrad: ObjGrad,
        x0: np.ndarray,
        lower: float | np.ndarray = 0.0,
        monitor: Monitor | None = None,
        upper: np.ndarray | None = None,
        gatol_floor: float = 0.0,
    ) -> tuple[np.ndarray, SolveInfo]:
        """Run TAO from ``x0`` (local flat array); return the local solution and TAO's report.

        ``lower`` is one lower bound for all unknowns or a local array of them (``-inf``:
        none); ``upper`` is an optional local array of upper bounds (default: none).
        ``monitor(iteration, f, gnorm)`` is called every iteration (the iterate is
        :attr:`x`); returning ``True`` stops the solve with ``DIVERGED_USER``.
        ``gatol_floor`` raises TAO's absolute tolerance to what double precision can resolve
        (see :meth:`~petsc_contact.geometries.periodic.PeriodicProblem.rounding_floor`);
        the tolerance actually used is reported in :class:`SolveInfo`.
        """
        self._load(x0, lower, upper)
        tao = self.tao if self.tao is not None else self._create()
        if self.lower is None:  # a type that takes the bounds as they are
            tao.getPythonContext().set_bounds(*self.bounds)
        if self.free_set is not None:
            self.free_set.load_bounds()
        self.current = current = _Solve(objgrad, monitor)
        gatol = max(self.requested_gatol, gatol_floor)
        tao.setTolerances(gatol=gatol)
        _, grtol, gttol = tao.getTolerances()
        h0, p0 = self.hessian_op.applications, self._pc_count()
        start = time.perf_counter()
        try:
            tao.solve(self.x)
        finally:
            self.current = None
        elapsed = self.grid.max(time.perf_counter() - start)
        its, f, gnorm, _, _, code = tao.getSolutionStatus()
        code = int(code)
        info = SolveInfo(
            tao_type=_type_name(tao, tao.getPythonContext() if self.tao_type == "python" else None),
            reason=self._reasons.get(code, str(code)),
            reason_code=code,
            iterations=int(its),
            objective_gradient_evaluations=current.evaluations,
            hessian_applications=self.hessian_op.applications - h0,
            preconditioner_applications=self._pc_count() - p0,
            gradient_norm=float(gnorm),
            solve_time=elapsed,
            tolerance=float(gatol),
            relative_tolerance=float(grtol),
            initial_gradient_norm=current.norms[0] if current.norms else np.inf,
            objective=float(f),
            gradient_ratio_tolerance=float(gttol),
        )
        answer, self.answer = self.answer, None  # the next solve gets a Vec of its own
        assert answer is not None
        return answer, info

    def _solution(self) -> None:
        """A new solution Vec on an array of its own, which :meth:`solve` hands out as the
        answer (no copy: a field less while the step is measured).  TAO lets go of the old
        Vec when it is given the new one."""
        n_local = int(np.prod(self.grid.local_shape))
        self.answer = np.empty(n_local)
        comm = _petsc.petsc_comm(self.grid.comm)
        old = self.x
        self.x = self.petsc.Vec().createWithArray(
            self.answer, size=(n_local, self.grid.size), comm=comm
        )
        if old is not None:
            old.destroy()

    def _attach_h0(self, tao: Any) -> None:
        """The restricted compliance as ``tao``'s ``H0`` (:class:`FreeSetPreconditioner`)."""
        op = self.preconditioner_op
        self.free_set = FreeSetPreconditioner(op, tao, self.gradient, self.lower, self.upper)
        pc = self.petsc.PC().createPython(self.free_set, comm=_petsc.petsc_comm(self.grid.comm))
        pc.setOperators(self.hessian)
        pc.setUp()
        h0 = initial_matrix(self.petsc, pc, self.x)
        attach_h0(tao, self.tao_type, h0)
        self.initial = [h0, pc]

    def _load(self, x0: np.ndarray, lower: float | np.ndarray, upper: np.ndarray | None) -> None:
        """The start point into the solver's Vec, the bounds into its bound Vecs where it
        has them (:meth:`_bound_vecs`)."""
        if self.answer is None:
            self._solution()
        assert self.answer is not None
        self.answer[...] = x0.reshape(-1)
        self.bounds = (lower, self.petsc.INFINITY if upper is None else upper)
        if self.lower is not None:
            self._fill_bounds()

    def _bound_vecs(self, tao: Any) -> None:
        """Make the bound Vecs, fill them with :attr:`bounds` and give them to ``tao``."""
        self.lower, self.upper = self.x.duplicate(), self.x.duplicate()
        self._fill_bounds()
        tao.setVariableBounds(self.lower, self.upper)

    def _fill_bounds(self) -> None:
        """:attr:`bounds` into the bound Vecs."""
        lower, upper = self.bounds
        if np.ndim(lower) == 0:
            self.lower.set(float(lower))
        else:
            with self.lower as la:
                la[...] = np.asarray(lower).reshape(-1)
        if np.ndim(upper) == 0:
            self.upper.set(float(upper))
        else:
            with self.upper as ua:
                ua[...] = upper

    def _create(self) -> Any:
        """The TAO of the requested type with the package's defaults, then the user's options
        (read with the solver's prefix); its callbacks serve :attr:`current`."""

        def tao_objgrad(tao: Any, x: Any, g: Any) -> float:
            assert self.current is not None
            self.current.evaluations += 1
            if self.use_h0:  # only H0 reads it: holding TAO's Vec costs memory otherwise
                self.gradient[:] = [g]
            with g as garr:
                return self.current.objgrad(x.array_r, garr)

        def tao_hessian(tao: Any, x: Any, H: Any, P: Any) -> None:
            pass  # the Hessian is constant: the shell Mat already is it

        tao = self.petsc.TAO().create(comm=_petsc.petsc_comm(self.grid.comm))
        self.tao = tao
        tao.setOptionsPrefix(self.prefix or None)
        tao.setType(self.tao_type)
        if self.tao_type == "python":
            tao.setPythonType(DEFAULT_PYTHON_TYPE)
        tao.setObjectiveGradient(tao_objgrad, None)
        tao.setHessian(tao_hessian, self.hessian, self.hessian if self.pmat is None else self.pmat)
        if self.tao_type != "python":  # TAO's own types read them (before their options)
            self._bound_vecs(tao)
        tao.setTolerances(gatol=DEFAULT_GATOL, grtol=0.0, gttol=0.0)
        tao.setMaximumIterations(DEFAULT_MAX_IT)
        tao.setMaximumFunctionEvaluations(10 * DEFAULT_MAX_IT)
        if self.tao_type in KSP_TYPES:
            # bqpip's Newton matrix is H plus its barrier's diagonal, which dominates near the
            # bounds: Jacobi on that diagonal (DiagonalShift's) takes its KSP from 1024
            # iterations without converging to about 80 (docs/solvers.md)
            kind = "jacobi" if self.tao_type in SHIFT_TYPES else "none"
            tao.getKSP().getPC().setType(kind if self.pmat is None else "mat")
        opts = _petsc.options(self.prefix)
        default_matrix = self.use_h0 and self.tao_type == "bncg"
        default_matrix = default_matrix and not opts.hasName("tao_bncg_mat_type")
        if default_matrix:  # read by TaoSetFromOptions only
            opts.setValue("tao_bncg_mat_type", BNCG_MATRIX)
        try:
            tao.setFromOptions()
        finally:
            if default_matrix:
                opts.delValue("tao_bncg_mat_type")
        self.requested_gatol = tao.getTolerances()[0]
        context = tao.getPythonContext() if self.tao_type == "python" else None
        if self.lower is None and not isinstance(context, TakesBounds):
            self._bound_vecs(tao)  # a Python type of the user's
        if self.pc is not None and self.tao_type in J0_TYPES:
            attach_lmvm_j0(tao, self.pc)
        if self.use_h0:
            self._attach_h0(tao)
        if self.pc is not None and isinstance(context, TakesPreconditioner):
            context.set_preconditioner(self.pc)
        tao.setMonitor(self._monitor)
        return tao

    def _monitor(self, tao: Any) -> None:
        """TAO's monitor: record the first gradient norm, call the solve's monitor, stop if it
        says so."""
        assert self.current is not None
        it, f, gnorm = tao.getSolutionStatus()[:3]
        if not self.current.norms:
            self.current.norms.append(float(gnorm))
        monitor = self.current.monitor
        if monitor is not None and monitor(it, f, gnorm):  # True: stop this solve
            tao.setConvergedReason(self.petsc.TAO.Reason.DIVERGED_USER)

    def _pc_count(self) -> int:
        return self.preconditioner_op.applications if self.preconditioner_op is not None else 0

    def __enter__(self) -> BoundSolver:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Destroy the PETSc objects (PETSc must not finalise with live objects)."""
        kept = [self.tao, *self.initial, self.pc, self.pmat]
        for obj in (*kept, self.hessian, self.x, self.lower, self.upper):
            if obj is not None:
                obj.destroy()
        self.tao = self.pc = self.pmat = self.free_set = self.lower = self.upper = None
        self.initial = []
        self.gradient.clear()
