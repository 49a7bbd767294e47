"""The device and the solver backend of a run, chosen once, when it is prepared.

``--device`` names where the arrays live (:func:`~petsc_contact.devices.device.get_device`);
the solver backend that goes with it is :data:`SOLVER_BACKENDS`' (PETSc/TAO on ``cpu``, the
package's array solver on ``gpu`` and ``cpu-array``).  Everything below this module is handed
the :class:`~petsc_contact.devices.device.Device` and the
:class:`~petsc_contact.solver.backends.SolverBackend` and never asks for either by name.
"""

from __future__ import annotations

from collections.abc import Sequence
from contextlib import AbstractContextManager, nullcontext
from types import ModuleType

from ..backend import _petsc
from ..devices.device import DEVICES
from ..solver.backends import ArrayBackend, SolverBackend
from ..solver.driver import SolveSettings

SOLVER_BACKENDS = {"cpu": "petsc", "gpu": "array", "cpu-array": "array"}
"""The solver backend of each device: ``petsc`` (TAO, any ``-tao_type``, PETSc's options
database) or ``array`` (the package's CG, no PETSc; the options it reads:
:class:`~petsc_contact.solver.driver.SolveSettings`)."""


def uses_petsc(device: str) -> bool:
    """Whether a run on ``device`` is solved by PETSc (and records PETSc's options)."""
    if device not in SOLVER_BACKENDS:
        raise ValueError(f"unknown device '{device}': choose one of {', '.join(DEVICES)}")
    return SOLVER_BACKENDS[device] == "petsc"


def solver_backend(device: str, options: Sequence[str] = (), prefix: str = "") -> SolverBackend:
    """The solver backend of a run on ``device``: PETSc's, reading the options database with
    ``prefix`` (the run's options scoped there: :func:`scoped_options`); the array solver's,
    ``options`` parsed once (``ValueError`` in one line for one it does not read)."""
    if uses_petsc(device):
        from ..backend.tao import PetscBackend

        return PetscBackend(prefix)
    return ArrayBackend(SolveSettings.from_options(list(options), device, prefix))


def scoped_options(
    device: str, options: _petsc.OptionsArg, prefix: str = ""
) -> AbstractContextManager[ModuleType | None]:
    """PETSc with ``options`` and ``prefix`` for a ``with`` block, where ``device``'s backend
    is PETSc's; nothing for the array backend (its settings hold the options)."""
    if uses_petsc(device):
        return _petsc.scoped_options(options, prefix)
    return nullcontext(None)
