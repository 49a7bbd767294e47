"""Solver comparison on one periodic scene: error against wall time for each TAO type.

Every solver is measured with the same errors, computed by the package from the iterate at
each TAO iteration (never TAO's own gnorm, which means different things for different types):

- ``mean_gap_error``: ``|u_bar - u_bar_ref| / u_bar_ref`` (over ``h_rms`` at full contact);
- ``pressure_error``: ``||p - p_ref||_2 / ||p_ref||_2`` (``p = K(g + h) + p0``);
- ``natural_residual``: ``rms(min(k g, p)) / p0``, zero exactly at the solution (KKT): the
  projected-gradient norm ``||g - P(g - grad/(a^2 k))||`` (``P`` the projection on
  ``g >= 0``, step ``1/k`` with ``k`` the pixel stiffness), in units of ``p0``;
- ``complementarity``: ``sum(p+ g) / (sum(p+) h_rms)``, as Tamaas reports it (``h_rms``
  replaced by the problem's length scale for a flat surface).

With a hardness cap the scene is posed in the pressure (:class:`PressurePosed`): the
reference reaches ``mean(p) = p0`` by Newton on the approach, every solver solves at that
approach, and the natural residual is the box's (``0 <= p <= H``), in units of ``p0``.
With an adhesive law the cell is posed in the gap with the law's energy
(:class:`AdhesivePosed`): the reference is ``blmvm`` at the same tolerance, the natural
residual the law's, ``rms(min(k g, p + phi'(g))) / p0``, and the package's CG (``cg``,
``pk``: a QP solver) is refused, a solver that failed saying why; the punch with an
adhesive law is compared so from Python (:class:`AdhesivePunchPosed`, measured on its
footprint).

The reference is the default solver at ``REFERENCE_GATOL`` (or the rounding floor); its own
natural residual is stored, so the reference's accuracy is stated next to every error.
The time axis excludes the cost of these measurements (one FFT per iteration).

Solvers are named by TAO type (``tron``, ``bncg``, ...), ``cg`` (the default, a
Fourier-preconditioned constrained CG), ``pk`` (Polonsky-Keer, unpreconditioned), or a path
to a PETSc options file (``my-bqnls.opts``).  Each solver of :data:`DEFAULT_SOLVERS` runs with
the options file the package ships for it (:data:`OPTIONS`, ``options/NAME.opts``: what makes
it converge); a path runs that file instead, and any other TAO type runs as
``-tao_type TYPE``.
"""

from __future__ import annotations

import json
import os
import shlex
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..backend import _petsc
from ..backend.solve import BOUND_TYPES, BoundSolver, SolveInfo
from ..backend.tao import PetscBackend
from ..conventions.warnings import user_level
from ..geometries.adhesive_periodic import QP_ONLY, AdhesivePeriodicProblem
from ..geometries.adhesive_punch import AdhesivePunchProblem
from ..geometries.capped_periodic import CappedPeriodicProblem
from ..geometries.periodic import PeriodicProblem
from ..geometries.punch import PressureProblem
from ..geometries.step import residual_verdict, solve_step
from ..interactions.adhesion import Adhesion
from ..interactions.hard_wall import HARD_WALL
from ..interactions.interaction import Interaction
from ..io.atomic import atomic_h5, on_root, replaced, storage
from ..io.names import partial_path
from ..io.partial import check_same_input, check_same_run, commit, discard, opened
from ..io.plot import plot_compare
from ..io.results import group_name, labelled, scale
from ..io.schema import COMPARE, annotate, write_attributes
from ..io.store import check_resume_or_overwrite, remove_temporaries, warn_replaced
from ..physics.observables import natural_residual
from ..physics.surface import rms_of
from .periodic_steps import sweep
from .punch_steps import PunchSolver, capped_from_wall

REFERENCE_GATOL = 1e-12
STALL_GAIN = 0.9  # a new low of the natural residual must be 10% below the best so far
DEFAULT_SOLVERS = ("cg", "pk", "tron", "bnls", "bntr", "bqnls", "blmvm", "bncg", "gpcg")
OPTIONS = Path(__file__).resolve().parents[1] / "options"
"""The options file of each solver of :data:`DEFAULT_SOLVERS`, ``NAME.opts``, shipped with the
package (the repository's ``options/`` links here)."""


def solver_options(name: str) -> list[str]:
    """PETSc options that select a solver: ``-options_file`` with the package's file
    ``NAME.opts`` (every solver of :data:`DEFAULT_SOLVERS` has one; ``bqpip`` and ``tight``
    too) or with the file ``name`` is a path to, else ``-tao_type name`` for a
    bound-constrained TAO type; ``OSError`` (one line) where a file of
    :data:`DEFAULT_SOLVERS` is missing, ``ValueError`` (one line) for a name that is none of
    these."""
    if name.endswith(".opts") or os.sep in name:
        if not os.path.isfile(name):
            raise OSError(f"options file '{name}' does not exist")
        return ["-options_file", name]
    shipped = OPTIONS / f"{name}.opts"
    if name not in DEFAULT_SOLVERS and not shipped.is_file():
        if name not in BOUND_TYPES or name == "python":
            files = sorted(p.stem for p in OPTIONS.glob("*.opts"))
            known = [*DEFAULT_SOLVERS, *files, *BOUND_TYPES]
            others = [t for i, t in enumerate(known) if t not in known[:i] and t != "python"]
            raise ValueError(
                f"--solvers: unknown solver '{name}'; choose from "
                f"{', '.join(others)}, or give an options file (NAME.opts)"
            )
        return ["-tao_type", name]
    if not shipped.is_file():
        raise OSError(
            f"the options file of solver '{name}' is missing: {shipped} (reinstall the package)"
        )
    return ["-options_file", str(shipped)]


def own_options(options: Sequence[str], name: str, solvers: Sequence[str]) -> list[str]:
    """The command line's PETSc ``options`` that solver ``name`` of a comparison of
    ``solvers`` runs with: those that name no solver, and those with its own prefix, without
    it (``-bncg_tao_max_it 50`` is ``-tao_max_it 50`` for ``bncg`` alone).  A solver's prefix
    is its name (its group in the file) and an underscore."""
    prefixes = {f"-{group_name(other)}_": other for other in solvers}
    own, keep = [], True
    for token in options:
        if _petsc.is_petsc_option(token):
            prefix = next((p for p in prefixes if token.startswith(p)), None)
            keep = prefix is None or prefixes[prefix] == name
            if keep:
                own.append(token if prefix is None else "-" + token.removeprefix(prefix))
        elif keep:
            own.append(token)
    return own


def run_options(name: str, solvers: Sequence[str], options: Sequence[str]) -> list[str]:
    """The PETSc options solver ``name`` of a comparison of ``solvers`` runs with: its own
    (:func:`solver_options`) then its share of the command line's ``options``
    (:func:`own_options`), which therefore win."""
    return solver_options(name) + own_options(options, name, solvers)


def shared_options(options: Sequence[str], solvers: Sequence[str]) -> list[str]:
    """The command line's PETSc ``options`` that name no solver of ``solvers`` (every
    solver's); those with a solver's prefix reach that solver alone (:func:`own_options`)."""
    return own_options(options, "", solvers)


def unchanged(
    done: Sequence[Trajectory], solvers: Sequence[str], options: Sequence[str]
) -> list[Trajectory]:
    """The solvers of ``done`` (an interrupted comparison's) that ran with the options they
    would run with now (:func:`run_options`, and what their options file says); one whose
    options changed is solved again."""
    kept = []
    for t in done:
        now = run_options(t.name, solvers, options)
        if t.options == now and t.options_file_text == options_file_text(now):
            kept.append(t)
    return kept


def check_solvers(solvers: Sequence[str]) -> None:
    """``ValueError`` (one line) unless ``solvers`` names at least one solver and no two
    share a group of the file; ``OSError`` where an options file is missing."""
    if not solvers:
        raise ValueError("--solvers names no solver: give cg,tron,... or leave it out")
    groups = [group_name(name) for name in solvers]
    twice = sorted({n for n, g in zip(solvers, groups, strict=True) if groups.count(g) > 1})
    if twice:
        raise ValueError(f"--solvers names a solver twice (each is one group): {', '.join(twice)}")
    for name in solvers:
        solver_options(name)


@dataclass
class Trajectory:
    """Errors of one solver along its iterations (and its final TAO report)."""

    name: str
    options: list[str] = field(default_factory=list)  # the PETSc options it ran with
    time: list[float] = field(default_factory=list)
    iteration: list[int] = field(default_factory=list)
    mean_gap_error: list[float] = field(default_factory=list)
    pressure_error: list[float] = field(default_factory=list)
    natural_residual: list[float] = field(default_factory=list)
    complementarity: list[float] = field(default_factory=list)
    reason: str = ""
    solve_time: float = float("nan")
    iterations: int = 0
    converged: bool = False
    verification: str = ""
    options_file_text: str | None = None  # what its -options_file said when it ran

    def __post_init__(self) -> None:
        if self.options_file_text is None:
            self.options_file_text = options_file_text(self.options)


def options_file_text(options: Sequence[str]) -> str:
    """What the ``-options_file`` among ``options`` says now (``""`` without one)."""
    if "-options_file" not in options:
        return ""
    with open(options[list(options).index("-options_file") + 1]) as opts:
        return opts.read()


@dataclass
class Reference:
    """The tight solve every trajectory is measured against."""

    pressure: np.ndarray  # local slab
    mean_gap: float
    natural_residual: float
    tolerance: float
    iterations: int

    def scalars(self) -> dict[str, Any]:
        """What is stored with the comparison (``reference_*`` attributes)."""
        return {
            "mean_gap": self.mean_gap,
            "natural_residual": self.natural_residual,
            "tolerance": self.tolerance,
            "iterations": self.iterations,
        }


def reference_solve(problem: PeriodicProblem, pressure: float) -> Reference:
    """The default solver at ``REFERENCE_GATOL`` (or the rounding floor); raises if it fails
    (``ValueError`` for a pressure ``problem`` does not resolve:
    :meth:`~petsc_contact.geometries.periodic.PeriodicProblem.check_pressure`)."""
    problem.check_pressure(pressure)
    gatol = max(REFERENCE_GATOL, problem.stiffness_rounding_floor(pressure))
    with _petsc.scoped_options(["-tao_gatol", str(gatol)]):
        (step,) = sweep(problem, [pressure], fields=True)
    if not step.converged or step.pressure is None:
        raise RuntimeError(f"reference solve failed: {step.scalars['verification']}")
    s = step.scalars
    return Reference(
        step.pressure, s["mean_gap"], s["kkt_residual"], s["tolerance"], s["iterations"]
    )


class GapPosed:
    """What :func:`compare` asks of the periodic cell posed in the gap (the package's own
    problem): its reference, its first touch, and the gap and pressure of an iterate."""

    def __init__(self, problem: PeriodicProblem) -> None:
        self.problem = problem
        self.grid, self.scale_length = problem.grid, problem.scale_length

    def reference(self, pressure: float) -> Reference:
        """:func:`reference_solve`."""
        return reference_solve(self.problem, pressure)

    def pose(self, pressure: float, backend: PetscBackend) -> tuple[np.ndarray, float]:
        """Posed at ``pressure`` for ``backend``: the first touch (TAO's scaled gap) and the
        gradient tolerance's rounding floor."""
        problem = self.problem
        x0 = problem.initial_gap().reshape(-1) / problem.scale_length
        problem.use(backend)
        problem.set_pressure(pressure)
        problem.start(x0)
        return x0, problem.rounding_floor(pressure)

    def tolerance_unit(self) -> float:
        """The natural residual over ``p0`` is in the unit of TAO's tolerance: 1."""
        return 1.0

    def refusal(self, backend: PetscBackend) -> str | None:
        """Why ``backend``'s solver cannot solve the problem: never."""
        return None

    def fields(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The gap, the pressure and the natural residual (a pressure) of TAO's iterate."""
        problem = self.problem
        gap = x.reshape(problem.grid.local_shape) * problem.scale_length
        p = problem.pressure(gap)
        return gap, p, natural_residual(gap, p, problem.pixel_stiffness)


class AdhesivePosed(GapPosed):
    """The periodic cell with an adhesive law, posed in the gap with the law's energy
    (:class:`~petsc_contact.geometries.adhesive_periodic.AdhesivePeriodicProblem`): what
    :func:`compare` asks of it, as of :class:`GapPosed`, with the law's natural residual and
    pressure scale, a ``blmvm`` reference and the package's CG refused."""

    problem: AdhesivePeriodicProblem

    def __init__(self, problem: AdhesivePeriodicProblem) -> None:
        super().__init__(problem)
        self.nominal = np.nan

    def reference(self, pressure: float) -> Reference:
        """``blmvm`` at :data:`REFERENCE_GATOL` (or the rounding floor) from first touch;
        raises if it fails.  Its pressure is the elastic one, tension included."""
        problem = self.problem
        with _petsc.scoped_options(["-tao_type", "blmvm", "-tao_gatol", str(REFERENCE_GATOL)]):
            backend = PetscBackend()
            x0, _ = self.pose(pressure, backend)
            with backend.solver(problem) as solver:
                watch = problem.separation_monitor(None)
                step, x = solve_step(solver, problem, x0, watch)
        if not step.converged:
            raise RuntimeError(f"reference solve failed: {step.scalars['verification']}")
        _, p, r = self.fields(x)
        (r2,) = self.grid.sum(np.vdot(r, r))
        s = step.scalars
        rms = float(np.sqrt(r2 / self.grid.size)) / pressure
        return Reference(p, s["mean_gap"], rms, s["tolerance"], s["iterations"])

    def pose(self, pressure: float, backend: PetscBackend) -> tuple[np.ndarray, float]:
        """As :meth:`GapPosed.pose`, with the law's floor (in units of ``P``)."""
        x0, _ = super().pose(pressure, backend)
        self.nominal = pressure
        return x0, self.problem.tolerance_floor()

    def tolerance_unit(self) -> float:
        """The natural residual over ``p0`` in the unit of TAO's tolerance: ``p0 / P``."""
        return self.nominal / self.problem.pressure_scale

    def refusal(self, backend: PetscBackend) -> str | None:
        """The package's CG (a QP solver) cannot: its one-line refusal."""
        return QP_ONLY if backend.runs_default_type else None

    def fields(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The gap, the pressure and the law's natural residual, ``min(k g, p + phi'(g))``."""
        gap, p, _ = super().fields(x)
        k = self.problem.pixel_stiffness
        return gap, p, k * self.problem.adhesion.residual(gap, p, k)


class AdhesivePunchPosed(AdhesivePosed):
    """The punch with an adhesive law (:class:`~petsc_contact.geometries.adhesive_punch.
    AdhesivePunchProblem`) at a nominal pressure over its face: as :class:`AdhesivePosed`,
    measured on the footprint grid (the solver's unknown is the padded cell's; the traction
    off the face is left out of the natural residual)."""

    problem: AdhesivePunchProblem

    def __init__(self, problem: AdhesivePunchProblem) -> None:
        super().__init__(problem)
        self.grid = problem.face_grid

    def fields(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The footprint's gap, pressure and law's natural residual (0 off the footprint)."""
        problem = self.problem
        gap = x.reshape(problem.grid.local_shape) * problem.scale_length
        gap, p = problem.to_face(gap), problem.to_face(problem.pressure(gap))
        k, on = problem.pixel_stiffness, problem.footprint
        attraction = problem.adhesion.derivative(np.where(on, gap, np.inf))
        return gap, p, np.where(on, np.minimum(k * gap, p + attraction), 0.0)


class PressurePosed:
    """What :func:`compare` asks of a problem posed in the pressure: the periodic cell under a
    hardness cap (:class:`~petsc_contact.geometries.capped_periodic.CappedPeriodicProblem`) or
    the punch.  The reference reaches ``mean(p) = p0`` (over the face) by Newton on the
    approach; every solver then solves at that approach, from no pressure."""

    def __init__(self, problem: PressureProblem, wall: PeriodicProblem | None = None) -> None:
        self.problem, self.wall = problem, wall
        self.grid, self.scale_length = problem.grid, problem.scale_length
        self.approach = self.nominal = np.nan

    def reference(self, pressure: float) -> Reference:
        """The default solver at :data:`REFERENCE_GATOL`, Newton to ``mean(p) = p0``: from
        the hard wall's answer at ``p0`` where the cell's ``wall`` is given
        (:func:`~petsc_contact.workflows.punch_steps.capped_from_wall`), else from none."""
        problem, start = self.problem, None
        if self.wall is not None:
            (start,) = sweep(self.wall, [pressure], fields=True)
        tight = ["-tao_gatol", str(REFERENCE_GATOL)]
        with _petsc.scoped_options(tight), PunchSolver(problem) as solver:
            if start is None:
                step = solver.at_force(pressure * problem.grid.area)
            else:
                mean_gap = start.scalars["mean_gap"]
                step = capped_from_wall(solver, pressure, start.pressure, mean_gap)
            x = solver.x
        if not step.converged:
            raise RuntimeError(f"reference solve failed: {step.scalars['verification']}")
        self.approach = problem.approach
        gap, p, r = self.fields(x)
        (r2,) = self.grid.sum(np.vdot(r, r))
        s = step.scalars
        rms = float(np.sqrt(r2 / self.grid.size)) / pressure
        return Reference(p, s["mean_gap"], rms, s["tolerance"], s["iterations"])

    def pose(self, pressure: float, backend: PetscBackend) -> tuple[np.ndarray, float]:
        """At the reference's approach: no pressure (TAO's scaled pressure), no floor."""
        self.problem.backend = backend
        self.problem.set_approach(self.approach)
        self.nominal = pressure
        return np.zeros(self.grid.local_shape).reshape(-1), 0.0

    def tolerance_unit(self) -> float:
        """The natural residual over ``p0`` in the unit of TAO's tolerance (the gap's over
        the rms height): ``p0 / (k h_rms)``."""
        problem = self.problem
        return self.nominal / (problem.pixel_stiffness * problem.scale_length)

    def fields(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The gap, the pressure and the natural residual (a pressure, the interaction's) of
        TAO's iterate."""
        problem = self.problem
        p = x.reshape(problem.grid.local_shape) * problem.pressure_scale
        gap = problem.gap(p)
        k = problem.pixel_stiffness
        return gap, p, k * problem.interaction.residual(gap, p, k)

    def refusal(self, backend: PetscBackend) -> str | None:
        """Why ``backend``'s solver cannot solve the problem: never."""
        return None


Posed = GapPosed | PressurePosed


class _Recorder:
    """The TAO monitor of one trajectory: measures the iterate, decides when to stop.

    The time spent measuring is kept apart (:attr:`spent`) so that the time axis is the
    solver's own.
    """

    def __init__(
        self,
        problem: Posed,
        reference: Reference,
        nominal_pressure: float,
        traj: Trajectory,
        solver: BoundSolver,
        time_limit: float,
        stall_iterations: int,
    ) -> None:
        self.problem, self.reference, self.p0 = problem, reference, nominal_pressure
        self.traj, self.solver = traj, solver
        self.time_limit, self.stall_iterations = time_limit, stall_iterations
        grid = problem.grid
        self.u_scale = reference.mean_gap if reference.mean_gap > 0 else problem.scale_length
        (self.p_ref_norm,) = np.sqrt(grid.sum(np.vdot(reference.pressure, reference.pressure)))
        self.spent = 0.0
        self.best = (np.inf, 0)  # lowest natural residual so far, and its iteration
        self.stop: list[str] = []
        self.start = time.perf_counter()

    def __call__(self, it: int, f: float, gnorm: float) -> bool:
        t_in = time.perf_counter()
        problem, grid, traj = self.problem, self.problem.grid, self.traj
        gap, p, r = problem.fields(self.solver.x.array_r)
        pp = np.maximum(p, 0.0)
        dp = p - self.reference.pressure
        g_sum, dp2, r2, pg, p_sum = grid.sum(
            gap.sum(), np.vdot(dp, dp), np.vdot(r, r), np.vdot(pp, np.maximum(gap, 0.0)), pp.sum()
        )
        traj.iteration.append(int(it))
        # the slowest rank's time, so that every rank stops at the same iteration
        traj.time.append(grid.max(t_in - self.start - self.spent))
        traj.mean_gap_error.append(abs(g_sum / grid.size - self.reference.mean_gap) / self.u_scale)
        traj.pressure_error.append(float(np.sqrt(dp2)) / self.p_ref_norm)
        traj.natural_residual.append(float(np.sqrt(r2 / grid.size)) / self.p0)
        traj.complementarity.append(pg / (p_sum * problem.scale_length) if p_sum > 0 else 0.0)
        self._check_stop(it)
        self.spent += time.perf_counter() - t_in
        return bool(self.stop)

    def _check_stop(self, it: int) -> None:
        residual = self.traj.natural_residual[-1]
        if residual < STALL_GAIN * self.best[0]:
            self.best = (residual, it)
        if self.traj.time[-1] > self.time_limit:
            self.stop.append(f"time limit {self.time_limit:g} s")
        elif self.stall_iterations and it - self.best[1] >= self.stall_iterations:
            self.stop.append(
                f"stalled: natural residual not 10% below its best "
                f"{self.best[0]:.1e} in {self.stall_iterations} iterations"
            )


def _conclude(traj: Trajectory, info: SolveInfo, recorder: _Recorder) -> None:
    """Fill in the final report; converged only if TAO says so *and* the residual agrees."""
    traj.reason = f"{info.reason} ({recorder.stop[0]})" if recorder.stop else info.reason
    traj.solve_time = info.solve_time - recorder.spent
    traj.iterations = info.iterations
    final = traj.natural_residual[-1] if traj.natural_residual else np.inf
    verdict = residual_verdict(final * recorder.problem.tolerance_unit(), info.tolerance)
    traj.converged = info.reason_code > 0 and verdict == "ok"
    traj.verification = verdict if info.reason_code > 0 else f"TAO: {info.reason}"


def compare(
    problem: PeriodicProblem | Posed,
    pressure: float,
    solvers: Sequence[str],
    time_limit: float = 120.0,
    extra_options: Sequence[str] = (),
    stall_iterations: int = 1000,
    report: Callable[[Trajectory], None] | None = None,
    done: Sequence[Trajectory] = (),
    reference_ready: Callable[[dict[str, Any]], None] | None = None,
) -> tuple[dict[str, Any], list[Trajectory]]:
    """Run each solver from first touch and record its error against time.

    Each solver runs with :func:`solver_options` then its share of ``extra_options``
    (:func:`own_options`: those of every solver and those with its prefix, ``-bncg_...``),
    which therefore win over its options file; both are recorded (:attr:`Trajectory.options`).

    The solvers of ``done`` (an interrupted comparison's, :func:`read_partial`) that ran with
    the options they would run with now are kept as they are and not run again
    (:func:`unchanged`); the reference is solved again (the same solve, so the same
    reference).  ``reference_ready(scalars)`` is called once the reference is solved.

    A solver is stopped (``DIVERGED_USER``, with the cause in its reason) after
    ``time_limit`` seconds, or once its natural residual has not fallen 10% below its best
    for ``stall_iterations`` iterations (0: never): a solver stuck at its own floor (BQNLS's
    line search at ``~1e-8 p0``) then does not spend the whole time limit there.
    ``report(trajectory)`` is called as each solver finishes.

    Returns
    -------
    reference, trajectories
        ``reference`` holds the reference solution's scalars (``mean_gap``,
        ``natural_residual``, ``tolerance``, ``iterations``); one :class:`Trajectory` per
        solver, in order.
    """
    check_solvers(solvers)
    posed = GapPosed(problem) if isinstance(problem, PeriodicProblem) else problem
    reference = posed.reference(pressure)
    if reference_ready is not None:
        reference_ready(reference.scalars())
    kept = {t.name: t for t in unchanged(done, solvers, extra_options)}
    out = []
    for name in solvers:
        if name in kept:
            out.append(kept[name])
            continue
        opts = run_options(name, solvers, extra_options)
        traj = _trajectory(posed, reference, pressure, Trajectory(name, opts), time_limit,
                           stall_iterations)  # fmt: skip
        out.append(traj)
        if report is not None:
            report(traj)
    return reference.scalars(), out


def _trajectory(
    posed: Posed,
    reference: Reference,
    pressure: float,
    traj: Trajectory,
    time_limit: float,
    stall_iterations: int,
) -> Trajectory:
    """Run one solver (its options in ``traj``) from first touch, recording ``traj``."""
    problem = posed.problem
    with _petsc.scoped_options(traj.options):
        backend = PetscBackend()  # this solver's options, its two-level form's among them
        refused = posed.refusal(backend)
        if refused is not None:  # a failed solver, saying why
            traj.reason = traj.verification = f"refused: {refused}"
            return traj
        x0, floor = posed.pose(pressure, backend)
        with backend.solver(problem) as s:
            recorder = _Recorder(posed, reference, pressure, traj, s, time_limit, stall_iterations)
            _, info = s.solve(
                problem.objective_gradient,
                x0,
                lower=problem.lower_bound,
                monitor=recorder,
                upper=problem.upper_bound,
                gatol_floor=floor,
            )
    _conclude(traj, info, recorder)
    return traj


def check_comparison(
    solvers: Sequence[str] | None,
    time_limit: float,
    stall_iterations: int,
    extra_options: Sequence[str] = (),
) -> list[str]:
    """The solvers a comparison runs (:data:`DEFAULT_SOLVERS` for ``None``), after checking
    them and its limits before any work (``ValueError`` in one line)."""
    if not time_limit >= 0 or stall_iterations < 0:
        raise ValueError("--time-limit and --stall-iterations must not be negative")
    if "-tao_type" in extra_options:  # it would follow, and replace, every solver's own
        raise ValueError("compare takes its solvers from --solvers, not -tao_type")
    chosen = list(DEFAULT_SOLVERS) if solvers is None else list(solvers)
    check_solvers(chosen)
    return chosen


@dataclass
class Comparison:
    """What :func:`compare_into` computed and wrote: the reference's scalars, one
    :class:`Trajectory` per solver, and the table and plot beside the output (rank 0's;
    ``""`` on the other ranks)."""

    reference: dict[str, Any]
    trajectories: list[Trajectory]
    csv: str = ""
    png: str = ""

    @property
    def converged(self) -> bool:
        """Whether every solver converged (the same on every rank)."""
        return all(t.converged for t in self.trajectories)


def compare_into(
    output: str,
    scene: Any,
    modulus: float,
    pressure: float,
    record: Callable[[dict[str, Any]], dict[str, Any]],
    solvers: Sequence[str],
    time_limit: float = 120.0,
    stall_iterations: int = 1000,
    extra_options: Sequence[str] = (),
    resume: bool = False,
    overwrite: bool = False,
    report: Callable[[Trajectory], None] | None = None,
    interaction: Interaction = HARD_WALL,
) -> Comparison:
    """:func:`compare` on a prepared ``scene`` at ``pressure``, durable solver by solver in
    ``output``'s ``.partial`` file (the caller holds the output's lock), then written whole:
    ``output``, its table and its plot (:func:`write_compare`).

    ``record(realised)`` is the run record of the scene for the realised ``rms_height`` and
    ``pressure``; the comparison's own parameters are added to it.  An interrupted
    comparison goes on with ``resume`` or starts afresh with ``overwrite``
    (:func:`finished_solvers`); a finished solver whose options changed is solved again.
    ``report(trajectory)`` is called with each finished solver: first those an interrupted
    comparison kept, then each as it is committed.  An ``interaction`` that caps the pressure
    (a hardness) poses the cell in the pressure (:class:`PressurePosed`), an adhesive law in
    the gap with its energy (:class:`AdhesivePosed`).
    """
    grid, fft, heights = scene.grid, scene.fft, scene.heights
    problem = posed_cell(scene, modulus, interaction)
    realised = {"rms_height": rms_of(grid, fft, heights), "pressure": pressure}  # collective
    attrs = record(realised)
    attrs["parameters"] |= _parameters(pressure, solvers, time_limit, stall_iterations)
    finished = finished_solvers(
        output, attrs["parameters"], resume, overwrite, attrs.get("heights_sha256")
    )
    done = unchanged(finished, solvers, extra_options)  # those whose options changed run again
    if report is not None:
        for trajectory in done:
            report(trajectory)
    kept = list(done)
    solved: dict[str, Any] = {}  # the reference's scalars, which every commit records

    def committed(trajectory: Trajectory) -> None:
        """Commit the finished solver ``trajectory`` (rank 0 writes), then report it."""
        kept.append(trajectory)
        on_root(grid.comm, lambda: commit_partial(output, solved, kept, attrs))
        if report is not None:
            report(trajectory)

    reference, trajectories = compare(
        problem, pressure, solvers, time_limit,
        extra_options,  # after each solver's options file: the command line wins
        stall_iterations=stall_iterations, report=committed, done=done,
        reference_ready=solved.update,
    )  # fmt: skip
    result = Comparison(reference, trajectories)
    if grid.comm.rank == 0:  # the verdicts come from reduced residuals: the same on every rank
        result.csv, result.png = write_compare(output, reference, trajectories, attrs)
    return result


def posed_cell(scene: Any, modulus: float, interaction: Interaction) -> PeriodicProblem | Posed:
    """The periodic cell of ``scene``: posed in the gap (the hard wall; with an adhesive law's
    energy, :class:`AdhesivePosed`), or in the pressure for an ``interaction`` that caps it
    (:class:`PressurePosed`)."""
    grid, fft, heights = scene.grid, scene.fft, scene.heights
    if interaction is HARD_WALL:
        return PeriodicProblem(grid, fft, heights, modulus)
    if isinstance(interaction, Adhesion):
        return AdhesivePosed(AdhesivePeriodicProblem(grid, fft, heights, modulus, interaction))
    capped = CappedPeriodicProblem(grid, fft, heights, modulus, interaction)
    return PressurePosed(capped, PeriodicProblem(grid, fft, heights, modulus))


def _parameters(
    pressure: float, solvers: Sequence[str], time_limit: float, stall_iterations: int
) -> dict[str, Any]:
    """What a comparison is, beyond its scene: added to its run record's ``parameters``."""
    return {
        "command": "compare",
        "pressure": pressure,
        "solvers": list(solvers),
        "time_limit": time_limit,
        "stall_iterations": stall_iterations,
    }


def write_compare(
    path: str,
    reference: dict[str, Any],
    trajectories: Sequence[Trajectory],
    attributes: dict[str, Any],
) -> tuple[str, str]:
    """HDF5 (one group per solver), a CSV table and a PNG of error against time; the
    comparison's ``.partial`` file is removed once the HDF5 file is written (a failure to
    write the table or the plot then leaves the whole comparison, which ``--resume`` draws
    again, and no stale ``.partial`` beside it).

    Returns the CSV and PNG paths (next to ``path``).
    """
    stem = path[:-3] if path.endswith(".h5") else path
    with atomic_h5(path) as f:
        _write_groups(f, reference, trajectories, {**attributes, "complete": True})
    discard(path)
    csv = stem + ".csv"
    with storage(csv), replaced(csv) as temporary, open(temporary, "w") as f:
        f.write(
            "solver,reason,converged,iterations,time_s,mean_gap_error,pressure_error,"
            "natural_residual,complementarity\n"
        )
        for row in table_rows(trajectories):
            f.write(",".join(str(v) for v in row) + "\n")
    png = stem + ".png"
    plot_compare(png, trajectories, reference)
    remove_temporaries(path)  # of writers killed before this one
    return csv, png


def commit_partial(
    path: str,
    reference: dict[str, Any],
    trajectories: Sequence[Trajectory],
    attributes: dict[str, Any],
) -> None:
    """Replace ``path + '.partial'`` by one holding every finished solver (atomically,
    :func:`~petsc_contact.io.partial.commit`)."""
    record = _record(reference, trajectories, {**attributes, "complete": False})
    commit(path, record, lambda f: _write_trajectories(f, trajectories))


def finished_solvers(
    path: str, parameters: dict[str, Any], resume: bool, overwrite: bool, digest: str | None = None
) -> list[Trajectory]:
    """What a comparison into ``path`` starts from (the caller holds the output's lock): with
    ``resume``, the finished solvers of its ``.partial`` file or, without one, of its complete
    output, measured against a reference of the same map (of digest ``digest``;
    :func:`read_partial`); with
    ``overwrite``, none, that file removed (by rank 0); with neither, none, and
    ``ValueError`` where that file holds finished solvers."""
    from ..conventions.grid import world

    partial = partial_path(path)
    check_resume_or_overwrite(resume, overwrite)
    if resume:
        return read_partial(path, parameters, digest)
    if os.path.exists(partial) and not overwrite:
        raise ValueError(
            f"'{partial}' holds the finished solvers of an interrupted comparison: --resume "
            "continues it, --overwrite deletes them and starts afresh"
        )
    if not overwrite:
        warn_replaced(path, stacklevel=user_level())
    on_root(world(), lambda: discard(path))
    return []


def read_partial(
    path: str, parameters: dict[str, Any], digest: str | None = None
) -> list[Trajectory]:
    """The finished solvers of an interrupted comparison into ``path`` (its ``.partial``), or
    of its complete output where no ``.partial`` is left (every solver: only the reference
    is solved again); none without either.  ``ValueError`` when the file was run with other
    parameters or on another map than the one of digest ``digest`` (its solvers' errors are
    against that map's reference; ``--overwrite`` replaces it), or cannot be read."""
    partial = partial_path(path)
    source = partial if os.path.exists(partial) else path
    if not os.path.exists(source):
        return []
    try:
        with opened(source) as f:
            try:
                check_same_run(source, json.loads(f.attrs["parameters"]), parameters)
            except ValueError as exc:
                raise ValueError(f"{exc}; --overwrite replaces it") from None
            check_same_input(source, f.attrs.get("heights_sha256"), digest)
            out = []
            for name in json.loads(f.attrs["solvers"]):
                g = f[group_name(name)]
                ran = shlex.split(str(g.attrs["petsc_options"]))
                t = Trajectory(
                    name, ran, options_file_text=str(g.attrs.get("options_file_text", ""))
                )
                for k in COMPARE:
                    setattr(t, k, g[k][...].tolist())
                t.reason, t.verification = str(g.attrs["reason"]), str(g.attrs["verification"])
                t.solve_time, t.iterations = (
                    float(g.attrs["solve_time"]),
                    int(g.attrs["iterations"]),
                )
                t.converged = bool(g.attrs["converged"])
                out.append(t)
    except (OSError, KeyError) as exc:
        raise ValueError(
            f"cannot resume '{source}': it is damaged ({exc}); --overwrite starts afresh"
        ) from None
    return out


def _write_groups(
    f: Any, reference: dict[str, Any], trajectories: Sequence[Trajectory], attrs: dict[str, Any]
) -> None:
    """A comparison's file ``f``: its record (:func:`_record`) and a group per solver."""
    write_attributes(f, _record(reference, trajectories, attrs))
    _write_trajectories(f, trajectories)


def _record(
    reference: dict[str, Any], trajectories: Sequence[Trajectory], attrs: dict[str, Any]
) -> dict[str, Any]:
    """A comparison file's attributes: ``attrs``, its solvers and the reference's scalars."""
    return {
        **attrs,
        "solvers": [t.name for t in trajectories],
        **{f"reference_{k}": v for k, v in reference.items()},
    }


def _write_trajectories(f: Any, trajectories: Sequence[Trajectory]) -> None:
    """One group per solver in the open comparison file ``f``."""
    for t in trajectories:
        g = f.create_group(group_name(t.name))
        iteration = scale(g, "iteration", t.iteration)
        for k in COMPARE:
            if k != "iteration":
                labelled(g, k, getattr(t, k), [iteration])
        annotate(g, COMPARE.__getitem__)
        for k in ("reason", "solve_time", "iterations", "converged", "verification"):
            g.attrs[k] = getattr(t, k)
        g.attrs["petsc_options"] = shlex.join(t.options)
        if t.options_file_text:  # what the file said when it ran
            g.attrs["options_file_text"] = t.options_file_text


def table_rows(trajectories: Sequence[Trajectory]) -> list[tuple[Any, ...]]:
    """One row per solver: name, reason, converged, iterations, time, final errors."""

    def last(v: Sequence[float]) -> float:
        return v[-1] if v else float("nan")

    rows = []
    for t in trajectories:
        rows.append(
            (
                t.name,
                t.reason,
                t.converged,
                t.iterations,
                round(t.solve_time, 4),
                last(t.mean_gap_error),
                last(t.pressure_error),
                last(t.natural_residual),
                last(t.complementarity),
            )
        )
    return rows
