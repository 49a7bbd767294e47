"""Periodic, load-controlled contact over a list of nominal pressures (warm-started).

This is the Python API behind ``petsc-contact periodic``::

    from petsc_contact import Grid, periodic_contact
    steps = periodic_contact(heights, length=1.0, modulus=1.0, pressures=[1e-3, 1e-2],
                             options=["-tao_type", "bncg"])

Every step is verified by the package itself, not only by TAO: it is ``converged`` when TAO
reports convergence, no gap is negative and the natural residual ``rms(min(k g, p))/p0``
is within ten times the tolerance TAO was asked for; and ``accurate`` when its measured
accuracy (natural residual, force balance, complementarity, the stiffness solve's residual)
is within the package's, whatever the tolerance asked for (:mod:`petsc_contact.solver.report`).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import partial
from typing import Any

import numpy as np

from ..backend import _petsc
from ..backend.solve import Monitor
from ..conventions.grid import grid_for
from ..conventions.validation import check_finite, keywords_after_first
from ..geometries.periodic import PeriodicProblem, verify
from ..geometries.step import VERIFY_FACTOR, Step, Steps
from ..io.topography import Heights, map_and_lengths
from ..numerics.device import Device, get_device
from ..numerics.fft import make_fft
from ..solver.backends import SolverBackend
from .choice import uses_petsc
from .description import Run
from .drivers import PeriodicDriver
from .periodic_steps import Progress, problem_solver, sweep
from .runner import contact_steps, posed_scene
from .scene import Scene, check_map

__all__ = [
    "VERIFY_FACTOR",  # re-exported with Step, verify and the steps' names: scripts import
    "Progress",  # them from here
    "Step",
    "check_pressures",
    "periodic_contact",
    "problem_solver",
    "sweep",
    "verify",
]
from ..conventions.validation import positive


def check_pressures(pressures: Sequence[float]) -> list[float]:
    """Raise ``ValueError`` unless every nominal pressure is positive and finite."""
    out = [float(p) for p in pressures]
    if not out:
        raise ValueError("give at least one nominal pressure")
    for p in out:
        positive("nominal pressures", p)
    return out


@keywords_after_first(
    "length",
    "modulus",
    "pressures",
    "options",
    "fields",
    "comm",
    "stiffness",
    "monitor",
    "progress",
    "device",
)
def periodic_contact(
    heights: Heights,
    *,
    length: float | tuple[float, float] | None = None,
    modulus: float = 1.0,
    pressures: float | Sequence[float] = (),
    options: _petsc.OptionsArg = None,
    fields: bool = False,
    stiffness: bool = False,
    progress: Progress | bool | None = True,
    monitor: Monitor | None = None,
    comm: Any = None,
    device: str = "cpu",
) -> Steps:
    """Solve the periodic contact of ``heights`` for each nominal pressure.

    The parameters after ``heights`` are keywords, named as ``Run``'s fields and the command
    line's options (by position they work until 0.3.0, with a ``DeprecationWarning``).

    Parameters
    ----------
    heights
        The full ``nx x ny`` height map in any form (``io.topography.as_topography``): an
        array (the same on every rank, or a memory map), ``read_topography``'s result, a
        SurfaceTopography ``Topography`` or a path; its sides are used, undefined points refused.
    length, modulus
        Cell sides ``(Lx, Ly)``, or the side ``Lx`` with square pixels (``L`` for a square
        map; optional for a map with sides), and the contact modulus ``E*``.
    pressures
        Nominal pressures ``p0`` (in ``modulus``'s unit), solved in order, warm-started; one
        number is one load.
    options
        PETSc options for this call only: ``["-tao_type", "bncg"]``, ``"-tao_type bncg"`` or
        ``{"tao_type": "bncg"}``; options nothing read (a misspelt name) are warned of.
    fields, stiffness
        Keep the local ``gap`` and ``pressure`` slabs of every step; add the exact
        incremental ``stiffness`` to every step (see :func:`sweep`).
    progress, monitor, comm
        ``progress(index, total, scalars)`` is told of each step (``index`` from 0: step
        ``index + 1`` of the table; default ``True``: a bar where a person watches, ``False``:
        nothing), ``monitor(iteration, f, gnorm)`` of every TAO iteration (``True`` stops); the
        mpi4py communicator (default ``COMM_WORLD``).
    device
        ``cpu`` (TAO), ``gpu`` (the package's solver on CuPy, one rank) or ``cpu-array`` (its
        code on NumPy), without petsc4py, reading the options ``SolveSettings`` reads.

    Returns
    -------
    Steps
        A list, one per load in order (``to_dataframe()``: a table); the last keeps ``state``.
    """
    array, sides, _ = map_and_lengths(heights, length)
    loads = check_pressures(np.atleast_1d(pressures).tolist())
    kept = {"fields": fields, "stiffness": stiffness}
    run = api_run(array, sides, modulus, options, device, pressures=tuple(loads), **kept)
    posing = partial(_posed, array, sides, modulus, comm)
    return contact_steps(run, posing, progress, monitor)


def api_run(
    array: np.ndarray,
    sides: tuple[float, float],
    modulus: float,
    options: _petsc.OptionsArg,
    device: str,
    **loads: Any,
) -> Run:
    """The :class:`Run` (no output) of a call of the Python API on the map ``array`` of
    ``sides``: its options in any form (:func:`~petsc_contact.backend._petsc.option_list`),
    its ``device`` and ``modulus`` checked first, as its problem checks them, and its
    ``loads`` (its geometry, loads and what it keeps, as ``Run`` takes them)."""
    given = tuple(_petsc.option_list(options))
    uses_petsc(device)  # an unknown device named as the API names it
    positive("modulus", modulus)
    return Run(heights=array, length=sides, modulus=modulus, device=device, options=given, **loads)


def _posed(
    array: np.ndarray,
    sides: tuple[float, float],
    modulus: float,
    comm: Any,
    run: Run,
    backend: SolverBackend,
) -> tuple[Scene, PeriodicDriver]:
    """:func:`periodic_contact`'s scene and driver: its problem (:func:`_periodic_problem`) on
    ``run``'s device."""
    problem = _periodic_problem(array, sides, modulus, comm, get_device(run.device), backend)
    scene = posed_scene(problem.grid)
    return scene, PeriodicDriver(run, scene, backend, problem)


def _periodic_problem(
    array: np.ndarray,
    sides: tuple[float, float],
    modulus: float,
    comm: Any,
    device: Device,
    backend: SolverBackend,
) -> PeriodicProblem:
    """:func:`periodic_contact`'s problem: the map scattered on its grid, with the FFT of
    ``device``; the map checked as a run's scene checks it (:func:`check_map`), where it
    lives: on a GPU on the device (a GPU runs on one rank, whose slab is the map).
    """
    grid = grid_for(array.shape, sides, comm)
    local = device.asarray(grid.scatter(array))
    check_finite(grid, local)
    check_map(local if grid.comm.size == 1 else array, grid, periodic=True)
    return PeriodicProblem(grid, make_fft(grid, device), local, modulus, backend)
