"""The periodic contact's steps: nominal pressures solved in order, each warm-started from the
last converged ones along the load path (:class:`~petsc_contact.physics.continuation.LoadPath`).

Every step is verified by the package itself, not only by TAO: it is ``converged`` when TAO
reports convergence, no gap is negative and the natural residual ``rms(min(k g, p))/p0``
is within ten times the tolerance TAO was asked for; and ``accurate`` when its measured
accuracy (natural residual, force balance, complementarity, the stiffness solve's residual)
is within the package's, whatever the tolerance asked for (:mod:`petsc_contact.solver.report`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from contextlib import nullcontext
from typing import Any

import numpy as np

from ..backend.solve import Monitor
from ..geometries.periodic import PeriodicProblem
from ..geometries.step import Step, solve_step
from ..io.progress import StepReport
from ..physics.continuation import ConvergedStep, Held, LoadPath
from ..solver.backends import BoundSolver


def problem_solver(problem: PeriodicProblem) -> BoundSolver:
    """The solver of ``problem``: its backend's (TAO, or the package's CG on the device's
    arrays: :class:`~petsc_contact.solver.backends.SolverBackend`)."""
    return problem.backend.solver(problem)


def sweep(
    problem: PeriodicProblem,
    pressures: Sequence[float],
    fields: bool = False,
    monitor: Monitor | None = None,
    stiffness: bool = False,
    start: np.ndarray | None = None,
    solver: BoundSolver | None = None,
    held: Held | None = None,
) -> Iterator[Step]:
    """Solve the pressures in the given order, each warm-started from the last converged steps.

    Each step starts from the last converged gap, extrapolated along the load path, and its
    preconditioner is held by the interfacial stiffness the path predicts
    (:class:`~petsc_contact.physics.continuation.LoadPath`; Persson's estimate for the first step).

    Parameters
    ----------
    pressures
        Nominal pressures, checked positive where they were given
        (:class:`~petsc_contact.workflows.description.Run`, :func:`check_pressures`) and
        against what ``problem`` resolves (:meth:`PeriodicProblem.check_pressure`) by the
        caller: a run's driver (before the output is touched), :func:`periodic_contact`.
    stiffness
        Add ``stiffness``, the exact ``-dp0/du_bar`` with the contact set held fixed
        (:func:`~petsc_contact.backend.stiffness.periodic_stiffness_exact`), and its CG iterations.
    start
        Local gap slab to start from (e.g. a resumed run's last state); default: first touch.
    solver
        The TAO solver to use (kept open); default: one made for this sweep and closed after.
    held
        What the sweep that ended with ``start`` held (its last step's ``held``): given, this
        sweep goes on exactly as that one would have (the same starts and preconditioners).

    Yields
    ------
    Step
        Scalars (observables, TAO report, ``converged``, ``accurate``, ``verification``)
        and, with ``fields``, the local ``gap`` and ``pressure`` slabs.
    """
    loads = [float(p) for p in pressures]
    ell, device = problem.scale_length, problem.device
    x = (problem.initial_gap() if start is None else device.asarray(start)).reshape(-1) / ell
    path = LoadPath() if held is None or start is None else _resumed_path(held, x, ell, device)
    with nullcontext(solver) if solver is not None else problem_solver(problem) as solver:
        for p0 in loads:
            problem.set_pressure(p0, path.stiffness_estimate(p0))
            problem.start(path.start(p0, x))
            step, x_new = solve_step(
                solver, problem, problem.start_point, monitor, stiffness, fields
            )
            if step.converged:
                x = x_new
                k = step.scalars.get("stiffness", np.nan)
                path.add(ConvergedStep(p0, step.scalars["mean_gap"], x, k))
            step.resume = _resume_point(x, path, ell, device, problem.grid.local_shape)
            yield step


def _resume_point(
    x: Any, path: LoadPath, ell: float, device: Any, shape: tuple[int, ...]
) -> Callable[[], tuple[np.ndarray, Held]]:
    """What makes a step's state (the gap ``x`` the next step starts from, on the host) and
    what the sweep holds after it: its load path's pressures, mean gaps and stiffnesses, and
    the older of its two gaps.  Taken when read (the arrays are never changed in place)."""
    steps = list(path.steps)

    def make() -> tuple[np.ndarray, Held]:
        scalars = np.array([[s.pressure, s.mean_gap, s.stiffness] for s in steps])
        older = tuple(device.to_host(s.gap).reshape(shape) * ell for s in steps[:-1])
        state = device.to_host(x).reshape(shape) * ell
        return state, Held(scalars.reshape(-1, 3), older)

    return make


def _resumed_path(held: Held, x: Any, ell: float, device: Any) -> LoadPath:
    """The load path :func:`_held` recorded, its newest gap the start ``x`` (solver units)."""
    if not len(held.scalars):
        return LoadPath()
    gaps = [device.asarray(f).reshape(-1) / ell for f in held.fields] + [x]
    rows = [(float(p), float(u), float(k)) for p, u, k in held.scalars]
    return LoadPath(
        [ConvergedStep(p, u, gap, k) for (p, u, k), gap in zip(rows, gaps, strict=True)]
    )


Progress = StepReport
"""Called as ``progress(index, total, scalars)`` after each step (``index`` from 0; the
table and ``--step`` number that step ``index + 1``; a resumed run reports only the steps
it solves, its earlier ones are in the result's table).  Where a run takes it, ``True``
(the default) is a progress bar where a person watches, ``False`` or ``None`` nothing
(:func:`~petsc_contact.io.progress.reporting`)."""
