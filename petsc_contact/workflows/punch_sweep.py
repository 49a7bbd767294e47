"""Pressing the punch (:class:`~petsc_contact.geometries.punch.PunchProblem`) along a list of
approaches or forces, each solve warm-started from the last converged pressure.

Load control (``forces=``) wraps the displacement-controlled solve in a safeguarded Newton
iteration on ``δ`` that uses the exact ``dF/dδ``; ``F(δ)`` is increasing and convex.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np

from ..backend import _petsc
from ..backend.solve import Monitor
from ..conventions.grid import grid_for
from ..conventions.validation import check_finite, keywords_after_first, non_negative, positive
from ..devices.device import Device, get_device
from ..geometries.punch import PunchProblem, footprint_mask
from ..geometries.step import Step, Steps
from ..interactions.interaction import Interaction
from ..io.topography import Heights, map_and_lengths
from ..solver.backends import SolverBackend
from .description import Run
from .drivers import PunchDriver
from .newton import MAX_NEWTON
from .periodic_steps import Progress
from .periodic_sweep import api_run
from .punch_steps import FORCE_RESOLVED, FORCE_RTOL, PunchSolver, punch_solver, punch_sweep
from .runner import contact_steps, posed_scene
from .scene import Scene, check_map

__all__ = [  # the steps' names re-exported: scripts import them from here
    "FORCE_RESOLVED",
    "FORCE_RTOL",
    "MAX_NEWTON",
    "PunchSolver",
    "punch_contact",
    "punch_solver",
    "punch_steps",
    "punch_sweep",
]


@keywords_after_first(
    "length",
    "modulus",
    "approaches",
    "forces",
    "options",
    "fields",
    "footprint",
    "flat_stiffness",
    "beta",
    "comm",
    "monitor",
)
def punch_contact(
    heights: Heights,
    *,
    length: float | tuple[float, float] | None = None,
    modulus: float = 1.0,
    approaches: float | Sequence[float] | None = None,
    forces: float | Sequence[float] | None = None,
    options: _petsc.OptionsArg = None,
    fields: bool = False,
    stiffness: bool = False,
    progress: Progress | bool | None = True,
    monitor: Monitor | None = None,
    footprint: str | np.ndarray | None = None,
    flat_stiffness: str = "grid",
    beta: float | None = None,
    comm: Any = None,
    flat: str | None = None,
    device: str = "cpu",
    hardness: float | None = None,
) -> Steps:
    """Press a rigid punch with face ``heights`` into a free elastic half-space.

    The parameters after ``heights`` are keywords, named as ``Run``'s fields and the command
    line's options (by position they work until 0.3.0, with a ``DeprecationWarning``).

    Parameters
    ----------
    heights, length, modulus
        The punch face's full ``nx x ny`` height map in any form, the footprint's sides
        (``Lp`` for a square patch) and the contact modulus ``E*``, as for
        :func:`~petsc_contact.workflows.periodic_sweep.periodic_contact`.
    approaches, forces
        Exactly one of them: rigid approaches ``δ`` beyond first touch (displacement
        control), or total forces ``F`` (load control).  Solved in order, warm-started; one
        number is one load.
    options, fields, progress, monitor, comm, device
        As for :func:`~petsc_contact.workflows.periodic_sweep.periodic_contact` (``device``
        too: ``cpu``, TAO; ``gpu`` or ``cpu-array``, the package's CG without petsc4py).
    stiffness, hardness
        Add the exact interfacial stiffness to every step, and cap the pressure at
        ``hardness`` (``None``: no cap), as ``Run``'s ``stiffness`` and ``hardness`` do.
    footprint
        ``square`` (default) or ``disk``, as ``Run``'s, or a full ``nx x ny`` boolean mask.
    flat_stiffness, beta
        Paper Eq. 2's flat punch, ``grid``, ``analytic`` (``beta 2 E* sqrt(A/pi)``, ``beta``
        by default the footprint's, :func:`footprint_mask`) or ``king`` (square only);
        ``flat``, its deprecated name (a ``DeprecationWarning``; removed in 0.3.0).

    Returns
    -------
    Steps
        A list, one per load in order (``to_dataframe()``: a table); the last keeps ``state``.
    """
    face = (footprint, _renamed_flat(flat, flat_stiffness), beta)
    kept = {"fields": fields, "stiffness": stiffness, **_punch_loads(approaches, forces)}
    kept |= {"hardness": hardness}
    array, sides, _ = map_and_lengths(heights, length)
    run = api_run(array, sides, modulus, options, device, geometry="punch", **kept)
    posing = partial(_posed, array, sides, modulus, face, comm)
    return contact_steps(run, posing, progress, monitor)


def _punch_loads(
    approaches: float | Sequence[float] | None, forces: float | Sequence[float] | None
) -> dict[str, list[float]]:
    """The loads of :func:`punch_contact`, ``{"approaches": [...]}`` or ``{"forces": [...]}``
    as :class:`Run` takes them: exactly one of them given, at least one load, every force
    positive and no approach negative (``ValueError`` otherwise, as
    :meth:`PunchSolver.at_force` and the problem say it)."""
    given, label = (approaches, "approach") if approaches is not None else (forces, "force")
    values = [float(v) for v in np.atleast_1d(given if given is not None else [])]
    if (approaches is None) == (forces is None) or not values:
        raise ValueError("give either approaches or forces, at least one of them")
    for value in values:  # as the problem and the solver check them, before any is solved
        (positive if forces is not None else non_negative)(label, value)
    return {"approaches" if forces is None else "forces": values}


def _posed(
    array: np.ndarray,
    sides: tuple[float, float],
    modulus: float,
    described: tuple[str | np.ndarray | None, str, float | None],
    comm: Any,
    run: Run,
    backend: SolverBackend,
) -> tuple[Scene, PunchDriver]:
    """:func:`punch_contact`'s scene and driver: its problem (:func:`_punch_problem`) on
    ``run``'s device, with the footprint, flat punch and shape factor ``described``."""
    face = _PunchFace(*described, get_device(run.device), backend, run.interaction)
    problem = _punch_problem(array, sides, modulus, face, comm)
    scene = posed_scene(problem.grid)
    return scene, PunchDriver(run, scene, backend, problem)


@dataclass(frozen=True)
class _PunchFace:
    """What :func:`punch_contact` says of its punch besides the map: the footprint, the
    flat-punch reference and its shape factor, the device, the solver backend and the
    interaction."""

    footprint: str | np.ndarray | None
    flat_stiffness: str
    beta: float | None
    device: Device
    backend: SolverBackend
    interaction: Interaction


def _punch_problem(
    array: np.ndarray, sides: tuple[float, float], modulus: float, face: _PunchFace, comm: Any
) -> PunchProblem:
    """:func:`punch_contact`'s problem: the map and the footprint scattered on its grid; the
    map checked as a run's scene checks it (:func:`check_map`)."""
    grid = grid_for(array.shape, sides, comm)
    local = grid.scatter(array)
    check_finite(grid, local)
    mask, shape = footprint_mask(grid, face.footprint)
    beta = shape if face.beta is None else face.beta
    problem = PunchProblem(
        grid,
        local,
        modulus,
        mask,
        face.flat_stiffness,
        beta,
        device=face.device,
        backend=face.backend,
        interaction=face.interaction,
    )
    check_map(array, grid, periodic=False)
    return problem


def _renamed_flat(flat: str | None, flat_stiffness: str) -> str:
    """``flat_stiffness``, or the deprecated ``flat=`` of :func:`punch_contact` given in its
    place (with a ``DeprecationWarning``); both given are refused."""
    if flat is None:
        return flat_stiffness
    if flat_stiffness != "grid":
        raise TypeError("punch_contact(): give flat_stiffness= alone (flat= is its old name)")
    warnings.warn(
        "punch_contact(flat=...) is deprecated; use flat_stiffness=",
        DeprecationWarning,
        stacklevel=4,  # the caller of punch_contact, through keywords_after_first
    )
    return flat


def punch_steps(*args: Any, **kwargs: Any) -> Iterator[Step]:
    """Deprecated: the steps of :func:`punch_contact` (same arguments), one by one."""
    warnings.warn("punch_steps is deprecated; use punch_contact", DeprecationWarning, stacklevel=2)
    yield from punch_contact(*args, **kwargs)
