"""The periodic contact's steps: nominal pressures solved in order, each warm-started from the
last converged ones along the load path (:class:`~petsc_contact.physics.continuation.LoadPath`),
or prescribed mean gaps (displacement control), each reached by safeguarded Newton steps on
``-ln p0`` with the exact ``du_bar/d(-ln p0) = p0/K`` (:mod:`~petsc_contact.workflows.newton`).

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
from ..physics.theory import GAMMA
from ..solver.backends import BoundSolver
from .newton import Bracket, check_reached, newton

MEAN_GAP_RTOL = 1e-6  # Newton aims at a prescribed mean gap to this, relative
MEAN_GAP_RESOLVED = 1e-4  # a mean gap further than this from its target is not converged
DECADE = float(np.log(10.0))  # Newton's fallback step in -ln p0: a tenth of the pressure
UNRESOLVED_MEAN_GAP = (
    "the nominal pressure is lost in the tolerance on the pressure (a mean gap so close to "
    "full contact or first touch that this grid and tolerance do not resolve it)"
)


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
    steps = PeriodicSteps(problem, start, held)
    with nullcontext(solver) if solver is not None else problem_solver(problem) as solver:
        for p0 in loads:
            yield steps.at_pressure(solver, p0, fields, monitor, stiffness)


def mean_gap_sweep(
    problem: PeriodicProblem,
    mean_gaps: Sequence[float],
    fields: bool = False,
    monitor: Monitor | None = None,
    start: np.ndarray | None = None,
    solver: BoundSolver | None = None,
    held: Held | None = None,
) -> Iterator[Step]:
    """Solve the prescribed mean gaps in the given order (displacement control): each by
    Newton's steps on the nominal pressure (:meth:`PeriodicSteps.at_mean_gap`), each solve
    warm-started as :func:`sweep`'s.  The mean gaps are checked by the caller
    (:meth:`PeriodicProblem.check_mean_gap`); the other parameters are :func:`sweep`'s.
    Every step has the exact ``stiffness`` (Newton's derivative)."""
    targets = [float(g) for g in mean_gaps]
    steps = PeriodicSteps(problem, start, held)
    with nullcontext(solver) if solver is not None else problem_solver(problem) as solver:
        for mean_gap in targets:
            yield steps.at_mean_gap(solver, mean_gap, fields, monitor)


class PeriodicSteps:
    """The steps of one periodic problem, each from the last converged gap along its load
    path: at a nominal pressure (:meth:`at_pressure`) or at a mean gap (:meth:`at_mean_gap`).

    ``start`` is the local gap slab to begin from (default: first touch), ``held`` what the
    sweep that ended there held (:func:`sweep`)."""

    def __init__(
        self, problem: PeriodicProblem, start: np.ndarray | None, held: Held | None
    ) -> None:
        ell, device = problem.scale_length, problem.device
        if start is None:
            x = problem.initial_gap().reshape(-1)  # a field of its own: scaled in place
            x /= ell
        else:
            x = device.asarray(start).reshape(-1) / ell
        self.problem, self.x = problem, x
        self.path = (
            LoadPath() if held is None or start is None else _resumed_path(held, x, ell, device)
        )

    def at_pressure(
        self, solver: BoundSolver, p0: float, fields: bool, monitor: Monitor | None, stiffness: bool
    ) -> Step:
        """Solve at the nominal pressure ``p0`` by ``solver`` from the load path's start,
        held by the stiffness it predicts; a converged step joins the path."""
        problem, path = self.problem, self.path
        problem.set_pressure(p0, path.stiffness_estimate(p0))
        problem.start(path.start(p0, self.x))
        step, x_new = solve_step(solver, problem, problem.start_point, monitor, stiffness, fields)
        if step.converged:
            self.x = x_new
            k = step.scalars.get("stiffness", np.nan)
            path.add(ConvergedStep(p0, step.scalars["mean_gap"], x_new, k))
        shape = problem.grid.local_shape
        step.resume = _resume_point(self.x, path, problem.scale_length, problem.device, shape)
        return step

    def at_mean_gap(
        self,
        solver: BoundSolver,
        mean_gap: float,
        fields: bool,
        monitor: Monitor | None,
        rtol: float = MEAN_GAP_RTOL,
    ) -> Step:
        """Find ``p0`` with ``u_bar(p0) = mean_gap`` and solve there: safeguarded Newton
        (:func:`~petsc_contact.workflows.newton.newton`) on ``y = -ln p0``, where ``u_bar``
        increases with the exact slope ``p0/K`` (``K = -dp0/du_bar``, the held-set stiffness
        of every solve), to ``rtol`` times the nearer of the mean gap and the approach from
        first touch ``max(h) - mean(h) - mean_gap`` (near first touch ``u_bar`` hardly moves
        with ``p0``: a tolerance relative to ``u_bar`` alone would leave ``p0`` unresolved).

        The root lies above full contact's ``y`` (``u_bar = 0`` there) and at most at the
        smallest pressure the surface resolves (:meth:`PeriodicProblem.smallest_pressure`:
        beyond it the mean gap is out of reach, not converged).  Newton starts from the
        tangent at the last converged step, else from the exponential law
        ``u_bar = u0 ln(p_full/p0)``, ``u0 = gamma h_rms`` (paper Eqs. 1, 3), through full
        contact.  The step's scalars add ``target_mean_gap``, ``mean_gap_mismatch`` (the miss
        in units of that nearer length; beyond :data:`MEAN_GAP_RESOLVED` not converged),
        ``mean_gap_tolerance`` (``rtol``) and ``newton_iterations``; ``iterations`` and
        ``solve_time`` are summed over Newton.
        """
        problem = self.problem
        lowest, full = problem.smallest_pressure(), problem.full_contact_pressure()
        scale = min(mean_gap, problem.largest_mean_gap() - mean_gap)
        bracket = Bracket(
            mean_gap, -np.log(full), np.inf, lambda lo: lo + DECADE, ceiling=-np.log(lowest)
        )
        first = -np.log(full) + mean_gap / (GAMMA * problem.h_rms)
        end = newton(
            bracket,
            bracket.start(first, self._last_point()),
            lambda y: self.at_pressure(
                solver, max(float(np.exp(-y)), lowest), fields, monitor, True
            ),
            lambda s: (s["mean_gap"], _log_slope(s["nominal_pressure"], s["stiffness"])),
            rtol,
            "mean gap",
            f"it needs a nominal pressure below {lowest:.3g}, the smallest this surface resolves",
            scale,
        )
        s = end.step.scalars
        reached = f"mean gap {s['mean_gap']:.6g} reached, not {mean_gap:.6g}: "
        within = MEAN_GAP_RESOLVED * scale
        check_reached(s, s["mean_gap"], mean_gap, within, reached + UNRESOLVED_MEAN_GAP)
        s.update(
            target_mean_gap=mean_gap,
            mean_gap_mismatch=abs(s["mean_gap"] - mean_gap) / scale,
            mean_gap_tolerance=rtol,
            newton_iterations=end.count,
            iterations=end.iterations,
            solve_time=end.solve_time,
        )
        return end.step

    def _last_point(self) -> tuple[float, float, float] | None:
        """Newton's point of the last converged step (``-ln p0``, ``u_bar``, ``p0/K``)."""
        if not self.path.steps:
            return None
        last = self.path.steps[-1]
        return -np.log(last.pressure), last.mean_gap, _log_slope(last.pressure, last.stiffness)


def _log_slope(p0: float, stiffness: float) -> float:
    """``du_bar/d(-ln p0) = p0/K``, NaN where ``K`` is not a positive number."""
    return float(p0 / stiffness) if stiffness > 0 else np.nan


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
