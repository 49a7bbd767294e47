"""One load step of either geometry: the problem it needs, the driver, what it yields.

Both geometries (:class:`~petsc_contact.geometries.periodic.PeriodicProblem`,
:class:`~petsc_contact.geometries.punch.PunchProblem`) are a :class:`ContactProblem`: a scaled
bound-constrained QP that TAO minimises, and the observables and verdict of its solution.
:func:`solve_step` is the one step driver both go through.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import KW_ONLY, dataclass, field
from typing import Any, Protocol

import numpy as np

from ..backend.operator import SpectralOperator
from ..backend.solve import Monitor, SolveInfo
from ..backend.tao import PetscBackend
from ..conventions.grid import Grid
from ..devices.device import CPU, Device
from ..physics.continuation import Held
from ..solver.backends import BoundSolver, SolverBackend
from ..solver.report import Accuracy

FIELD_NAMES = ("gap", "pressure", "contact")
VERIFY_FACTOR = 10.0  # a step's natural residual may exceed the tolerance asked for by this


@dataclass
class Step:
    """One load step: scalars for the table and the HDF5 file, and optional local fields.

    The fields are projected by the contact rule (``p > k g``): the pressure is exactly zero
    on open pixels, the gap exactly zero on contact pixels; the residual of that projection
    is the step's ``kkt_residual``.
    """

    scalars: dict[str, Any]
    gap: np.ndarray | None = None
    pressure: np.ndarray | None = None
    _: KW_ONLY  # the rest by name only (the fourth field by position was ``state`` in 0.2.0)
    contact: np.ndarray | None = None  # local mask of the pixels in contact
    extra: dict[str, np.ndarray] = field(default_factory=dict)
    """The interaction's fields (``plastic_displacement`` under a hardness cap), by name."""
    resume: Callable[[], tuple[np.ndarray, Held]] | None = field(default=None, repr=False)
    """Makes :attr:`state` and :attr:`held` on their first reading: a sweep whose steps
    nobody goes on from moves no field off its device (512 MB a step at 8192^2)."""
    _point: tuple[np.ndarray, Held] | None = field(default=None, init=False, repr=False)

    @property
    def state(self) -> np.ndarray | None:
        """The local gap (periodic) or pressure (punch) slab the next step starts from, on
        the host; ``None`` once the run has dropped it (:meth:`forget_resume`: a list of a
        long sweep would otherwise hold one full field per step; the last keeps its own)."""
        point = self._resume_point()
        return None if point is None else point[0]

    @property
    def held(self) -> Held | None:
        """What the sweep holds besides :attr:`state`, to go on from."""
        point = self._resume_point()
        return None if point is None else point[1]

    def _resume_point(self) -> tuple[np.ndarray, Held] | None:
        if self._point is None and self.resume is not None:
            self._point, self.resume = self.resume(), None  # the device's arrays let go
        return self._point

    def take_resume(self) -> None:
        """Bring :attr:`state` and :attr:`held` to the host now, letting go of the device's
        arrays they are made from (a kept step then holds no device memory)."""
        self._resume_point()

    def forget_resume(self) -> None:
        """Drop :attr:`state` and :attr:`held` (and what makes them)."""
        self.resume, self._point = None, None

    def field(self, name: str) -> np.ndarray | None:
        """A field by its dataset name: ``gap``, ``pressure``, ``contact`` or one of the
        interaction's (:attr:`extra`)."""
        if name in self.extra:
            return self.extra[name]
        if name not in FIELD_NAMES:
            names = (*FIELD_NAMES, *self.extra)
            raise KeyError(f"no field '{name}': choose one of {', '.join(names)}")
        value: np.ndarray | None = getattr(self, name)
        return value

    @property
    def converged(self) -> bool:
        return bool(self.scalars["converged"])


class Steps(list[Step]):
    """A sweep's steps in order: a list, whose table :meth:`to_dataframe` gives and a
    notebook shows (``kind``: the geometry, ``periodic`` or ``punch``, which orders the
    columns as :func:`~petsc_contact.io.results.read_frame` does)."""

    def __init__(self, steps: Iterable[Step] = (), kind: str | None = None) -> None:
        super().__init__(steps)
        self.kind = kind

    def to_dataframe(self) -> Any:
        """The steps' scalars as a pandas ``DataFrame``, one row per step (from 1), as
        :meth:`~petsc_contact.workflows.runner.RunResult.to_dataframe` gives a run's."""
        from ..io.results import table_frame

        return table_frame([step.scalars for step in self], self.kind)

    def _repr_html_(self) -> str:
        return str(self.to_dataframe()._repr_html_())


def contact_fields(
    gap: np.ndarray, pressure: np.ndarray, contact: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Gap and pressure projected by the contact mask: ``g = 0`` on it, ``p = 0`` off it."""
    return np.where(contact, 0.0, gap), np.where(contact, pressure, 0.0)


def mark_full_contact(scalars: dict[str, Any]) -> None:
    """Flag a step whose every pixel (punch: of the footprint) is in contact,
    ``full_contact``: its load is at or beyond full contact, where the mean gap is 0 whatever
    the load and the interfacial stiffness ``-dp0/du_bar`` is unbounded (periodic: the
    held-set value is infinite; punch: ``K_tot`` is the flat punch's, and paper Eq. 2
    divides by ``1/K_tot - 1/K_flat``, zero up to rounding).  Such a step's ``stiffness``
    and ``interfacial_stiffness`` are NaN (docs/formulation.md), never a number."""
    full = bool(scalars["area_fraction"] >= 1.0)
    scalars["full_contact"] = full
    if full:
        for name in ("stiffness", "interfacial_stiffness"):
            if name in scalars:
                scalars[name] = np.nan


def residual_verdict(residual: float, tolerance: float) -> str:
    """``'ok'`` if the natural residual is within :data:`VERIFY_FACTOR` of the tolerance."""
    if residual <= VERIFY_FACTOR * tolerance:
        return "ok"
    return f"KKT residual {residual:.2e} > {VERIFY_FACTOR:g} x tolerance {tolerance:.1e}"


def held_set_residual(
    grid: Grid, op: Any, pc: Any, mask: Any, y: Any, device: Device = CPU
) -> float:
    """``||P M (1_M - A y)|| / ||P M 1_M||``: the residual of the held-set solve
    ``A_MM y = 1_M`` (:mod:`~petsc_contact.backend.stiffness`) recomputed from its answer
    ``y``, in the norm of its preconditioner ``M`` restricted to the set (``P``).

    It is the quantity the solve's tolerance bounds (``KSPCG``'s default test), evaluated
    afresh rather than taken from the recurrence; with ``M`` near ``A^-1`` it is the relative
    error of ``y``, which is that of the stiffness.  The plain residual is no measure of it:
    ``1_M`` is smooth, the compliance damps rough residuals, and at 512^2 its relative norm
    stood at 1.2e-4 where the stiffness was right to 1e-10.  ``inf`` for the NaN answer of
    a solve that did not converge
    (:func:`~petsc_contact.solver.linear.unconverged`).
    """
    xp = device.xp
    held = device.asarray(mask).reshape(y.shape)
    off = ~held
    work = xp.where(held, y, 0.0)
    image = op.apply_array(work, xp.empty_like(y))
    xp.subtract(1.0, image, out=image)  # 1 - A y: two fields beside y, each reused

    def preconditioned(v: Any) -> float:
        """``|P M P v|^2`` (``v`` overwritten, ``work`` holds ``M P v``)."""
        xp.copyto(v, 0.0, where=off)
        mv = pc.apply_array(v, work)
        xp.copyto(v, mv)
        xp.copyto(v, 0.0, where=off)
        return float(xp.vdot(mv, v))

    r2 = preconditioned(image)
    image.fill(1.0)
    r2, b2 = grid.sum(r2, preconditioned(image))
    if not b2 > 0:
        return 0.0
    residual = float(np.sqrt(r2 / b2))
    return residual if np.isfinite(residual) else np.inf  # a solve that did not converge


class MeasuredSolve:
    """A held-set solve, ``solve(grid, op, pc, mask) -> (y, iterations)``, that keeps what
    :meth:`residual` needs to measure its answers afterwards (outside the solve's timer,
    before the preconditioner is changed)."""

    def __init__(self, solve: Any, device: Device = CPU) -> None:
        self.solve = solve
        self.device = device
        self.answers: list[tuple[Grid, Any, Any, Any, Any]] = []

    def __call__(self, grid: Grid, op: Any, pc: Any, mask: Any) -> tuple[Any, int]:
        y, its = self.solve(grid, op, pc, mask)
        self.answers.append((grid, op, pc, mask, y))
        return y, its

    def residual(self) -> float:
        """The largest :func:`held_set_residual` of the answers (0 if no solve was needed:
        no contact, or no open pixel); the answers are dropped."""
        answers, self.answers = self.answers, []
        return max((held_set_residual(*a, self.device) for a in answers), default=0.0)


def default_backend() -> SolverBackend:
    """What a problem made without a backend is solved by: PETSc's, with the options of the
    block it is made in (:class:`~petsc_contact.backend.tao.PetscBackend`)."""
    return PetscBackend()


class ContactProblem(Protocol):
    """A contact geometry posed as a scaled bound-constrained QP: a substrate and an
    interaction (its bounds) put together."""

    @property
    def grid(self) -> Grid: ...

    @property
    def hessian(self) -> SpectralOperator:
        """The scaled Hessian (a constant: the QP is quadratic)."""
        ...

    @property
    def preconditioner(self) -> SpectralOperator:
        """An approximation of the Hessian's inverse."""
        ...

    @property
    def upper_bound(self) -> np.ndarray | None:
        """Local upper bounds of the unknowns, or ``None``."""
        ...

    @property
    def lower_bound(self) -> float:
        """The lower bound of the unknowns (the interaction's)."""
        ...

    def objective_gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        """The scaled objective at ``x``; its gradient into ``grad``."""
        ...

    def tolerance_floor(self) -> float:
        """The smallest gradient tolerance double precision resolves for the current load."""
        ...

    def accuracy(self) -> Accuracy:
        """The largest measured figures of an accurate step at the current load."""
        ...

    def measure(self, x: np.ndarray, info: SolveInfo, stiffness: bool, fields: bool) -> Step:
        """Observables, verdict and (if asked) the held-set stiffness of a solution ``x``."""
        ...


def solve_step(
    solver: BoundSolver,
    problem: ContactProblem,
    start: np.ndarray,
    monitor: Monitor | None = None,
    stiffness: bool = False,
    fields: bool = False,
) -> tuple[Step, np.ndarray]:
    """Solve the problem's current load from ``start``; the step and TAO's solution."""
    x, info = solver.solve(
        problem.objective_gradient,
        start,
        lower=problem.lower_bound,
        monitor=monitor,
        upper=problem.upper_bound,
        gatol_floor=problem.tolerance_floor(),
    )
    return problem.measure(x, info, stiffness, fields), x
