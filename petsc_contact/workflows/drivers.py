"""What :mod:`~petsc_contact.workflows.runner` runs for each geometry: a :class:`Driver`.

A driver holds a run's loads (checked, in the run's units), what the run resolved of them
for its record, one line on its problem, and a solver kept open for the whole sweep; it
solves a list of loads as a generator of steps, from first touch or a resumed state::

    driver = driver_for(run, scene, backend)   # PeriodicDriver or PunchDriver
    try:
        for step in driver.solve(driver.loads, None, None, []):
            ...
    finally:
        driver.close()

:class:`PeriodicDriver` sweeps nominal pressures with continuation
(:func:`~petsc_contact.workflows.periodic_sweep.sweep`) or reaches prescribed mean gaps by
Newton's steps on the pressure
(:func:`~petsc_contact.workflows.periodic_steps.mean_gap_sweep`), :class:`PunchDriver`
presses the punch along approaches or forces
(:func:`~petsc_contact.workflows.punch_sweep.punch_sweep`).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any, Protocol

import numpy as np

from ..backend.solve import Monitor
from ..backend.tao import PetscBackend
from ..conventions.units import force_value, format_quantity, length_value, pressure_value
from ..geometries.adhesive_periodic import AdhesivePeriodicProblem, check_solver
from ..geometries.adhesive_punch import AdhesivePunchProblem
from ..geometries.capped_periodic import CappedPeriodicProblem
from ..geometries.periodic import LARGEST_LOAD, PeriodicProblem
from ..geometries.punch import PunchProblem, footprint_mask
from ..geometries.step import Step
from ..interactions.adhesion import Adhesion
from ..interactions.hardness import HardnessCap
from ..physics.continuation import Held
from ..physics.observables import MIN_CONTACT_PIXELS
from ..solver.backends import SolverBackend
from ..substrates.half_space import PeriodicHalfSpace
from ..substrates.layer import PeriodicLayer
from ..substrates.substrate import PeriodicSubstrate
from .adhesive_steps import adhesive_mean_gap_sweep, adhesive_sweep
from .choice import uses_petsc
from .description import Run, cycled, swept
from .periodic_steps import PeriodicSteps, mean_gap_sweep, problem_solver, sweep
from .punch_steps import PunchSolver, capped_from_wall, punch_sweep
from .scene import Scene

Start = tuple[np.ndarray, Held | None] | None
"""Where a resumed run's sweep goes on from: its last state (a local slab) and what the sweep
held beside it (``None`` in a state file of an earlier version); ``None``: first touch."""
Earlier = Sequence[dict[str, Any]]
"""The scalars of the steps a resumed run finished (its committed table; none from the
start): an adhesive cycle's history (its jumps, pull-off and hysteresis energy are of all
its steps)."""


class Driver(Protocol):
    """A geometry's part of a run: its loads, its records, its solver.

    Attributes
    ----------
    loads
        Every load of the run, in order, in the run's units (checked).
    resolved
        What the run's record adds to its parameters (a sweep's loads, loads given with units).
    intro
        One line on the problem (``", full contact at p0 = ..."``), after the grid's.
    backend
        The FFT backend's name, for the record.
    """

    loads: list[float]
    resolved: dict[str, Any]
    intro: str
    backend: str

    def solve(
        self, loads: list[float], start: Start, monitor: Monitor | None, earlier: Earlier
    ) -> Iterator[Step]:
        """The steps of ``loads`` in order, from ``start`` (``None``: first touch) after the
        steps ``earlier``; ``monitor`` sees every TAO iteration."""
        ...

    def close(self) -> None:
        """Release the solver (its TAO, KSP and work Vecs)."""
        ...


def on_device(run: Run, device: str, options: Sequence[str] = ()) -> Run:
    """``run`` on the array ``device`` (``gpu``, ``cpu-array``), reading ``options`` there
    (the command line's PETSc options, which PETSc reads on ``cpu``); as it is on ``cpu``."""
    if uses_petsc(device):
        return run
    return run.with_(device=device, options=(*run.options, *options))


def driver_for(run: Run, scene: Scene, backend: SolverBackend) -> Driver:
    """The driver of ``run``'s geometry on ``scene``, solved by ``backend``, its loads
    checked (``ValueError``): a periodic run with a hardness is posed in the pressure
    (:class:`CappedPeriodicDriver`), one with adhesion in the gap with the law's energy
    (:class:`AdhesivePeriodicDriver`)."""
    if run.geometry == "punch":
        if run.adhesion is not None:
            return AdhesivePunchDriver(run, scene, backend)
        return PunchDriver(run, scene, backend)
    if run.adhesion is not None:
        return AdhesivePeriodicDriver(run, scene, backend)
    if run.hardness is not None:
        return CappedPeriodicDriver(run, scene, backend)
    return PeriodicDriver(run, scene, backend)


class PeriodicDriver:
    """The periodic geometry's driver: nominal pressures swept with continuation, or mean
    gaps (``run.mean_gaps``) reached by Newton's steps on the pressure.

    The pressures (``run.pressures`` or a ``run.sweep``, by default over :func:`sweep_range`) are
    checked against what the surface resolves (:meth:`PeriodicProblem.check_pressure`).  Its
    problem is posed on ``scene``, or given (``problem``: the Python API's, posed from a map
    as it is)."""

    def __init__(
        self, run: Run, scene: Scene, backend: SolverBackend, problem: PeriodicProblem | None = None
    ) -> None:
        if problem is None:
            problem = PeriodicProblem(
                scene.grid, scene.fft, scene.heights, run.modulus_value, backend,
                substrate=periodic_substrate(run, scene),
            )  # fmt: skip
            problem.filled = scene.filled
        p_full = problem.full_contact_pressure()
        if run.approaches is not None or run.forces is not None:
            raise ValueError(
                "a periodic run takes --pressures, --sweep or --mean-gaps, not --approaches or "
                "--forces"
            )
        self.by_mean_gap = run.mean_gaps is not None
        if self.by_mean_gap:
            self.loads, self.resolved = _mean_gaps(run, scene.resolved["length_unit"])
        else:
            self.loads, self.resolved = _pressures(run, problem)
        check = problem.check_mean_gap if self.by_mean_gap else problem.check_pressure
        for load in self.loads:
            check(load)  # before the output is touched
        self.run, self.problem = run, problem
        self.solver = problem_solver(problem)
        self.intro = (
            _layer_words(run)
            + f", full contact at p0 = {format_quantity(p_full, run.pressure_unit)}"
        )
        self.backend = type(problem.stiffness.fft).__name__

    def solve(
        self, loads: list[float], start: Start, monitor: Monitor | None, earlier: Earlier
    ) -> Iterator[Step]:
        """The sweep of ``loads`` (:func:`~petsc_contact.workflows.periodic_sweep.sweep`)."""
        state, held = start or (None, None)
        run = self.run
        if self.by_mean_gap:
            return mean_gap_sweep(
                self.problem, loads, run.fields, monitor, state, self.solver, held
            )
        return sweep(
            self.problem, loads, run.fields, monitor, run.stiffness, state, self.solver, held
        )

    def close(self) -> None:
        """Release the solver."""
        self.solver.close()


def periodic_substrate(run: Run, scene: Scene) -> PeriodicSubstrate:
    """The elastic body of a periodic ``run``: the half-space, or the layer of its
    ``thickness`` (in the scene's length unit), ``poisson`` and ``base``."""
    if run.thickness is None:
        return PeriodicHalfSpace(run.modulus_value)
    unit = scene.resolved["length_unit"] or None
    thickness = length_value(run.thickness, unit, "--thickness")
    return PeriodicLayer(run.modulus_value, thickness, run.poisson, run.base)


def _layer_words(run: Run) -> str:
    """The intro's words on a periodic ``run``'s layer (none on the half-space)."""
    if run.thickness is None:
        return ""
    thickness = run.thickness if isinstance(run.thickness, str) else f"{run.thickness:g}"
    return f", a {run.base} layer {thickness} thick (nu = {run.poisson:g}) on a rigid base"


class CappedPeriodicDriver:
    """A periodic run with a hardness: each nominal pressure solved first on the hard wall
    (the gap-posed cell of :class:`PeriodicDriver`, with its continuation along the sweep);
    where its pressure stays at or below the hardness that is the capped answer too (Kato's
    conditions hold with no pixel at the cap), else the cell posed in the pressure
    (:class:`~petsc_contact.geometries.capped_periodic.CappedPeriodicProblem`) is solved by
    Newton on the approach, from the hard wall's pressure clipped at the cap and its approach.
    Each step says which (``cap_reached``).  It takes ``--pressures`` or a ``--sweep``, each
    load below the hardness."""

    def __init__(self, run: Run, scene: Scene, backend: SolverBackend) -> None:
        if run.pressures is None and run.sweep is None:
            raise ValueError("a periodic run with --hardness takes --pressures or a --sweep")
        cap = run.interaction
        assert isinstance(cap, HardnessCap)  # driver_for's choice: run.hardness is given
        self.wall = PeriodicDriver(run, scene, backend)
        self.loads, self.resolved = self.wall.loads, self.wall.resolved
        for p0 in self.loads:
            cap.check_nominal(p0, "--pressures" if run.sweep is None else "--sweep")
        self.run, self.scene, self.cap, self.backend_ = run, scene, cap, backend
        # posed when a step first reaches the cap
        self.capped: PunchSolver | None = None
        hardness = format_quantity(cap.hardness, run.pressure_unit)
        self.intro = f"{self.wall.intro}, hardness {hardness}"
        self.backend = self.wall.backend

    def solve(
        self, loads: list[float], start: Start, monitor: Monitor | None, earlier: Earlier
    ) -> Iterator[Step]:
        """Each load on the hard wall along its load path (resumed from ``start``, a hard-wall
        state), then, where the cap is reached, capped (:meth:`capped_step`)."""
        state, held = start or (None, None)
        run, wall = self.run, self.wall.problem
        steps = PeriodicSteps(wall, state, held)
        for p0 in loads:
            step = steps.at_pressure(self.wall.solver, p0, run.fields, monitor, run.stiffness)
            s = step.scalars
            if step.converged and s["max_pressure"] <= self.cap.hardness:
                s.update(plastic_area_fraction=0.0, cap_reached=False)
                if run.fields:  # the hard wall's: no plastic displacement anywhere
                    step.extra["plastic_displacement"] = np.zeros_like(step.gap)
                yield step
                continue
            guess = wall.pressure(steps.x.reshape(wall.grid.local_shape) * wall.scale_length)
            capped = self.capped_step(p0, guess, s["mean_gap"], monitor)
            for name in ("iterations", "solve_time"):  # the hard wall's solve too
                capped.scalars[name] += s[name]
            capped.resume = step.resume  # a resumed sweep goes on along the hard wall's path
            yield capped

    def capped_step(self, p0: float, pressure: Any, mean_gap: float, monitor: Any) -> Step:
        """The capped cell at ``p0`` from the hard wall's ``pressure`` clipped at the cap, its
        Newton from the hard wall's approach (of its ``mean_gap``)."""
        if self.capped is None:
            scene, run = self.scene, self.run
            problem = CappedPeriodicProblem(
                scene.grid, scene.fft, scene.heights, run.modulus_value, self.cap, self.backend_
            )
            problem.filled = scene.filled
            self.capped = PunchSolver(problem)
        run = self.run
        step = capped_from_wall(
            self.capped, p0, pressure, mean_gap, run.fields, monitor, run.stiffness
        )
        step.scalars["cap_reached"] = True
        return step

    def close(self) -> None:
        """Release the solvers."""
        self.wall.close()
        if self.capped is not None:
            self.capped.close()


class AdhesivePeriodicDriver:
    """A periodic run with an adhesive law: its nominal pressures (any sign) or mean gaps in
    order, each from the last converged step (:func:`~petsc_contact.workflows.adhesive_steps.
    adhesive_sweep`, :func:`~petsc_contact.workflows.adhesive_steps.adhesive_mean_gap_sweep`),
    by one of TAO's bound solvers (the package's CG refused)."""

    def __init__(self, run: Run, scene: Scene, backend: SolverBackend) -> None:
        check_solver(backend)
        law = adhesive_law(run, scene)
        self.by_mean_gap = run.mean_gaps is not None
        if self.by_mean_gap:
            self.loads, self.resolved = _mean_gaps(run, scene.resolved["length_unit"])
        else:
            self.loads, self.resolved = _pressures(run, None)
        for p0 in [] if self.by_mean_gap else self.loads:
            law.check_nominal(p0, "--pressures")
        problem = AdhesivePeriodicProblem(
            scene.grid, scene.fft, scene.heights, run.modulus_value, law, backend
        )
        problem.filled = scene.filled
        self.run, self.problem, self.solver = run, problem, problem_solver(problem)
        self.scene = scene
        self.intro = adhesive_intro(law)
        self.backend = type(problem.stiffness.fft).__name__

    def solve(
        self, loads: list[float], start: Start, monitor: Monitor | None, earlier: Earlier
    ) -> Iterator[Step]:
        """The cycle of ``loads`` from ``start``'s gap (a fresh run's: first touch, or
        :meth:`_hard_wall_start`'s by mean gaps), its history the steps ``earlier``."""
        state = start[0] if start else None
        if state is None and not earlier and loads and self.by_mean_gap:
            state = self._hard_wall_start(loads[0])
        solve = adhesive_mean_gap_sweep if self.by_mean_gap else adhesive_sweep
        return solve(
            self.problem, loads, self.run.fields, monitor, state, self.solver, earlier=earlier
        )

    def _hard_wall_start(self, load: float) -> np.ndarray | None:
        """A fresh displacement-controlled run's first start: the hard wall's gap at its mean
        gap ``load`` (a local slab, by the package's CG under its own options prefix,
        :data:`HARD_WALL_START`), nearer the adhesive answer than first touch (over 12
        seeds at 256^2 8092 -> 1214 BLMVM iterations, docs/performance.md; under load control
        it saved none); ``None`` (first touch) where the hard wall does not reach it (above
        first touch) or did not converge."""
        scene = self.scene
        wall = PeriodicProblem(
            scene.grid, scene.fft, scene.heights, self.run.modulus_value,
            PetscBackend(HARD_WALL_START),
        )  # fmt: skip
        try:
            wall.check_mean_gap(load)
        except ValueError:
            return None
        step = next(iter(mean_gap_sweep(wall, [load], True)))
        return step.gap if step.converged else None

    def close(self) -> None:
        """Release the solver."""
        self.solver.close()


HARD_WALL_START = "petsc_contact_hard_wall_start_"
"""The options prefix of an adhesive run's first hard-wall solve (none given: the package's
CG at its defaults, whatever ``-tao_type`` the run gives its adhesive solves)."""


def adhesive_law(run: Run, scene: Scene) -> Adhesion:
    """The adhesive law of ``run`` (its range in the scene's length unit)."""
    assert run.adhesion and run.work_of_adhesion and run.interaction_range  # Run checked
    unit = scene.resolved["length_unit"] or None
    rho = length_value(run.interaction_range, unit, "--interaction-range")
    return Adhesion(run.adhesion, run.work_of_adhesion, rho)


def adhesive_intro(law: Adhesion) -> str:
    """The line an adhesive run's intro adds."""
    return f", {law.law} adhesion w = {law.work:.4g}, rho = {law.range:.4g}"


class AdhesivePunchDriver:
    """A punch run with an adhesive law: approaches (any sign) or forces (``forces``, or
    nominal pressures over the face; any sign) in order, each from the last converged step
    (:func:`~petsc_contact.workflows.adhesive_steps.adhesive_sweep`, the approaches by
    :meth:`~petsc_contact.geometries.adhesive_punch.AdhesivePunchProblem.set_approach`), by
    one of TAO's bound solvers (the package's CG refused).  Its problem is posed on
    ``scene`` with ``run``'s footprint, or given (the Python API's)."""

    def __init__(
        self,
        run: Run,
        scene: Scene,
        backend: SolverBackend,
        problem: AdhesivePunchProblem | None = None,
    ) -> None:
        check_solver(backend)
        law = adhesive_law(run, scene)
        if problem is None:
            mask, _ = footprint_mask(scene.grid, run.footprint)
            problem = AdhesivePunchProblem(
                scene.grid, scene.heights, run.modulus_value, law, mask, backend,
                device=scene.fft.device,
            )  # fmt: skip
        if sum(v is not None for v in (run.forces, run.approaches, run.pressures)) != 1:
            raise ValueError("give one of --approaches, --forces and --pressures")
        self.by_approach = run.approaches is not None
        self.loads, self.resolved = _punch_loads(run, problem, scene.resolved["length_unit"])
        for load in self.loads:
            law.check_nominal(load, "--approaches" if self.by_approach else "the force")
        self.run, self.problem, self.solver = run, problem, problem_solver(problem)
        self.intro = adhesive_intro(law)
        self.backend = type(problem.stiffness.fft).__name__

    def solve(
        self, loads: list[float], start: Start, monitor: Monitor | None, earlier: Earlier
    ) -> Iterator[Step]:
        """The cycle of ``loads`` from first touch (``start`` and ``earlier`` refused: an
        adhesive punch run is not resumed)."""
        if start is not None or earlier:
            raise ValueError("an adhesive punch run starts from first touch: it is not resumed")
        pb = self.problem
        if self.by_approach:
            steps = adhesive_sweep(
                pb, loads, self.run.fields, monitor, None, self.solver, pb.set_approach
            )
        else:
            pressures = [force / pb.face_area for force in loads]
            steps = adhesive_sweep(pb, pressures, self.run.fields, monitor, None, self.solver)
        for step in steps:
            step.resume = None  # its gap is the padded cell's, not a state of the run's grid
            yield step

    def close(self) -> None:
        """Release the solver."""
        self.solver.close()


HALF_AREA = 0.5  # a measured map's default sweep ends where Persson's law puts half in contact


def sweep_range(run: Run, problem: PeriodicProblem) -> tuple[float, float]:
    """The default range of a periodic ``run``'s sweep (collective): a generated surface's
    from ``1e-4`` to ``0.9`` times full contact; a measured map's from its first resolved
    contact (:data:`~petsc_contact.physics.observables.MIN_CONTACT_PIXELS` pixels) to about
    half the area (:data:`HALF_AREA`), both by Persson's area law
    (:meth:`~petsc_contact.geometries.periodic.PeriodicProblem.area_pressure`), and below
    ``0.9`` of full contact: a measured map's full contact is set by its deepest pixel (an
    outlier, a dropout), often orders of magnitude above the rest of its loads."""
    p_full = problem.full_contact_pressure()
    if not run.measured:
        return 1e-4 * p_full, 0.9 * p_full
    high = min(problem.area_pressure(HALF_AREA), 0.9 * p_full)
    # a map of fewer pixels than a resolved contact needs starts a tenth below the half
    low = problem.area_pressure(min(MIN_CONTACT_PIXELS / problem.grid.size, HALF_AREA))
    return min(low, 0.1 * high), high


def _pressures(run: Run, problem: PeriodicProblem | None) -> tuple[list[float], dict[str, Any]]:
    """The nominal pressures of a periodic ``run`` (a sweep's default range:
    :func:`sweep_range`; an adhesive run's sweep: its load cycle, :func:`cycled`), in its
    pressure unit, and what its record adds: a sweep's
    pressures, or those given with units."""
    unit = run.pressure_unit
    if run.sweep is not None:

        def value(bound: float | str) -> float:
            return pressure_value(bound, unit, "--sweep")

        if run.adhesion is not None:  # an adhesive run's sweep is a load cycle
            pressures = cycled(run.sweep, value)
        else:
            assert problem is not None  # every other periodic run gives its problem
            pressures = swept(run.sweep, *sweep_range(run, problem), value)
        return pressures, {"pressures": pressures, "sweep": None}  # the file records the loads
    if run.pressures is None:
        raise ValueError("give the nominal pressures (--pressures), a --sweep or --mean-gaps")
    pressures = [pressure_value(p, unit, "--pressures") for p in run.pressures]  # Run checked
    if any(isinstance(p, str) for p in run.pressures):
        return pressures, {"pressures_resolved": pressures}  # in the run's pressure unit
    return pressures, {}


def _mean_gaps(run: Run, length_unit: str) -> tuple[list[float], dict[str, Any]]:
    """The prescribed mean gaps of a periodic ``run`` in its length unit (their signs checked
    by :class:`Run`), and what its record adds: those given with units."""
    given = run.mean_gaps or ()
    gaps = [length_value(g, length_unit or None, "--mean-gaps") for g in given]
    if any(isinstance(g, str) for g in given):
        return gaps, {"mean_gaps_resolved": gaps}  # in the run's length unit
    return gaps, {}


class PunchDriver:
    """The punch's driver: approaches, or forces (``forces`` or nominal pressures over the
    face) reached by Newton steps on the approach.  Its problem is posed on ``scene`` with
    ``run``'s footprint and flat punch, or given (``problem``: the Python API's, whose
    footprint may be a mask and its shape factor any)."""

    def __init__(
        self, run: Run, scene: Scene, backend: SolverBackend, problem: PunchProblem | None = None
    ) -> None:
        posed_here = problem is None
        if problem is None:
            mask, beta = footprint_mask(scene.grid, run.footprint)
            problem = PunchProblem(
                scene.grid, scene.heights, run.modulus_value, mask, run.flat_stiffness, beta,
                device=scene.fft.device, backend=backend, interaction=run.interaction,
            )  # fmt: skip
            problem.filled = scene.filled
        given = [run.forces, run.approaches, run.pressures, run.sweep]
        if sum(v is not None for v in given) != 1:
            raise ValueError("give one of --approaches, --forces, --pressures and --sweep")
        self.by_force = run.forces is not None or run.pressures is not None
        self.loads, self.resolved = _punch_loads(run, problem, scene.resolved["length_unit"])
        if self.by_force:  # a hardness cap at or below a nominal pressure over the face
            area = problem.footprint_pixels * problem.grid.pixel_area
            for force in self.loads:
                problem.interaction.check_nominal(force / area, "the force")
        if self.by_force and posed_here:  # the Python API's solver says what it reaches
            _check_forces(self.loads, problem, run)
        self.run, self.solver = run, PunchSolver(problem)
        length_unit = scene.resolved["length_unit"]
        unit = f"{run.pressure_unit}*{length_unit}" if run.pressure_unit and length_unit else ""
        self.intro = (
            f", K_flat = {format_quantity(self.solver.k_flat, unit, 6)} ({problem.flat};"
            f" analytic {format_quantity(self.solver.k_flat_analytic, unit, 6)})"
        )
        self.backend = type(problem.compliance.fft).__name__

    def solve(
        self, loads: list[float], start: Start, monitor: Monitor | None, earlier: Earlier
    ) -> Iterator[Step]:
        """The punch along ``loads`` (:func:`~petsc_contact.workflows.punch_sweep.punch_sweep`)."""
        state, held = start or (None, None)
        run = self.run
        return punch_sweep(
            self.solver, loads, self.by_force, run.fields, monitor, run.stiffness, state, held
        )

    def close(self) -> None:
        """Release the solver."""
        self.solver.close()


def _check_forces(forces: list[float], problem: PunchProblem, run: Run) -> None:
    """``ValueError`` in one line, before anything is solved, for a force whose nominal
    pressure over the punch's face is above :data:`~petsc_contact.geometries.periodic.LARGEST_LOAD`
    ``E*``: no elastic contact (the solver would overflow)."""
    area = problem.footprint_pixels * problem.grid.pixel_area
    option = "--forces" if run.forces is not None else "--pressures"
    for force in forces:
        pressure = force / area / run.modulus_value
        if not pressure <= LARGEST_LOAD:  # inf and NaN too
            raise ValueError(
                f"{option}: a force of {force:.3g} is a nominal pressure of {pressure:.3g} E* "
                f"over the punch's face, more than {LARGEST_LOAD:g} E*: no elastic contact"
            )


def _punch_loads(
    run: Run, problem: PunchProblem | AdhesivePunchProblem, length_unit: str
) -> tuple[list[float], dict[str, Any]]:
    """The punch's approaches or forces in the run's units (their signs checked by
    :class:`Run`), and what its record adds: a sweep's approaches, or the forces of loads given
    with units or as nominal pressures over the face."""
    unit = length_unit or None
    if run.sweep is not None:
        low, high = 0.01 * problem.scale_length, 3 * problem.scale_length
        loads = swept(run.sweep, low, high, lambda v: length_value(v, unit, "--sweep"))
        return loads, {"approaches": loads, "sweep": None}  # the file records the loads
    if run.forces is not None:
        units = run.pressure_unit, unit
        forces = [force_value(f, *units, "--forces") for f in run.forces]
        return forces, {"forces_resolved": forces}  # in the run's force unit
    if run.pressures is not None:  # nominal pressure over the punch's face
        area = problem.footprint_pixels * problem.grid.pixel_area
        forces = [pressure_value(p, run.pressure_unit, "--pressures") * area for p in run.pressures]
        return forces, {"forces_resolved": forces}  # the forces of those pressures
    approaches = [length_value(v, unit, "--approaches") for v in run.approaches or []]
    return approaches, {}
