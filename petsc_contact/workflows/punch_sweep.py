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
from ..conventions.grid import Grid, grid_for
from ..conventions.validation import check_finite, keywords_after_first, non_negative, positive
from ..devices.device import Device, get_device
from ..geometries.adhesive_punch import AdhesivePunchProblem
from ..geometries.punch import PunchProblem, footprint_mask
from ..geometries.step import Step, Steps
from ..interactions.interaction import Interaction
from ..io.topography import Heights, map_and_lengths
from ..solver.backends import SolverBackend
from .description import Run
from .drivers import AdhesivePunchDriver, PunchDriver, adhesive_law
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
    adhesion: str | None = None,
    work_of_adhesion: float | None = None,
    interaction_range: float | str | None = None,
) -> Steps:
    """Press a rigid punch with face ``heights`` into a free elastic half-space.

    Keywords after ``heights``, as ``Run``'s (by position until 0.3.0, deprecated).

    Parameters
    ----------
    heights, length, modulus
        The face's full ``nx x ny`` map in any form, its sides (``Lp``: a square) and ``E*``,
        as for :func:`~petsc_contact.workflows.periodic_sweep.periodic_contact`.
    approaches, forces
        Exactly one: rigid approaches ``δ`` beyond first touch (displacement control), or
        total forces ``F`` (load control), solved in order, warm-started (one number: one).
    options, fields, progress, monitor, comm, device
        As for :func:`~petsc_contact.workflows.periodic_sweep.periodic_contact` (``device``:
        ``cpu``, TAO; ``gpu`` or ``cpu-array``, the package's CG without petsc4py).
    stiffness, hardness, adhesion, work_of_adhesion, interaction_range
        As ``Run``'s: every step's exact interfacial stiffness, a cap on the pressure, an
        adhesive law (``-tao_type blmvm``, ``bncg``; approaches and forces of any sign).
    footprint, flat_stiffness, beta
        ``square`` (default), ``disk`` or a full ``nx x ny`` boolean mask; paper Eq. 2's flat
        punch, ``grid``, ``analytic`` (``beta 2 E* sqrt(A/pi)``, ``beta`` by default the
        footprint's, :func:`footprint_mask`) or ``king`` (square only); ``flat``, its
        deprecated name (a ``DeprecationWarning``; removed in 0.3.0).

    Returns
    -------
    Steps
        A list, one per load in order (``to_dataframe()``: a table); the last keeps ``state``.
    """
    face = (footprint, _renamed_flat(flat, flat_stiffness), beta)
    kept: dict[str, Any] = {**_punch_loads(approaches, forces, adhesion is not None)}
    kept.update(fields=fields, stiffness=stiffness, hardness=hardness, adhesion=adhesion)
    kept.update(work_of_adhesion=work_of_adhesion, interaction_range=interaction_range)
    array, sides, _ = map_and_lengths(heights, length)
    run = api_run(array, sides, modulus, options, device, geometry="punch", **kept)
    posing = partial(_posed, array, sides, modulus, face, comm)
    return contact_steps(run, posing, progress, monitor)


def _punch_loads(
    approaches: float | Sequence[float] | None,
    forces: float | Sequence[float] | None,
    adhesive: bool = False,
) -> dict[str, list[float]]:
    """The loads of :func:`punch_contact`, ``{"approaches": [...]}`` or ``{"forces": [...]}``
    as :class:`Run` takes them: exactly one of them given, at least one load, every force
    positive and no approach negative unless ``adhesive`` (``ValueError`` otherwise, as
    :meth:`PunchSolver.at_force` and the problem say it)."""
    given, label = (approaches, "approach") if approaches is not None else (forces, "force")
    values = [float(v) for v in np.atleast_1d(given if given is not None else [])]
    if (approaches is None) == (forces is None) or not values:
        raise ValueError("give either approaches or forces, at least one of them")
    for value in [] if adhesive else values:  # as the problem and the solver check them
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
) -> tuple[Scene, PunchDriver | AdhesivePunchDriver]:
    """:func:`punch_contact`'s scene and driver: its problem (:func:`_punch_problem`) on
    ``run``'s device, with the footprint, flat punch and shape factor ``described``."""
    face = _PunchFace(*described, get_device(run.device), backend, run.interaction)
    if run.adhesion is not None:
        grid, local, (mask, _) = _face_map(array, sides, face, comm)
        scene = posed_scene(grid)
        law = adhesive_law(run, scene)
        posed = AdhesivePunchProblem(grid, local, modulus, law, mask, backend, device=face.device)
        check_map(array, grid, periodic=False)
        return scene, AdhesivePunchDriver(run, scene, backend, posed)
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
    grid, local, (mask, shape) = _face_map(array, sides, face, comm)
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


def _face_map(
    array: np.ndarray, sides: tuple[float, float], face: _PunchFace, comm: Any
) -> tuple[Grid, np.ndarray, tuple[Any, float]]:
    """The grid of :func:`punch_contact`'s map, its local slab (checked finite) and the
    footprint's mask and shape factor (:func:`footprint_mask`)."""
    grid = grid_for(array.shape, sides, comm)
    local = grid.scatter(array)
    check_finite(grid, local)
    return grid, local, footprint_mask(grid, face.footprint)


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
