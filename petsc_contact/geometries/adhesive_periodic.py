"""The periodic contact with adhesion, posed in the gap (docs/formulation.md).

The periodic geometry's energy (:mod:`~petsc_contact.geometries.periodic`) with the
interaction energy of an adhesive law ``phi`` (:class:`~petsc_contact.interactions.adhesion.
Adhesion`) added,

    Pi(g) = a^2 [ 1/2 (g + h)^T K (g + h) + p0 sum(g) + sum(phi(g)) ],     g >= 0,

whose gradient is ``a^2 (p + phi'(g))`` with the elastic pressure ``p = K (g + h) + p0``.  It is
smooth (Maugis' law smoothed) but not convex (``phi'' < 0``), and bounded below only while
``p0 >= 0``: under tension its minima are local, the adhesive contact a solver reaches from
the previous step of its branch, and beyond the pull-off there is none (the gap grows without
bound and the solve fails, never a silent answer).  A gradient method solves it: TAO's bound
solvers (``-tao_type blmvm``, ``bncg``) with the package's Fourier preconditioner as their
initial Hessian; the package's own CG is a QP solver and refuses it
(:func:`check_solver`).

The scaling is the periodic geometry's with the pressure scale ``P = max(|p0|, w/rho)``
in place of ``p0`` (``p0`` may be zero or tensile): TAO's gradient norm is the rms residual
in units of ``P``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..backend.solve import Monitor, SolveInfo
from ..conventions.grid import Grid
from ..devices.fft import FFT
from ..interactions.adhesion import Adhesion
from ..solver.backends import SolverBackend
from ..substrates.substrate import PeriodicSubstrate
from .periodic import PeriodicProblem, verify
from .step import Step, contact_fields, mark_full_contact

SEPARATED = 30.0  # apart beyond this many ranges (attraction e^-30 w/rho) under tension: pulled off
QP_ONLY = (
    "--adhesion: the package's CG solves the hard wall's QP, not an adhesive energy (not "
    "convex); give -tao_type blmvm (or bncg)"
)


def check_solver(backend: SolverBackend) -> None:
    """``ValueError`` in one line where ``backend`` would run the package's CG (a QP solver)."""
    if backend.runs_default_type:
        raise ValueError(QP_ONLY)


class AdhesivePeriodicProblem(PeriodicProblem):
    """The periodic cell of ``heights`` with the adhesive law ``adhesion`` (module docstring).

    Parameters
    ----------
    grid, fft, heights, modulus, backend, substrate
        As for :class:`~petsc_contact.geometries.periodic.PeriodicProblem`; the backend must
        run one of TAO's bound solvers (:func:`check_solver`).
    adhesion
        The law at the surface.
    """

    def __init__(
        self,
        grid: Grid,
        fft: FFT,
        heights: np.ndarray,
        modulus: float,
        adhesion: Adhesion,
        backend: SolverBackend | None = None,
        *,
        substrate: PeriodicSubstrate | None = None,
    ) -> None:
        super().__init__(
            grid, fft, heights, modulus, backend, substrate=substrate, interaction=adhesion
        )
        self.adhesion = adhesion
        self.pressure_scale = np.nan
        self._phi_ref: Any = None  # phi(g) at the reference point
        self.separated = False
        self.machine: tuple[float, float] | None = None  # displacement control's (k_m, t)

    def set_pressure(self, p0: float, interfacial_stiffness: float | None = None) -> None:
        """Set the nominal pressure ``p0`` (any sign) and scale the problem by
        ``P = max(|p0|, w/rho)``: the operators and preconditioner are the periodic
        geometry's at ``P`` (``interfacial_stiffness`` as there, default Persson's at ``P``)."""
        self.adhesion.check_nominal(p0, "nominal pressure")
        scale = max(abs(float(p0)), self.adhesion.strength)
        super().set_pressure(scale, interfacial_stiffness)
        self.pressure_scale = scale
        self.nominal_pressure = float(p0)
        self.machine = None

    def set_machine(self, anchor: float, scale: float, stiffness: float | None = None) -> None:
        """Displacement control: a loading machine of stiffness ``k_m`` (``stiffness``, by
        default the pixel stiffness, stiffer than any contact) holds the mean gap near
        ``anchor``, adding ``N k_m/2 (mean(g) - anchor)^2`` to the energy in place of
        ``p0 sum(g)``: the nominal pressure is ``k_m (mean(g) - anchor)``, and every branch
        is stable under it.  ``scale`` is the pressure scale (``P``); the preconditioner's
        mean mode is held by ``k_m`` exactly."""
        k_m = float(self.pixel_stiffness if stiffness is None else stiffness)
        self.set_pressure(max(scale, self.adhesion.strength), k_m)
        self.nominal_pressure = 0.0
        self.machine = (k_m, float(anchor))

    def tolerance_floor(self) -> float:
        """The tolerance double precision resolves, in units of the pressure scale."""
        return self.rounding_floor(self.pressure_scale)

    def start(self, x0: np.ndarray) -> None:
        """The periodic geometry's reference point, and the interaction energy there."""
        super().start(x0)
        xp = self.device.xp
        self._phi_ref = self.adhesion.energy(self.law_gap(self._x_ref), xp)

    def _spring(self, x: np.ndarray) -> tuple[float, float]:
        """The change of the loading machine's energy from the reference over the pixel area,
        ``N k_m/2 (s^2 - s_ref^2)`` with ``s = mean(g) - t``, formed as ``N k_m/2 (s -
        s_ref)(s + s_ref)`` (no cancellation of the large terms), and its pressure ``k_m s``
        (both 0 under load control)."""
        if self.machine is None:
            return 0.0, 0.0
        k_m, anchor = self.machine
        ell, n = self.scale_length, self.grid.size
        total, change = self.grid.sum(float(x.sum()), float((x - self._x_ref).sum()))
        stretch = total * ell / n - anchor
        moved = change * ell / n
        return 0.5 * n * k_m * moved * (2 * stretch - moved), k_m * stretch

    def law_gap(self, x: Any) -> Any:
        """The gap the law sees of the scaled unknown ``x``: ``l x`` on every pixel."""
        return x * self.scale_length

    def _interaction_change(self, phi: np.ndarray) -> float:
        """``sum(phi - phi(l x_ref))`` over the grid of the energies ``phi`` at the law's gap,
        pixel by pixel (the change, not the difference of two large sums)."""
        (total,) = self.grid.sum(float((phi - self._phi_ref).sum()))
        return float(total)

    def objective_gradient(self, x: np.ndarray, grad: np.ndarray) -> float:
        """The periodic geometry's scaled objective (relative to the reference) plus
        ``s/l (sum(phi(l x)) - sum(phi(l x_ref)))`` and the loading machine's change
        (:meth:`set_machine`); ``grad <- s (p + phi'(g) + k_m (mean(g) - t))``: one FFT pair
        (the periodic geometry's) and one pass of the law per evaluation."""
        f = super().objective_gradient(x, grad)
        xp, ell = self.device.xp, self.scale_length
        gap = self.law_gap(x)
        if self.nominal_pressure < 0:  # the gap grows without bound once pulled off
            lowest = self.grid.min(float(gap.min(initial=np.inf)))
            self.separated = lowest > SEPARATED * self.adhesion.range
        spring, pull = self._spring(x)
        phi, slope = self.adhesion.energy_and_derivative(gap, xp)
        grad += self._s * (slope + pull)
        return f + self._s / ell * (self._interaction_change(phi) + spring)

    def separation_monitor(self, monitor: Monitor | None) -> Monitor:
        """``monitor`` that also stops the solve once the surfaces separated under tension
        (their smallest gap beyond :data:`SEPARATED` ranges): pulled off, no equilibrium."""
        self.separated = False

        def watch(iteration: int, f: float, gnorm: float) -> bool:
            given = bool(monitor(iteration, f, gnorm)) if monitor is not None else False
            return given or self.separated

        return watch

    def measure(
        self, x: np.ndarray, info: SolveInfo, stiffness: bool = False, fields: bool = False
    ) -> Step:
        """The step of a solution ``x`` (the scaled gap): :func:`adhesive_observables`, the
        solver's report and the verdict (``stiffness`` is not measured: the held-set
        stiffness leaves out the law's curvature)."""
        grid, ell, device = self.grid, self.scale_length, self.device
        if self.machine is not None:  # the nominal pressure the machine holds
            self.nominal_pressure = self._spring(x)[1]
        gap = device.to_host(x.reshape(grid.local_shape) * ell)
        pressure = device.to_host(self.pressure(device.asarray(gap)))
        obs = adhesive_observables(self, gap, pressure)
        return self.judged(info, obs, fields, gap, pressure)

    def judged(
        self, info: SolveInfo, obs: dict[str, Any], fields: bool, gap: Any, pressure: Any
    ) -> Step:
        """The step of a solution's observables ``obs`` (this rank's ``contact`` mask among
        them, taken out) and the solver's report ``info``: the verdict (a pull-off said), the
        accuracy's assessment, and the host fields ``gap`` and ``pressure`` if asked."""
        contact = obs.pop("contact")
        verdict = verify(info, obs, self.scale_length, self.interaction)
        if self.separated:
            verdict = f"pulled off: the surfaces separated (min gap > {SEPARATED:g} ranges)"
        scalars = {**obs, **info.scalars(verdict)}
        mark_full_contact(scalars)
        self.accuracy().assess(scalars)
        if not fields:
            return Step(scalars)
        return Step(scalars, *contact_fields(gap, pressure, contact), contact=contact)


def adhesive_observables(
    problem: AdhesivePeriodicProblem, gap: np.ndarray, pressure: np.ndarray
) -> dict[str, Any]:
    """Scalars of one adhesive step (same on every rank) and the contact mask ``contact``.

    ``contact`` is where the wall pushes, ``p + phi'(g) > k g`` (the projection of the natural
    residual); ``adhesive_pressure`` the mean attraction ``mean(phi'(g))``, so that the mean
    wall reaction less it is ``p0`` (``force_balance``: the miss in units of the pressure
    scale ``P``); ``kkt_residual`` ``rms(min(k g, p + phi'(g)))/P``; ``interaction_energy``
    ``mean(phi(g))`` and ``elastic_energy`` ``1/2 mean((g + h)(p - p0))`` per area."""
    grid, law, k = problem.grid, problem.adhesion, problem.pixel_stiffness
    attraction = law.derivative(gap)
    total = pressure + attraction
    contact = total > k * gap
    reaction = np.where(contact, total, 0.0)
    r = np.minimum(k * gap, total)
    heights = problem.device.to_host(problem.heights)
    p0, scale = problem.nominal_pressure, problem.pressure_scale
    sums = grid.sum(
        reaction.sum(),
        attraction.sum(),
        np.count_nonzero(contact),
        gap.sum(),
        np.vdot(r, r),
        law.energy(gap).sum(),
        np.vdot(gap + heights, pressure - p0),
    )
    r_sum, a_sum, n_contact, g_sum, r2, phi_sum, work = sums
    n = grid.size
    return {
        "nominal_pressure": p0,
        "mean_gap": g_sum / n,
        "area_fraction": n_contact / n,
        "contact_pressure_mean": r_sum / n,
        "adhesive_pressure": a_sum / n,
        "force_balance": abs(r_sum / n - a_sum / n - p0) / scale,
        "pressure_scale": scale,
        "max_pressure": grid.max(float(pressure.max(initial=-np.inf))),
        "min_pressure": grid.min(float(pressure.min(initial=np.inf))),
        "min_gap": grid.min(float(gap.min(initial=np.inf))),
        "kkt_residual": float(np.sqrt(r2 / n)) / scale,
        "interaction_energy": phi_sum / n,
        "elastic_energy": 0.5 * work / n,
        "contact": contact,
    }
