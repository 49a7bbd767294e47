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

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..backend.operator import FourierOperator
from ..conventions.grid import Grid
from ..devices.device import Device
from ..devices.fft import FFT, wavevector_magnitude
from ..interactions.interaction import Interaction
from ..physics.observables import contact_resolved, distributions, patch_sizes
from ..solver.backends import SolverBackend
from ..substrates.half_space import PeriodicHalfSpace
from ..substrates.substrate import PeriodicSubstrate, of_modulus
from .punch import Operators, PressureProblem


@dataclass(frozen=True)
class PeriodicCompliance:
    """The periodic compliance of ``substrate``: ``1/K(q)`` (the inverse of its stiffness) on
    every mode but the mean, and ``mean``, the finite compliance ``c`` of the mean mode, on
    it; on the cell's ``fft``."""

    substrate: PeriodicSubstrate
    fft: FFT
    mean: float

    def operators(self, grid: Grid, device: Device, scale: float) -> Operators:
        """``G``, its inverse, ``G / s`` and ``s G^-1`` as Fourier multipliers on the
        device's arrays."""
        fft, xp = self.fft, device.xp
        q = wavevector_magnitude(grid, fft, xp)
        stiffness = self.substrate.stiffness(xp.where(q > 0, q, 1.0))
        compliance = xp.where(q > 0, 1.0 / stiffness, self.mean)
        forward = FourierOperator(grid, fft, compliance)
        inverse = FourierOperator(grid, fft, 1.0 / compliance)
        return Operators(forward, inverse, forward.scaled(1.0 / scale), inverse.scaled(scale))


@dataclass(frozen=True)
class CellMeasure:
    """The periodic cell's step: its observables as the periodic geometry names them
    (:func:`cell_observables`), the total stiffness ``K_tot = dF/dδ`` and the dataset
    ``stiffness``, ``-dp0/du_bar`` from it, with ``mean`` the mean mode's compliance ``c``."""

    mean: float

    def observables(
        self, problem: PressureProblem, pressure: np.ndarray, gap: np.ndarray
    ) -> dict[str, Any]:
        return cell_observables(problem, pressure, gap)

    def stiffness_scalars(self, held: dict[str, Any]) -> dict[str, Any]:
        """The total stiffness and its solve's report (no flat punch: the cell has none)."""
        return {
            "total_stiffness": held["total_stiffness"],
            **{k: v for k, v in held.items() if k.startswith("stiffness_")},
        }

    def stiffness(self, problem: PressureProblem, scalars: dict[str, Any]) -> float:
        """:meth:`cell_stiffness` of the step's ``total_stiffness``."""
        return self.cell_stiffness(problem, scalars["total_stiffness"])

    def cell_stiffness(self, problem: PressureProblem, total: float) -> float:
        """``-dp0/du_bar = 1/(A/K_tot - c)`` from ``K_tot = dF/dδ``: ``u_bar = c p0 +
        mean(s) - δ``, so ``du_bar/dp0 = c - A/K_tot`` (0 without an elastic contact pixel;
        NaN where ``K_tot`` is)."""
        with np.errstate(divide="ignore"):
            return float(1.0 / (problem.grid.area / np.float64(total) - self.mean))

    def approach_at(self, problem: PressureProblem, p0: float, mean_gap: float) -> float:
        """The approach at which an answer of nominal pressure ``p0`` has the mean gap
        ``mean_gap``: ``mean(g) = c p0 + mean(s) - δ``."""
        return float(self.mean * p0 + problem.recess_sum / problem.grid.size - mean_gap)


class CappedPeriodicProblem(PressureProblem):
    """The periodic cell of ``heights`` posed in the pressure, bounded by ``interaction``: a
    :class:`~petsc_contact.geometries.punch.PressureProblem` of the periodic compliance
    (:class:`PeriodicCompliance`) and the cell's measure (:class:`CellMeasure`), whose
    footprint is the whole cell.  The flat punch's reference enters no answer: it is the
    analytic one (no held-set solve at set-up), load control's first approach.

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
        self.cell_measure = CellMeasure(self.mean_compliance)
        super().__init__(
            grid, heights, modulus, PeriodicCompliance(self.cell, fft, self.mean_compliance),
            self.cell_measure, flat="analytic", device=fft.device, backend=backend,
            interaction=interaction,
        )  # fmt: skip

    def approach_at(self, p0: float, mean_gap: float) -> float:
        """:meth:`CellMeasure.approach_at` of this cell."""
        return self.cell_measure.approach_at(self, p0, mean_gap)

    def cell_stiffness(self, total: float) -> float:
        """:meth:`CellMeasure.cell_stiffness` of this cell."""
        return self.cell_measure.cell_stiffness(self, total)


def cell_observables(
    problem: PressureProblem, pressure: np.ndarray, gap: np.ndarray
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
