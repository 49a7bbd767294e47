"""The periodic cell posed in the pressure: the punch's formulation on a periodic substrate,
for an interaction that bounds the pressure above (a hardness cap).

The periodic geometry (:mod:`~petsc_contact.geometries.periodic`) is posed in the gap, where
a cap on the pressure ``p = K (g + h) + p0`` is no box.  Here the unknown is the pressure,
``0 <= p <= H`` (the interaction's bounds), and the problem is the punch's dual QP

    W(p) = a^2 [ 1/2 p^T G p - p^T (δ - s) ],     s = max(h) - h,

with the periodic compliance ``G``: ``2/(E* |q|)`` (the inverse of the substrate's
stiffness) on every mode but the mean, and the finite compliance ``c = 2/(E* q0)`` of the
longest wavelength on the mean mode.  The nominal pressure ``mean(p) = p0`` is reached by the
punch's safeguarded Newton on the rigid approach ``δ`` (:class:`~petsc_contact.workflows.
punch_steps.PunchSolver`).  Once ``mean(p) = p0`` the mean mode adds the constant ``c p0``
to every gap, which ``δ`` takes up: the gap field, and every answer, do not depend on ``c``
(only ``δ`` does, and only the path of the Newton).

Per step the periodic geometry's observables (the gap's natural residual as the punch
measures it, in units of the rms height), the interaction's (``plastic_area_fraction``,
``plastic_displacement``), Newton's (``force``, ``target_force``, ``newton_iterations``,
``force_balance``) and, with the stiffness, ``-dp0/du_bar = 1/(A/K_tot - c)`` from the
exact ``K_tot = dF/dδ`` with the elastic contact held and the plastic pixels at the cap.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..backend.operator import FourierOperator
from ..backend.solve import SolveInfo
from ..conventions.grid import Grid
from ..devices.fft import FFT, wavevector_magnitude
from ..interactions.interaction import Interaction
from ..physics.observables import contact_resolved, distributions, patch_sizes
from ..solver.backends import SolverBackend
from ..substrates.half_space import PeriodicHalfSpace
from ..substrates.substrate import PeriodicSubstrate, of_modulus
from .punch import PunchProblem
from .step import Step, contact_fields, mark_full_contact, residual_verdict


class CappedPeriodicProblem(PunchProblem):
    """The periodic cell of ``heights`` posed in the pressure, bounded by ``interaction``.

    A :class:`~petsc_contact.geometries.punch.PunchProblem` whose footprint is the whole cell
    and whose compliance is the periodic one: the objective, the bounds, the gap and the
    held-set stiffness are the punch's; the operators (:meth:`_operators`) and what a step
    measures (:meth:`measure`) are the cell's.  The punch's flat reference enters no answer:
    it is the analytic one (no held-set solve at set-up).

    Parameters
    ----------
    grid, fft, heights, modulus
        As for :class:`~petsc_contact.geometries.periodic.PeriodicProblem`: the cell, its FFT
        (whose device the fields live on), this rank's heights and ``E*``.
    interaction
        The law at the surface (:class:`~petsc_contact.interactions.hardness.HardnessCap`).
    backend
        What solves it (default: PETSc's).
    substrate
        The periodic body (:class:`~petsc_contact.substrates.substrate.PeriodicSubstrate`);
        default: the half-space of ``modulus``.
    """

    def __init__(
        self,
        grid: Grid,
        fft: FFT,
        heights: np.ndarray,
        modulus: float,
        interaction: Interaction,
        backend: SolverBackend | None = None,
        substrate: PeriodicSubstrate | None = None,
    ) -> None:
        self.fft = fft
        body = PeriodicHalfSpace(modulus) if substrate is None else substrate
        self.cell = of_modulus(body, modulus)
        self.mean_compliance = self.cell.mean_mode_compliance(grid.q0, 0.0)  # c
        super().__init__(
            grid, heights, modulus, flat="analytic", device=fft.device, backend=backend,
            interaction=interaction,
        )  # fmt: skip
        (self.recess_sum,) = grid.sum(self.recess.sum())

    def _operators(self) -> None:
        """The periodic compliance ``G`` (``c`` on the mean mode), its inverse, and the scaled
        Hessian ``G / (a sqrt(N) / E*)`` with its inverse as the preconditioner."""
        grid, fft, xp = self.grid, self.fft, self.device.xp
        q = wavevector_magnitude(grid, fft, xp)
        stiffness = self.cell.stiffness(xp.where(q > 0, q, 1.0))
        compliance = xp.where(q > 0, 1.0 / stiffness, self.mean_compliance)
        a = np.sqrt(grid.pixel_area)
        self._scale = a * np.sqrt(grid.size) / self.modulus
        self.compliance = FourierOperator(grid, fft, compliance)
        self.inverse = FourierOperator(grid, fft, 1.0 / compliance)
        self.hessian = self.compliance.scaled(1.0 / self._scale)
        self.preconditioner = self.inverse.scaled(self._scale)
        self.pixel_stiffness = 1.0 / self.compliance.diagonal()
        self.pressure_scale = self.modulus * self.scale_length / a

    def measure(
        self, x: Any, info: SolveInfo, stiffness: bool = False, fields: bool = False
    ) -> Step:
        """The step of a solution ``x`` (the scaled pressure) at the current approach: the
        periodic cell's observables (:func:`cell_observables`), the solver's report, the
        verdict, and the exact ``K_tot = dF/dδ`` (Newton's) with ``-dp0/du_bar`` from it
        (``stiffness`` adds the dataset ``stiffness``)."""
        device = self.device
        on_device = x.reshape(self.grid.local_shape) * self.pressure_scale
        gap = device.to_host(self.gap(on_device))
        pressure = device.to_host(on_device)
        obs = cell_observables(self, pressure, gap)
        contact, plastic = obs.pop("contact"), obs.pop("plastic")
        verdict = residual_verdict(obs["kkt_residual"], info.effective_tolerance)
        if info.reason_code <= 0:
            verdict = f"TAO did not converge ({info.reason})"
        held = self.held_set_stiffness(contact & ~plastic, verdict == "ok")
        scalars = {
            **obs,
            "force_balance": np.nan,  # under load control: PunchSolver.at_force
            "total_stiffness": held["total_stiffness"],
            **{k: v for k, v in held.items() if k.startswith("stiffness_")},
            **info.scalars(verdict),
        }
        if stiffness:
            scalars["stiffness"] = self.cell_stiffness(held["total_stiffness"])
        mark_full_contact(scalars)
        self.accuracy().assess(scalars)
        if not fields:
            return Step(scalars)
        extra = self.interaction.fields(gap, plastic)
        return Step(scalars, *contact_fields(gap, pressure, contact), contact=contact, extra=extra)

    def approach_at(self, p0: float, mean_gap: float) -> float:
        """The approach at which an answer of nominal pressure ``p0`` has the mean gap
        ``mean_gap``: ``mean(g) = c p0 + mean(s) - δ``."""
        return float(self.mean_compliance * p0 + self.recess_sum / self.grid.size - mean_gap)

    def cell_stiffness(self, total: float) -> float:
        """``-dp0/du_bar = 1/(A/K_tot - c)`` from ``K_tot = dF/dδ``: ``u_bar = c p0 +
        mean(s) - δ``, so ``du_bar/dp0 = c - A/K_tot`` (0 without an elastic contact pixel;
        NaN where ``K_tot`` is)."""
        with np.errstate(divide="ignore"):
            return float(1.0 / (self.grid.area / np.float64(total) - self.mean_compliance))


def cell_observables(
    problem: CappedPeriodicProblem, pressure: np.ndarray, gap: np.ndarray
) -> dict[str, Any]:
    """Scalars of one step of the capped cell (same on every rank), as the periodic geometry
    names them, with its masks ``contact`` and ``plastic`` (see the module docstring)."""
    grid, law, k = problem.grid, problem.interaction, problem.pixel_stiffness
    contact = pressure > k * gap
    plastic = law.plastic(gap, pressure, k)
    sizes = patch_sizes(grid, contact)
    r = law.residual(gap, pressure, k)
    sums = grid.sum(
        pressure.sum(),
        np.count_nonzero(contact),
        np.vdot(gap - problem.recess, pressure),
        np.vdot(pressure, np.maximum(gap, 0.0)),
        np.vdot(r, r),
        gap.sum(),
        np.count_nonzero(plastic),
    )
    p_sum, n_contact, work, pg, r2, g_sum, n_plastic = sums
    n, ell = grid.size, problem.scale_length
    p0 = p_sum / n
    return {
        "approach": problem.approach,
        "force": grid.pixel_area * p_sum,
        "nominal_pressure": p0,
        "mean_gap": g_sum / n,
        "area_fraction": n_contact / n,
        "contact_resolved": bool(contact_resolved(n_contact / n, n)),
        "contact_patches": sizes.size,
        "contact_pressure_mean": p0,
        "elastic_energy": 0.5 * (work - p0 * (g_sum - problem.recess_sum)) / n,
        "max_pressure": grid.max(float(pressure.max(initial=0.0))),
        "min_gap": grid.min(float(np.where(plastic, np.inf, gap).min(initial=np.inf))),
        "min_pressure": grid.min(float(pressure.min(initial=np.inf))),
        "complementarity": pg / (p_sum * ell) if p_sum > 0 else 0.0,
        "kkt_residual": float(np.sqrt(r2 / n)) / ell,
        **law.scalars(int(n_plastic), n),
        **distributions(grid, gap, pressure, contact, sizes, filled=problem.filled),
        "contact": contact,
        "plastic": plastic,
    }
