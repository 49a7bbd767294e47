"""The punch's steps: a problem posed in the pressure (:class:`~petsc_contact.geometries.punch.
PressureProblem`: the punch, the capped periodic cell) pressed along a list of approaches or
forces, each solve warm-started from the last converged pressure.

Load control (``forces=``) wraps the displacement-controlled solve in a safeguarded Newton
iteration on ``δ`` that uses the exact ``dF/dδ`` (:mod:`~petsc_contact.workflows.newton`);
``F(δ)`` is increasing and convex.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np

from ..backend.solve import Monitor
from ..conventions.validation import positive
from ..geometries.capped_periodic import CappedPeriodicProblem
from ..geometries.punch import PressureProblem
from ..geometries.step import Step, solve_step
from ..physics.continuation import Held
from ..solver.backends import BoundSolver
from ..solver.report import FORCE_ACCURACY
from .newton import Bracket, check_reached, newton

FORCE_RTOL = 1e-6
FORCE_RESOLVED = FORCE_ACCURACY  # a force further than this from its target is not converged


def punch_solver(problem: PressureProblem) -> BoundSolver:
    """The solver of the displacement-controlled ``problem``: its backend's (TAO, or the
    package's CG on the device's arrays)."""
    return problem.backend.solver(problem)


class PunchSolver:
    """Displacement- and load-controlled solves of one :class:`PressureProblem` (warm-started).

    The load control (:meth:`at_force`) is written once around the displacement-controlled
    solves of :func:`punch_solver`, whichever backend the problem has.
    """

    def __init__(self, problem: PressureProblem) -> None:
        self.problem = problem
        self.x = problem.device.xp.zeros(int(np.prod(problem.grid.local_shape)))
        self.solver = punch_solver(problem)
        self.last: tuple[float, float, float] | None = None  # (δ, F, dF/dδ) of the last step

    @property
    def k_flat(self) -> float:
        """The flat-punch stiffness in use (:attr:`PressureProblem.k_flat`)."""
        return self.problem.k_flat

    @property
    def k_flat_analytic(self) -> float:
        return self.problem.k_flat_analytic

    def close(self) -> None:
        self.solver.close()

    def __enter__(self) -> PunchSolver:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def at_approach(
        self,
        delta: float,
        fields: bool = False,
        monitor: Monitor | None = None,
        stiffness: bool = False,
    ) -> Step:
        """Solve at approach ``δ`` from the last converged pressure."""
        pb = self.problem
        pb.set_approach(delta)
        step, x_new = solve_step(self.solver, pb, self.x, monitor, stiffness, fields)
        if step.converged:
            self.x = x_new
            s = step.scalars
            self.last = (float(delta), s["force"], s["total_stiffness"])
        x, last, scale, shape = self.x, self.last, pb.pressure_scale, pb.grid.local_shape
        device = pb.device  # not the problem: a step kept must not keep its operators

        def resume_point() -> tuple[np.ndarray, Held]:  # taken when read (x never changes)
            state = device.to_host(x).reshape(shape) * scale
            return state, Held(np.array([last] if last is not None else []).reshape(-1, 3))

        step.resume = resume_point
        return step

    def restart_from(self, pressure: np.ndarray, held: Held | None = None) -> None:
        """Start the next solve from this local pressure slab (a resumed run's state); with
        what the interrupted sweep ``held`` (its last step's ``held``: the approach, force and
        ``dF/dδ`` Newton starts from), go on exactly as it would have."""
        pb = self.problem
        self.x = (pb.device.asarray(pressure, dtype=float) / pb.pressure_scale).reshape(-1)
        last = held.scalars[-1] if held is not None and len(held.scalars) else None
        self.last = None if last is None else (float(last[0]), float(last[1]), float(last[2]))

    def at_force(
        self,
        force: float,
        fields: bool = False,
        rtol: float = FORCE_RTOL,
        monitor: Monitor | None = None,
        stiffness: bool = False,
        start: float | None = None,
    ) -> Step:
        """Find ``δ`` with ``F(δ) = force`` (relative tolerance ``rtol``) and solve there.

        Safeguarded Newton on the increasing, convex ``F(δ)`` with the exact ``dF/dδ``.  It
        starts from the last converged step, whose approach brackets the root and whose
        tangent is the first Newton step (on a convex ``F`` that step lands above the root,
        and Newton then descends to it monotonically); a first solve starts from
        ``force / K_flat`` (a rough punch is never stiffer than the flat one).  The step's
        scalars add ``target_force``, ``newton_iterations`` and ``force_balance``,
        ``|F - force| / force``, which the step's ``accurate`` weighs with the rest of its
        measured accuracy (:meth:`PressureProblem.accuracy`).

        Newton also stops when TAO accepts its warm start at the new approach without an
        iteration: the solve cannot tell the two approaches apart, and the force (stored next
        to ``target_force``) is as close to the target as the solve resolves, on contacts of
        a few pixels about ``1e-5`` (the gradient tolerance is an rms over the footprint).
        ``start`` replaces ``force / K_flat`` as the first approach when no step converged
        before (:meth:`restart_from` without ``held``).  A force further than
        :data:`FORCE_RESOLVED` from its target (a load so small that its approach is lost in
        the tolerance, force 0) is not converged, and says why.
        """
        positive("force", force)
        bracket = Bracket(force, 0.0, np.inf, lambda lo: 2 * lo + self.problem.scale_length)
        first = force / self.k_flat_analytic if start is None else start
        delta = bracket.start(first, self.last)
        end = newton(
            bracket,
            delta,
            lambda d: self.at_approach(d, fields, monitor, stiffness),
            lambda s: (s["force"], s["total_stiffness"]),
            rtol,
            "force",
        )
        s = end.step.scalars
        check_reached(
            s,
            s["force"],
            force,
            FORCE_RESOLVED * force,
            f"force {s['force']:.6g} reached, not {force:.6g}: the approach is lost in the "
            "tolerance on the gap (a load below what this grid resolves, or a loose tolerance)",
        )
        s.update(
            target_force=force,
            force_balance=abs(s["force"] - force) / force,
            newton_iterations=end.count,
            iterations=end.iterations,
            solve_time=end.solve_time,
        )
        self.problem.accuracy().assess(s)
        return end.step


def capped_from_wall(
    solver: PunchSolver,
    p0: float,
    wall_pressure: Any,
    wall_mean_gap: float,
    fields: bool = False,
    monitor: Monitor | None = None,
    stiffness: bool = False,
) -> Step:
    """The capped cell of ``solver`` (:class:`~petsc_contact.geometries.capped_periodic.
    CappedPeriodicProblem`) at the nominal pressure ``p0`` from the hard wall's answer there:
    its pressure (a local slab) clipped to the bounds, Newton from its approach (of its
    mean gap, :meth:`~petsc_contact.geometries.capped_periodic.CappedPeriodicProblem.
    approach_at`), the whole cell's force ``p0 A`` the target."""
    problem = solver.problem
    assert isinstance(problem, CappedPeriodicProblem)  # the punch has no hard wall's cell
    upper = problem.upper_bound.reshape(problem.grid.local_shape) * problem.pressure_scale
    xp = problem.device.xp
    solver.restart_from(xp.minimum(xp.maximum(wall_pressure, 0.0), upper))
    start = problem.approach_at(p0, wall_mean_gap)
    force = p0 * problem.grid.area
    return solver.at_force(force, fields, monitor=monitor, stiffness=stiffness, start=start)


def punch_sweep(
    solver: PunchSolver,
    loads: Sequence[float],
    by_force: bool,
    fields: bool = False,
    monitor: Monitor | None = None,
    stiffness: bool = False,
    start: np.ndarray | None = None,
    held: Held | None = None,
) -> Iterator[Step]:
    """Solve the approaches (or, ``by_force``, the forces) in order, each from the last
    converged pressure: the punch's counterpart of
    :func:`~petsc_contact.workflows.periodic_sweep.sweep`.

    ``start`` is a local pressure slab to begin from (a resumed run's last state), ``held``
    what the interrupted sweep held (:meth:`PunchSolver.restart_from`)."""
    if start is not None:
        solver.restart_from(start, held)
    for v in loads:
        if by_force:
            yield solver.at_force(v, fields, monitor=monitor, stiffness=stiffness)
        else:
            yield solver.at_approach(v, fields, monitor, stiffness)
