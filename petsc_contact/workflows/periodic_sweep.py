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
from ..devices.device import Device, get_device
from ..devices.fft import make_fft
from ..geometries.periodic import verify
from ..geometries.step import VERIFY_FACTOR, Step, Steps
from ..io.topography import Heights, map_and_lengths
from ..solver.backends import SolverBackend
from .choice import uses_petsc
from .description import Run
from .drivers import Driver, driver_for
from .options import run_default
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
    mean_gaps: float | Sequence[float] | None = None,
    hardness: float | None = None,
    thickness: float | None = None,
    poisson: float = run_default("poisson"),
    base: str = run_default("base"),
    adhesion: str | None = None,
    work_of_adhesion: float | None = None,
    interaction_range: float | None = None,
) -> Steps:
    """Solve the periodic contact of ``heights`` for each nominal pressure or mean gap.

    The parameters after ``heights`` are keywords, named as ``Run``'s fields (by position
    they work until 0.3.0, with a ``DeprecationWarning``).

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
        Nominal pressures ``p0`` (in ``modulus``'s unit), solved in order, warm-started.
    mean_gaps, hardness, thickness, poisson, base, adhesion, work_of_adhesion, interaction_range
        As ``Run``'s: mean gaps for ``pressures``, a hardness cap, a layer, an adhesive law.
    options
        PETSc options for this call only: ``["-tao_type", "bncg"]``, ``"-tao_type bncg"`` or
        ``{"tao_type": "bncg"}``; options nothing read (a misspelt name) are warned of.
    fields, stiffness, progress, monitor, comm, device
        Keep each step's ``gap`` and ``pressure``; add its exact ``stiffness``; ``progress``
        and ``monitor`` as :func:`~petsc_contact.workflows.runner.run_contact` takes them
        (``index`` from 0); the mpi4py communicator (default ``COMM_WORLD``); ``cpu`` (TAO),
        ``gpu`` (the package's solver on CuPy) or ``cpu-array`` (its code on NumPy).

    Returns
    -------
    Steps
        One per load in order (``to_dataframe()``: a table); the last keeps ``state``.
    """
    array, sides, _ = map_and_lengths(heights, length)
    model: dict[str, Any] = dict(hardness=hardness, thickness=thickness, poisson=poisson)
    model.update(base=base, adhesion=adhesion, work_of_adhesion=work_of_adhesion, fields=fields)
    model.update(_loads(pressures, mean_gaps, adhesion), interaction_range=interaction_range)
    run = api_run(array, sides, modulus, options, device, stiffness=stiffness, **model)
    return contact_steps(run, partial(_posed, array, sides, comm), progress, monitor)


def _loads(
    pressures: float | Sequence[float], mean_gaps: float | Sequence[float] | None, law: Any
) -> dict[str, tuple[float, ...]]:
    """:func:`periodic_contact`'s loads as ``Run`` takes them: its pressures (checked positive
    unless an adhesive ``law`` allows tension: then ``Run`` checks them), or its mean gaps;
    both given, refused as ``Run`` refuses them."""
    given = np.atleast_1d(pressures).tolist()
    loads: dict[str, tuple[float, ...]] = {}
    if mean_gaps is None or given:
        tension = law is not None and given
        loads["pressures"] = tuple(given if tension else check_pressures(given))
    if mean_gaps is not None:
        loads["mean_gaps"] = tuple(np.atleast_1d(mean_gaps).tolist())
    return loads


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
    array: np.ndarray, sides: tuple[float, float], comm: Any, run: Run, backend: SolverBackend
) -> tuple[Scene, Driver]:
    """:func:`periodic_contact`'s scene (:func:`periodic_scene`) on ``run``'s device and the
    driver :func:`~petsc_contact.workflows.runner.run_contact` takes there
    (:func:`~petsc_contact.workflows.drivers.driver_for`)."""
    scene = periodic_scene(array, sides, comm, get_device(run.device))
    return scene, driver_for(run, scene, backend)


def periodic_scene(
    array: np.ndarray, sides: tuple[float, float], comm: Any, device: Device
) -> Scene:
    """:func:`periodic_contact`'s scene: the map scattered on its grid, with the FFT of
    ``device``; the map checked as a run's scene checks it (:func:`check_map`), where it
    lives: on a GPU on the device (a GPU runs on one rank, whose slab is the map).
    """
    grid = grid_for(array.shape, sides, comm)
    local = device.asarray(grid.scatter(array))
    check_finite(grid, local)
    check_map(local if grid.comm.size == 1 else array, grid, periodic=True)
    return posed_scene(grid, make_fft(grid, device), local)
