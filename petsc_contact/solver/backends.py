"""The solver backend: what solves a posed contact problem, chosen once when a run is prepared.

A backend makes the bound-constrained solver of a problem (``solver``), solves the held-set
systems of the exact stiffness (``held_set_solve``) and carries the run's
:class:`~petsc_contact.solver.driver.SolveSettings`, parsed once from the run's options with
its prefix.  Two implement :class:`SolverBackend`:

- :class:`ArrayBackend` (here): the package's constrained CG on a device's arrays
  (:class:`~petsc_contact.solver.driver.ArraySolver`), no PETSc;
- :class:`~petsc_contact.backend.tao.PetscBackend`: TAO, any ``-tao_type``, at PETSc's edge.

The geometries take a backend and never ask which one it is; the device (where the arrays
live, :class:`~petsc_contact.devices.device.Device`) is chosen on its own.
"""

from __future__ import annotations

from typing import Any, Protocol

from ..conventions.grid import Grid
from ..devices.device import Device
from .driver import ArraySolver, SolveSettings
from .linear import held_set_solve
from .report import SolveInfo


class Posed(Protocol):
    """What a backend needs of a posed problem to make its solver."""

    @property
    def grid(self) -> Grid: ...

    @property
    def hessian(self) -> Any: ...

    @property
    def preconditioner(self) -> Any: ...

    @property
    def device(self) -> Device: ...


class BoundSolver(Protocol):
    """A bound-constrained solver kept open over a sweep's steps."""

    def solve(
        self,
        objgrad: Any,
        x0: Any,
        lower: float = 0.0,
        monitor: Any = None,
        upper: Any = None,
        gatol_floor: float = 0.0,
    ) -> tuple[Any, SolveInfo]:
        """The solution from ``x0`` and its report."""
        ...

    def close(self) -> None:
        """Release what the solver holds."""
        ...

    def __enter__(self) -> BoundSolver: ...

    def __exit__(self, *exc: object) -> None: ...


class SolverBackend(Protocol):
    """What solves a problem (module docstring).

    Attributes
    ----------
    name
        ``petsc`` or ``array``, for the record.
    settings
        The solve's settings, parsed once from the run's options.
    """

    name: str
    settings: SolveSettings

    @property
    def runs_default_type(self) -> bool:
        """Whether it runs the package's own solver (what the scene's checks assume)."""
        ...

    def solver(self, problem: Posed) -> BoundSolver:
        """The bound-constrained solver of ``problem`` (kept open; ``close`` it)."""
        ...

    def held_set_solve(
        self, grid: Grid, op: Any, pc: Any, mask: Any, device: Device
    ) -> tuple[Any, int]:
        """``A_MM y = 1_M`` on the pixels of ``mask`` by preconditioned CG: ``y`` (NaN where
        it did not converge) and the iterations."""
        ...

    def stiffness_rtol(self) -> float:
        """The relative tolerance the held-set solves are asked for (for the record)."""
        ...


class ArrayBackend:
    """The package's constrained CG on a device's arrays, with ``settings`` (module
    docstring)."""

    name = "array"
    runs_default_type = True  # the package's CG is its one solver

    def __init__(self, settings: SolveSettings | None = None) -> None:
        self.settings = SolveSettings() if settings is None else settings

    def solver(self, problem: Posed) -> ArraySolver:
        """:class:`~petsc_contact.solver.driver.ArraySolver` on ``problem``'s device, reducing
        over its grid's ranks."""
        pre = problem.preconditioner
        return ArraySolver(problem.hessian, pre, problem.device, self.settings, problem.grid)

    def held_set_solve(
        self, grid: Grid, op: Any, pc: Any, mask: Any, device: Device
    ) -> tuple[Any, int]:
        """:func:`~petsc_contact.solver.linear.held_set_solve` with the settings' tolerance
        and iteration limit."""
        s = self.settings
        return held_set_solve(grid, op, pc, mask, s.stiffness_rtol, device, s.stiffness_max_it)

    def stiffness_rtol(self) -> float:
        """``-stiffness_ksp_rtol`` as the settings read it."""
        return self.settings.stiffness_rtol
