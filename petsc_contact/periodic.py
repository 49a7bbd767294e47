"""Periodic, load-controlled contact over a list of nominal pressures (warm-started).

This is the Python API behind ``petsc-contact periodic``::

    from petsc_contact import Grid, periodic_contact
    steps = periodic_contact(heights, length=1.0, modulus=1.0, pressures=[1e-3, 1e-2],
                             options=["-tao_type", "bncg"])

Every step is verified by the package itself, not only by TAO: it is ``converged`` when TAO
reports convergence, no gap is negative and the natural residual ``rms(min(k g, p))/p0``
is within ten times the tolerance TAO was asked for.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import _petsc
from .continuation import ConvergedStep, LoadPath
from .fft import make_fft
from .grid import Grid
from .observables import step_observables
from .output import check_finite
from .problem import PeriodicProblem
from .solve import BoundSolver, Monitor, SolveInfo
from .stiffness import periodic_stiffness_exact
from .validation import positive

VERIFY_FACTOR = 10.0


@dataclass
class Step:
    """One load step: scalars for the table and the HDF5 file, and optional local fields."""

    scalars: dict[str, Any]
    gap: np.ndarray | None = None
    pressure: np.ndarray | None = None
    state: np.ndarray | None = None  # local gap/pressure the next step starts from

    @property
    def converged(self) -> bool:
        return bool(self.scalars["converged"])


def verify(info: SolveInfo, obs: dict[str, float], scale_length: float) -> str:
    """``'ok'`` or the reason a TAO answer cannot be used."""
    if info.reason_code <= 0:
        return f"TAO did not converge ({info.reason})"
    if obs["min_gap"] < -1e-12 * scale_length:
        return f"bound violated: min gap {obs['min_gap']:.3e}"
    relative = info.relative_tolerance
    tol = max(info.tolerance, relative * info.initial_gradient_norm if relative > 0 else 0.0)
    if not obs["kkt_residual"] <= VERIFY_FACTOR * tol:
        return f"KKT residual {obs['kkt_residual']:.2e} > {VERIFY_FACTOR:g} x tolerance {tol:.1e}"
    return "ok"


def check_pressures(pressures: Sequence[float]) -> list[float]:
    """Raise ``ValueError`` unless every nominal pressure is positive and finite."""
    out = [float(p) for p in pressures]
    if not out:
        raise ValueError("give at least one nominal pressure")
    for p in out:
        positive("nominal pressures", p)
    return out


def sweep(
    petsc: Any,
    problem: PeriodicProblem,
    pressures: Sequence[float],
    fields: bool = False,
    monitor: Monitor | None = None,
    stiffness: bool = False,
    start: np.ndarray | None = None,
) -> Iterator[Step]:
    """Solve the pressures in the given order, each warm-started from the last converged steps.

    Each step starts from the last converged gap, extrapolated along the load path, and its
    preconditioner is held by the interfacial stiffness the path predicts
    (:class:`~petsc_contact.continuation.LoadPath`; Persson's estimate for the first step).

    Parameters
    ----------
    stiffness
        Add ``stiffness``, the exact ``-dp0/du_bar`` with the contact set held fixed
        (:func:`~petsc_contact.stiffness.periodic_stiffness_exact`), and its CG iterations.
    start
        Local gap slab to start from (e.g. a resumed run's last state); default: first touch.

    Yields
    ------
    Step
        Scalars (observables, TAO report, ``converged``, ``verification``) and, with
        ``fields``, the local ``gap`` and ``pressure`` slabs.
    """
    ell = problem.scale_length
    x = (problem.initial_gap() if start is None else start).reshape(-1) / ell
    path = LoadPath()
    with BoundSolver(petsc, problem.grid, problem.hessian, problem.preconditioner) as solver:
        for p0 in check_pressures(pressures):
            problem.set_pressure(p0, path.stiffness_estimate(p0))
            problem.start(path.start(p0, x))
            x_new, info = solver.solve(
                problem.objective_gradient,
                problem.start_point,
                monitor=monitor,
                gatol_floor=problem.rounding_floor(p0),
            )
            step = measure(petsc, problem, x_new, info, stiffness, fields)
            if step.converged:
                x = x_new
                k = step.scalars.get("stiffness", np.nan)
                path.add(ConvergedStep(p0, step.scalars["mean_gap"], x, k))
            step.state = x.reshape(problem.grid.local_shape) * ell
            yield step


def measure(
    petsc: Any,
    problem: PeriodicProblem,
    x: np.ndarray,
    info: SolveInfo,
    stiffness: bool = False,
    fields: bool = False,
) -> Step:
    """The step of a solution ``x`` (TAO's scaled gap) at the problem's nominal pressure:
    observables, TAO's report, the package's verdict and, if asked, the exact stiffness."""
    grid, ell, p0 = problem.grid, problem.scale_length, problem.nominal_pressure
    gap = x.reshape(grid.local_shape) * ell
    pressure = problem.pressure(gap)
    obs = step_observables(grid, gap, pressure, problem.heights, p0, problem.pixel_stiffness)
    contact = obs.pop("contact")
    verdict = verify(info, obs, ell)
    scalars = {
        "nominal_pressure": p0,
        **obs,
        **info.scalars(verdict),
        "preconditioner_stiffness": problem.interfacial_stiffness,
    }
    if stiffness:
        k, its = (
            periodic_stiffness_exact(
                petsc,
                grid,
                problem.stiffness,
                problem.held_compliance(problem.interfacial_stiffness),
                contact,
            )
            if verdict == "ok"
            else (np.nan, 0)
        )
        scalars.update(stiffness=k, stiffness_iterations=its)
    return Step(scalars, gap if fields else None, pressure if fields else None)


def periodic_contact(
    heights: np.ndarray,
    length: float,
    modulus: float,
    pressures: Sequence[float],
    options: Sequence[str] | None = None,
    fields: bool = False,
    comm: Any = None,
    stiffness: bool = False,
) -> list[Step]:
    """Solve the periodic contact of ``heights`` for each nominal pressure.

    Parameters
    ----------
    heights
        The full ``n x n`` height map (every rank passes the same array or memory map).
    length, modulus
        Cell side ``L`` and contact modulus ``E*``.
    pressures
        Nominal pressures ``p0`` (same unit as ``modulus``), solved in order, warm-started.
    options
        PETSc options, e.g. ``["-tao_type", "bncg", "-tao_gatol", "1e-10"]``.
    fields
        Keep the local ``gap`` and ``pressure`` slabs of every step.
    comm
        mpi4py communicator (default ``COMM_WORLD``).
    stiffness
        Add the exact incremental stiffness ``stiffness`` to every step (see :func:`sweep`).

    Returns
    -------
    list of Step
    """
    from mpi4py import MPI

    with _petsc.scoped_options(options) as petsc:
        grid = Grid(int(heights.shape[0]), float(length), comm or MPI.COMM_WORLD)
        local = grid.scatter(heights)
        check_finite(grid, local)
        problem = PeriodicProblem(grid, make_fft(grid), local, modulus)
        return list(sweep(petsc, problem, pressures, fields, stiffness=stiffness))
