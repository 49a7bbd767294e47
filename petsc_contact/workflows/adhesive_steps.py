"""The adhesive periodic contact's steps under load control, through a load cycle.

Each nominal pressure (any sign: tension is held by the attraction) is solved from the last
converged gap, the previous step of its branch, never extrapolated (the energy is not convex:
a start on the other side of a jump would land on the other branch).  Every step records
``branch_jump`` (its contact area misses the tangent of its branch through the last two
converged steps by more than :data:`JUMP_AREA` of the larger of it and the last one's, a jump
into or out of contact, warned about loudly: :class:`BranchJump`), and a step under tension
whose surfaces came apart beyond the law's range is not converged: ``verification`` says
``pulled off``.  :func:`pull_off_pressure` reads the pull-off from the steps of an unloading
branch; each step records it as it stands, and under displacement control the energy the
cycle lost (:func:`hysteresis_energy`) once it is back at its first mean gap.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import nullcontext
from typing import Any

import numpy as np

from ..backend.solve import Monitor
from ..geometries.adhesive_periodic import AdhesivePeriodicProblem
from ..geometries.step import Step, solve_step
from ..physics.continuation import Held
from ..solver.backends import BoundSolver
from .periodic_steps import problem_solver

MACHINE_RTOL = 1e-6  # displacement control: the mean gap to this of its target
MACHINE_ITERATIONS = 20  # the anchor's corrections at most (each one solve)
RESTARTS = 3  # a machine's solve that stopped short is started again from its end this often
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
    approach: Callable[[float], None] | None = None,
    *,
    earlier: Sequence[dict[str, Any]] = (),
) -> Iterator[Step]:
    """Solve the nominal pressures in the given order (a cycle: down into compression and
    back into tension), each from the last converged gap (``start``, a local gap slab, for
    the first; default: first touch).  ``solver`` as :func:`~petsc_contact.workflows.
    periodic_steps.sweep` takes it; every step adds ``branch_jump`` (module docstring) and
    ``pull_off_pressure``, :func:`pull_off_pressure` of the steps so far: ``earlier`` (the
    scalars of the steps of the sweep that ended with ``start``, a resumed run's committed
    table) and these.  Each step's state (:attr:`~petsc_contact.geometries.step.Step.state`)
    is the gap the next starts from.  ``approach`` (the punch's
    :meth:`~petsc_contact.geometries.adhesive_punch.AdhesivePunchProblem.set_approach`) makes
    the loads approaches, prescribed in its place: displacement control, each branch judged
    along the approach, by its area and its force (:func:`note_force_jump`), from first
    touch (no ``earlier``)."""
    if approach is not None and earlier:
        raise ValueError("an approach-controlled adhesive sweep starts from first touch")
    x = _first_gap(problem, start)
    done = list(earlier)
    controls: list[float] | None = None if approach is None else []
    forces: list[tuple[float, float]] = []  # the converged steps' (approach, force)
    with nullcontext(solver) if solver is not None else problem_solver(problem) as solver:
        for load in (float(p) for p in pressures):
            (problem.set_pressure if approach is None else approach)(load)
            problem.start(x)
            watch = problem.separation_monitor(monitor)
            step, x_new = solve_step(solver, problem, problem.start_point, watch, False, fields)
            _judge(step.scalars, done, controls, forces, load)
            x = x_new if step.converged else x
            step.resume = _resume_point(problem, x)
            yield step


def adhesive_mean_gap_sweep(
    problem: AdhesivePeriodicProblem,
    mean_gaps: Sequence[float],
    fields: bool = False,
    monitor: Monitor | None = None,
    start: np.ndarray | None = None,
    solver: BoundSolver | None = None,
    *,
    earlier: Sequence[dict[str, Any]] = (),
) -> Iterator[Step]:
    """Solve the prescribed mean gaps in the given order (displacement control: down into
    contact and back up through the pull-off), each from the last converged gap, held by the
    loading machine (:meth:`~petsc_contact.geometries.adhesive_periodic.
    AdhesivePeriodicProblem.set_machine`) whose anchor starts on the branch's tangent and is
    corrected until the mean gap is within :data:`MACHINE_RTOL` of its target
    (:func:`_at_mean_gap`), its pressure scale the last converged step's.  Each step adds
    ``target_mean_gap``, ``mean_gap_mismatch`` (beyond :data:`MACHINE_RTOL` after
    :data:`MACHINE_ITERATIONS`: not converged), ``branch_jump``, ``pull_off_pressure`` (the
    most tensile ``p0`` with contact from the smallest mean gap on) and
    ``hysteresis_energy`` (:func:`hysteresis_energy` of the steps so far: ``earlier`` and
    these, as :func:`adhesive_sweep`'s); the counts of :data:`SUMMED` are summed over its
    solves."""
    x = _first_gap(problem, start)
    done = list(earlier)
    with nullcontext(solver) if solver is not None else problem_solver(problem) as solver:
        for target in (float(g) for g in mean_gaps):
            held = converged_loads(done, by_mean_gap=True)
            pressures = (_machine_scale(problem, done), predicted_pressure(done, target))
            step, x = _at_mean_gap(problem, solver, x, target, pressures, fields, monitor)
            s = step.scalars
            note_jump(s, held, -target)  # a smaller gap is a larger load
            done.append(s)
            s["pull_off_pressure"] = pull_off_pressure(done)[0]
            s["hysteresis_energy"] = hysteresis_energy(done)
            step.resume = _resume_point(problem, x)
            yield step


def _judge(
    scalars: dict[str, Any],
    done: list[dict[str, Any]],
    controls: list[float] | None,
    forces: list[tuple[float, float]],
    load: float,
) -> None:
    """Add a step's ``branch_jump`` and ``pull_off_pressure`` to its ``scalars``, the steps
    ``done`` before it (appended to) its history: judged along the nominal pressure, or
    along the approaches ``controls`` (appended to) by its area and, since the last jump, by
    its force against ``forces`` (:func:`note_force_jump`; updated)."""
    if controls is None:
        note_jump(scalars, converged_loads(done))
    else:
        held = [(c, s["area_fraction"]) for c, s in zip(controls, done, strict=True)]
        note_jump(scalars, [h for h, s in zip(held, done, strict=True) if s["converged"]], load)
        controls.append(load)
        note_force_jump(scalars, forces, load)
        if scalars["converged"]:
            if scalars["branch_jump"]:  # the force's branch starts afresh
                forces.clear()
            forces.append((load, scalars.get("force", np.nan)))
    done.append(scalars)
    scalars["pull_off_pressure"] = pull_off_pressure(done, controls)[0]


def _first_gap(problem: AdhesivePeriodicProblem, start: np.ndarray | None) -> Any:
    """The first step's start in the solver's units: the local gap slab ``start`` (a
    resumed run's state), or first touch."""
    gap = problem.initial_gap() if start is None else problem.device.asarray(start)
    return gap.reshape(-1) / problem.scale_length


def _resume_point(
    problem: AdhesivePeriodicProblem, x: Any
) -> Callable[[], tuple[np.ndarray, Held]]:
    """What makes a step's state: the gap ``x`` the next step starts from, a local slab on
    the host; the sweep holds nothing else (its history is its steps' scalars).  Taken when
    read (``x`` is never changed in place)."""
    shape, ell, device = problem.grid.local_shape, problem.scale_length, problem.device
    return lambda: (device.to_host(x).reshape(shape) * ell, Held())


def converged_loads(
    steps: Sequence[dict[str, Any]], by_mean_gap: bool = False
) -> list[tuple[float, float]]:
    """The ``(load, area)`` of the converged ``steps`` (``scalars``), as :func:`note_jump`
    judges a step against: the load is ``p0``, or minus the prescribed mean gap under
    displacement control (``by_mean_gap``: a smaller gap is a larger load)."""
    load = "target_mean_gap" if by_mean_gap else "nominal_pressure"
    sign = -1.0 if by_mean_gap else 1.0
    return [(sign * s[load], s["area_fraction"]) for s in steps if s["converged"]]


def _machine_scale(problem: AdhesivePeriodicProblem, steps: Sequence[dict[str, Any]]) -> float:
    """The loading machine's pressure scale: the last converged step's ``|p0|``, at least
    the law's strength ``w/rho``."""
    held = [abs(s["nominal_pressure"]) for s in steps if s["converged"]]
    return max(held[-1], problem.adhesion.strength) if held else problem.adhesion.strength


def predicted_pressure(steps: Sequence[dict[str, Any]], target: float) -> float:
    """The nominal pressure at the mean gap ``target`` on its branch's :func:`tangent`
    through the converged ``steps`` (``scalars``: their ``target_mean_gap`` and ``p0``); 0
    before the first."""
    branch = [(s["target_mean_gap"], s["nominal_pressure"]) for s in steps if s["converged"]]
    return tangent(branch, target) if branch else 0.0


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
    is stiffer than the contact).  A solve that stops short is started again from where it
    stopped, at most :data:`RESTARTS` times: a long descent (a pull-off, the whole neck let
    go) ends where the objective's change from its start, large, hides the last decreases in
    rounding (TAO's line search fails) or where the limited memory holds the law's curvature
    of the way there (BLMVM then stalls just above ``gatol``); from its own end neither
    holds, and the descent goes on."""
    scale, guess = pressures
    anchor = target - guess / float(problem.pixel_stiffness)
    counts: dict[str, float] = dict.fromkeys(SUMMED, 0)
    last: tuple[float, float] | None = None  # the last solve's (anchor, mean gap)
    restarts = RESTARTS
    for _ in range(MACHINE_ITERATIONS + RESTARTS):
        problem.set_machine(anchor, scale)
        problem.start(x)
        step, x_new = solve_step(solver, problem, problem.start_point, monitor, False, fields)
        counts = {k: v + step.scalars[k] for k, v in counts.items()}
        reached = step.scalars["mean_gap"]
        miss = target - reached
        if not step.converged and restarts and np.isfinite(miss):
            x, restarts = x_new, restarts - 1
            continue
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
    gap, or the punch's approach): the prediction is the tangent through the last two (the
    last area alone after the first); a step that did not converge, or the first, is not
    judged, and one whose area is the last one's (still apart, say) never jumped."""
    area, p0 = scalars["area_fraction"], scalars["nominal_pressure"]
    load = p0 if control is None else control
    jumped = False
    if scalars["converged"] and held:
        a_last = held[-1][1]
        predicted = tangent(held, load)
        jumped = area != a_last and abs(area - predicted) > JUMP_AREA * max(area, a_last)
    scalars["branch_jump"] = jumped
    if jumped:
        warnings.warn(
            f"at p0 = {p0:.4g} the contact area jumped from {held[-1][1]:.4g} to {area:.4g} "
            "of the cell: the step left its branch (a jump into or out of contact)",
            BranchJump,
            stacklevel=2,
        )


def tangent(held: Sequence[tuple[float, float]], load: float) -> float:
    """What a branch predicts at ``load`` from its converged ``(load, value)`` pairs
    ``held`` (one at least): the tangent through the last two, the last value alone after
    the first."""
    p_last, v_last = held[-1]
    predicted = v_last
    if len(held) > 1 and held[-2][0] != p_last:
        p_prev, v_prev = held[-2]
        predicted += (v_last - v_prev) / (p_last - p_prev) * (load - p_last)
    return predicted


def note_force_jump(
    scalars: dict[str, Any], held: Sequence[tuple[float, float]], approach: float
) -> None:
    """Under the punch's approach control, where the area may not tell (a contact that
    shrinks fast before it jumps out of contact): set ``branch_jump`` and warn where the force
    misses its branch's tangent through the last two converged ``held`` ``(approach,
    force)`` by more than :data:`JUMP_AREA` of the largest force, in magnitude, of it and
    them (the steps since the last jump).  A step already flagged, one that did not
    converge, or one with fewer than two before it is not judged."""
    force = scalars["force"]
    if scalars["branch_jump"] or not scalars["converged"] or len(held) < 2:
        return
    largest = max(abs(force), *(abs(f) for _, f in held))
    if abs(force - tangent(held, approach)) > JUMP_AREA * largest:
        scalars["branch_jump"] = True
        warnings.warn(
            f"at the approach {approach:.4g} the force jumped from {held[-1][1]:.4g} to "
            f"{force:.4g}: the step left its branch (a jump into or out of contact)",
            BranchJump,
            stacklevel=2,
        )


def pull_off_pressure(
    steps: Sequence[dict[str, Any]], controls: Sequence[float] | None = None
) -> tuple[float, bool]:
    """The pull-off estimate of a load cycle's step ``scalars``: the most tensile converged
    nominal pressure with contact on the unloading branch (the steps after the largest
    load: ``controls``, each step's, by default its nominal pressure; the punch's approach
    under displacement control), and whether it is bracketed (a more tensile step of that
    branch pulled off).  NaN where the unloading branch has no converged step in contact."""
    loads = [s["nominal_pressure"] for s in steps] if controls is None else list(controls)
    unloading = steps[int(np.argmax(loads)) :] if loads else []
    held = [s for s in unloading if s["converged"] and s["area_fraction"] > 0]
    if not held:
        return np.nan, False
    p_off = min(s["nominal_pressure"] for s in held)
    bracketed = any(not s["converged"] and s["nominal_pressure"] < p_off for s in unloading)
    return float(p_off), bracketed


def hysteresis_energy(steps: Sequence[dict[str, Any]]) -> float:
    """The energy per apparent area a displacement-controlled cycle's steps (``scalars``)
    lost: the work the loading machine did on the cell, ``-sum (p0_k + p0_k+1)/2 (u_k+1 -
    u_k)`` over consecutive steps' nominal pressures ``p0`` and mean gaps ``u`` (trapezoids; a
    jump, a change of ``p0`` between two steps, is closed by the chord between them), which is
    ``-closed integral p0 du`` once the last step is back at the first one's target mean gap
    (the states alike).  NaN before, and where a step did not converge."""
    if len(steps) < 3 or steps[-1]["target_mean_gap"] != steps[0]["target_mean_gap"]:
        return np.nan
    if not all(s["converged"] for s in steps):
        return np.nan
    u = np.array([s["mean_gap"] for s in steps])
    p0 = np.array([s["nominal_pressure"] for s in steps])
    return float(-np.sum(0.5 * (p0[1:] + p0[:-1]) * np.diff(u)))
