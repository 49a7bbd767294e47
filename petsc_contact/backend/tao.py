"""The PETSc/TAO solver backend (:class:`~petsc_contact.solver.backends.SolverBackend`).

:class:`PetscBackend` is PETSc's edge for a run: TAO solves the bound-constrained problems
(:class:`~petsc_contact.backend.solve.BoundSolver`, any ``-tao_type``) and ``KSPCG`` the
held-set systems of the exact stiffness (:func:`~petsc_contact.backend.stiffness.
restricted_solve`).  The package's own options (the two-level form's) are read from the
options database here, once, with the backend's prefix, into a
:class:`~petsc_contact.solver.driver.SolveSettings`; TAO and KSP read theirs as PETSc does.
"""

from __future__ import annotations

from typing import Any

from ..conventions.grid import Grid
from ..devices.device import Device
from ..solver.backends import Posed
from ..solver.driver import SolveSettings
from ..solver.report import STIFFNESS_RTOL
from . import _petsc
from .coarse import BLOCK, MAX_FRACTION
from .solve import DEFAULT_TYPE, BoundSolver, requested_type
from .stiffness import restricted_solve


class PetscBackend:
    """TAO and KSP with the options of the database (module docstring).

    Parameters
    ----------
    prefix
        The options prefix of the run's solvers (``a_`` reads ``-a_tao_type``); default:
        the prefix of the :func:`~petsc_contact.backend._petsc.scoped_options` block it is
        made in.
    """

    name = "petsc"

    def __init__(self, prefix: str | None = None) -> None:
        given = _petsc.options_prefix() if prefix is None else prefix
        self.prefix = _petsc.check_prefix(given)
        self.petsc = _petsc.petsc()
        opts = _petsc.options(self.prefix)
        block = opts.getInt("petsc_contact_two_level_block", BLOCK)
        if block < 1:
            raise ValueError(f"-petsc_contact_two_level_block must be positive, not {block}")
        self.settings = SolveSettings(
            two_level=opts.getBool("petsc_contact_two_level", True),
            block=block,
            max_fraction=opts.getReal("petsc_contact_two_level_max_fraction", MAX_FRACTION),
        )

    @property
    def runs_default_type(self) -> bool:
        """Whether ``-tao_type`` asks for the package's own solver (the default)."""
        return requested_type(self.petsc, self.prefix) == DEFAULT_TYPE

    def solver(self, problem: Posed) -> BoundSolver:
        """TAO on ``problem`` with this backend's prefix."""
        return BoundSolver(problem.grid, problem.hessian, problem.preconditioner, self.prefix)

    def held_set_solve(
        self, grid: Grid, op: Any, pc: Any, mask: Any, device: Device
    ) -> tuple[Any, int]:
        """``KSPCG`` with the options ``-stiffness_ksp_*`` under this backend's prefix."""
        return restricted_solve(grid, op, pc, mask, prefix=self.prefix)

    def stiffness_rtol(self) -> float:
        """``-stiffness_ksp_rtol`` as the held-set ``KSP`` reads it (read when asked: an
        option of a run that computes no stiffness stays unused)."""
        return float(_petsc.options(self.prefix).getReal("stiffness_ksp_rtol", STIFFNESS_RTOL))
