"""The adhesive periodic contact's steps under load control, through a load cycle.

Each nominal pressure (any sign: tension is held by the attraction) is solved from the last
converged gap, the previous step of its branch, never extrapolated (the energy is not convex:
a start on the other side of a jump would land on the other branch).  Every step records
``branch_jump`` (its contact area misses the tangent of its branch through the last two
converged steps by more than :data:`JUMP_AREA` of the larger of it and the last one's, a jump
into or out of contact, warned about loudly: :class:`BranchJump`), and a step under tension
whose surfaces came apart beyond the law's range is not converged: ``verification`` says
``pulled off``.  :func:`pull_off_pressure` reads the pull-off from the steps of an unloading
branch; each step records it as it stands.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator, Sequence
from contextlib import nullcontext
from typing import Any

import numpy as np

from ..backend.solve import Monitor
from ..geometries.adhesive_periodic import AdhesivePeriodicProblem
from ..geometries.step import Step, solve_step
from ..solver.backends import BoundSolver
from .periodic_steps import problem_solver

MACHINE_RTOL = 1e-6  # displacement control: the mean gap to this of its target
MACHINE_ITERATIONS = 20  # the anchor's corrections at most (each one solve)
JUMP_AREA = 0.5  # an area this far (of the larger area) off its branch's tangent: a jump
SUMMED = (  # a mean gap's solver counts, summed over its solves
    "iterations",
    "objective_gradient_evaluations",
    "hessian_applications",
    "preconditioner_applications",
    "solve_time",
)


class BranchJump(UserWarning):
    """A step whose contact area jumped from the last converged one's (module docstring)."""


def adhesive_sweep(
    problem: AdhesivePeriodicProblem,
    pressures: Sequence[float],
    fields: bool = False,
    monitor: Monitor | None = None,
    start: np.ndarray | None = None,
    solver: BoundSolver | None = None,
) -> Iterator[Step]:
    """Solve the nominal pressures in the given order (a cycle: down into compression and
    back into tension), each from the last converged gap (``start``, a local gap slab, for
    the first; default: first touch).  ``solver`` as :func:`~petsc_contact.workflows.
    periodic_steps.sweep` takes it; every step adds ``branch_jump`` (module docstring) and
    ``pull_off_pressure``, :func:`pull_off_pressure` of the steps so far."""
    ell, device = problem.scale_length, problem.device
    x = (problem.initial_gap() if start is None else device.asarray(start)).reshape(-1) / ell
    held: list[tuple[float, float]] = []  # the converged steps' (p0, area)
    done: list[dict[str, Any]] = []
    with nullcontext(solver) if solver is not None else problem_solver(problem) as solver:
        for p0 in (float(p) for p in pressures):
            problem.set_pressure(p0)
            problem.start(x)
            watch = problem.separation_monitor(monitor)
            step, x_new = solve_step(solver, problem, problem.start_point, watch, False, fields)
            note_jump(step.scalars, held)
            done.append(step.scalars)
            step.scalars["pull_off_pressure"] = pull_off_pressure(done)[0]
            if step.converged:
                x = x_new
                held.append((p0, step.scalars["area_fraction"]))
            yield step


def adhesive_mean_gap_sweep(
    problem: AdhesivePeriodicProblem,
    mean_gaps: Sequence[float],
    fields: bool = False,
    monitor: Monitor | None = None,
    start: np.ndarray | None = None,
    solver: BoundSolver | None = None,
) -> Iterator[Step]:
    """Solve the prescribed mean gaps in the given order (displacement control: down into
    contact and back up through the pull-off), each from the last converged gap, held by the
    loading machine (:meth:`~petsc_contact.geometries.adhesive_periodic.
    AdhesivePeriodicProblem.set_machine`) whose anchor starts on the branch's tangent and is
    corrected until the mean gap is within :data:`MACHINE_RTOL` of its target
    (:func:`_at_mean_gap`).  Each step adds ``target_mean_gap``, ``mean_gap_mismatch``
    (beyond :data:`MACHINE_RTOL` after :data:`MACHINE_ITERATIONS`: not converged),
    ``branch_jump`` and ``pull_off_pressure`` (the most tensile ``p0`` with contact from the
    smallest mean gap on); the counts of :data:`SUMMED` are summed over its solves."""
    ell, device = problem.scale_length, problem.device
    x = (problem.initial_gap() if start is None else device.asarray(start)).reshape(-1) / ell
    held: list[tuple[float, float]] = []
    branch: list[tuple[float, float]] = []  # the converged steps' (mean gap, p0)
    done: list[dict[str, Any]] = []
    scale = problem.adhesion.strength
    with nullcontext(solver) if solver is not None else problem_solver(problem) as solver:
        for target in (float(g) for g in mean_gaps):
            guess = predicted_pressure(branch, target)
            step, x = _at_mean_gap(problem, solver, x, target, (scale, guess), fields, monitor)
            s = step.scalars
            note_jump(s, held, -target)  # a smaller gap is a larger load
            done.append(s)
            s["pull_off_pressure"] = pull_off_pressure(done)[0]
            if step.converged:
                held.append((-target, s["area_fraction"]))
                branch.append((target, s["nominal_pressure"]))
                scale = max(abs(s["nominal_pressure"]), problem.adhesion.strength)
            yield step


def predicted_pressure(branch: Sequence[tuple[float, float]], target: float) -> float:
    """The nominal pressure at the mean gap ``target`` on the tangent of its branch through the
    last two converged ``(mean gap, p0)`` (the last ``p0`` after the first; 0 before)."""
    if not branch:
        return 0.0
    g_last, p_last = branch[-1]
    if len(branch) == 1 or branch[-2][0] == g_last:
        return p_last
    g_prev, p_prev = branch[-2]
    return p_last + (p_last - p_prev) / (g_last - g_prev) * (target - g_last)


def _at_mean_gap(
    problem: AdhesivePeriodicProblem,
    solver: BoundSolver,
    x: Any,
    target: float,
    pressures: tuple[float, float],
    fields: bool,
    monitor: Monitor | None,
) -> tuple[Step, Any]:
    """One prescribed mean gap (:func:`adhesive_mean_gap_sweep`): the step and the gap to go
    on from (``x`` unless it converged).  ``pressures`` are the pressure scale and the
    predicted nominal pressure ``p*`` (:func:`predicted_pressure`): the first anchor is
    ``t - p*/k_m``, where the machine holds ``t`` under ``p*``; each next one corrects the last
    by its miss times the secant ``da/dg`` of the solves so far (1 after the first: the machine
    is stiffer than the contact)."""
    scale, guess = pressures
    anchor = target - guess / float(problem.pixel_stiffness)
    counts: dict[str, float] = dict.fromkeys(SUMMED, 0)
    last: tuple[float, float] | None = None  # the last solve's (anchor, mean gap)
    for _ in range(MACHINE_ITERATIONS):
        problem.set_machine(anchor, scale)
        problem.start(x)
        step, x_new = solve_step(solver, problem, problem.start_point, monitor, False, fields)
        counts = {k: v + step.scalars[k] for k, v in counts.items()}
        reached = step.scalars["mean_gap"]
        miss = target - reached
        if not step.converged:
            break
        slope = 1.0  # da/dg before a secant: the machine is far stiffer than the contact
        if last is not None and reached != last[1]:
            slope = (anchor - last[0]) / (reached - last[1])
        x, last, anchor = x_new, (anchor, reached), anchor + miss * slope
        if abs(miss) <= MACHINE_RTOL * target:
            break
    s = step.scalars
    s.update(target_mean_gap=target, mean_gap_mismatch=abs(miss) / target, **counts)
    if s["converged"] and abs(miss) > MACHINE_RTOL * target:
        s["converged"] = False
        s["verification"] = f"mean gap {s['mean_gap']:.6g} reached, not {target:.6g}"
    return step, x


def note_jump(
    scalars: dict[str, Any], held: Sequence[tuple[float, float]], control: float | None = None
) -> None:
    """Record ``branch_jump`` in a step's ``scalars`` and warn (:class:`BranchJump`) where its
    area misses the one its branch predicts by more than :data:`JUMP_AREA` of the larger of
    it and the last converged step's.  ``held`` are the converged steps' ``(p0, area)`` so
    far (``control``: the load, by default ``p0``; under displacement control minus the mean
    gap): the prediction is the tangent through the last two (the last area alone after the
    first); a step that did not converge, or the first, is not judged."""
    area, p0 = scalars["area_fraction"], scalars["nominal_pressure"]
    load = p0 if control is None else control
    jumped = False
    if scalars["converged"] and held:
        p_last, a_last = held[-1]
        predicted = a_last
        if len(held) > 1 and held[-2][0] != p_last:
            p_prev, a_prev = held[-2]
            predicted += (a_last - a_prev) / (p_last - p_prev) * (load - p_last)
        jumped = abs(area - predicted) > JUMP_AREA * max(area, a_last)
    scalars["branch_jump"] = jumped
    if jumped:
        warnings.warn(
            f"at p0 = {p0:.4g} the contact area jumped from {held[-1][1]:.4g} to {area:.4g} "
            "of the cell: the step left its branch (a jump into or out of contact)",
            BranchJump,
            stacklevel=2,
        )


def pull_off_pressure(steps: Sequence[dict[str, Any]]) -> tuple[float, bool]:
    """The pull-off estimate of a load cycle's step ``scalars``: the most tensile converged
    nominal pressure with contact on the unloading branch (the steps after the largest
    pressure), and whether it is bracketed (a more tensile step of that branch pulled off).
    NaN where the unloading branch has no converged step in contact."""
    loads = [s["nominal_pressure"] for s in steps]
    unloading = steps[int(np.argmax(loads)) :] if loads else []
    held = [s for s in unloading if s["converged"] and s["area_fraction"] > 0]
    if not held:
        return np.nan, False
    p_off = min(s["nominal_pressure"] for s in held)
    bracketed = any(not s["converged"] and s["nominal_pressure"] < p_off for s in unloading)
    return float(p_off), bracketed
