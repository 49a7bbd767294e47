"""Adhesion: the hard wall with a short-range attraction (docs/formulation.md).

The gap stays non-negative and the surfaces attract each other with an interaction energy
per area ``phi(g)`` that vanishes far apart and is ``-w`` (the work of adhesion) at contact:

- ``exponential``: ``phi(g) = -w exp(-g/rho)``, the attraction ``-phi'(g) = (w/rho)
  exp(-g/rho)``: smooth;
- ``maugis`` (Maugis-Dugdale's cohesive zone): the constant attraction ``w/rho`` below
  ``g = rho``, none beyond.  Its attraction jumps at ``g = rho``; posed for the gradient
  solvers it is smoothed there (:data:`MAUGIS_SMOOTHING`): the attraction falls from ``w/rho``
  to 0 linearly over ``[rho (1 - eps), rho (1 + eps)]``, which keeps the work ``w`` exactly
  (the ramp is symmetric about ``rho``).

With the elastic pressure ``p = K (g + h) + p0`` (compression positive) the conditions on every
pixel are ``g >= 0``, ``p + phi'(g) >= 0`` and ``g (p + phi'(g)) = 0``: off contact the surface
carries the attraction as a tension, ``p = phi'(g) < 0``.  They are the KKT conditions of the
periodic energy with ``sum(phi(g))`` added, bounded by ``g >= 0`` and not convex
(:class:`~petsc_contact.geometries.adhesive_periodic.AdhesivePeriodicProblem`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..conventions.validation import positive
from .hard_wall import HARD_WALL

LAWS = ("exponential", "maugis")
MAUGIS_SMOOTHING = 0.05  # the half-width of Maugis' smoothed step, in units of rho


@dataclass(frozen=True)
class Adhesion:
    """An adhesive law (:class:`~petsc_contact.interactions.interaction.Interaction`; module
    docstring).

    Parameters
    ----------
    law
        ``exponential`` or ``maugis``.
    work
        The work of adhesion ``w > 0``: an energy per area (pressure times length).
    range
        The interaction range ``rho > 0`` (a length); ``w/rho`` is the largest attraction.
    """

    law: str
    work: float
    range: float
    name = "adhesion"

    def __post_init__(self) -> None:
        if self.law not in LAWS:
            raise ValueError(f"--adhesion must be one of {', '.join(LAWS)}, not {self.law!r}")
        positive("--work-of-adhesion", self.work)
        positive("--interaction-range", self.range)

    @property
    def strength(self) -> float:
        """The largest attraction, ``w/rho`` (a pressure)."""
        return self.work / self.range

    def energy(self, gap: Any, xp: Any = np) -> Any:
        """The interaction energy per area ``phi(g)`` on each pixel."""
        return self.energy_and_derivative(gap, xp)[0]

    def derivative(self, gap: Any, xp: Any = np) -> Any:
        """``phi'(g)``, minus the attraction, on each pixel (non-negative)."""
        return self.energy_and_derivative(gap, xp)[1]

    def energy_and_derivative(self, gap: Any, xp: Any = np) -> tuple[Any, Any]:
        """``phi(g)`` and ``phi'(g)`` on each pixel, from one exponential (or one ramp)."""
        if self.law == "exponential":
            decay = xp.exp(-gap / self.range)
            return -self.work * decay, self.strength * decay
        eps, rho = MAUGIS_SMOOTHING, self.range
        t = xp.clip((gap - rho * (1 - eps)) / (2 * eps * rho), 0.0, 1.0)  # 0 to 1 on the ramp
        # minus the attraction's integral beyond g: the flat part's, then the ramp's
        flat = xp.maximum(rho * (1 - eps) - gap, 0.0)
        return -self.strength * (flat + eps * rho * (1.0 - t) ** 2), self.strength * (1.0 - t)

    @property
    def field_names(self) -> tuple[str, ...]:
        """None beyond the geometry's."""
        return ()

    @property
    def gap_lower(self) -> float:
        """The gap's lower bound, 0."""
        return HARD_WALL.gap_lower

    @property
    def pressure_lower(self) -> float:
        """The pressure's lower bound: the largest tension, ``-w/rho``."""
        return -self.strength

    def pressure_upper(self, footprint: Any, xp: Any) -> Any:
        """Unbounded on the footprint, 0 off it."""
        return HARD_WALL.pressure_upper(footprint, xp)

    def violation(self, min_gap: float, scale_length: float) -> str | None:
        """The hard wall's check."""
        return HARD_WALL.violation(min_gap, scale_length)

    def residual(self, gap: np.ndarray, pressure: np.ndarray, stiffness: float) -> np.ndarray:
        """The natural residual in units of the gap, ``min(g, (p + phi'(g))/k)``."""
        return np.minimum(gap, (pressure + self.derivative(gap)) / stiffness)

    def plastic(self, gap: np.ndarray, pressure: np.ndarray, stiffness: float) -> np.ndarray:
        """No pixel is plastic."""
        return np.zeros(np.shape(gap), dtype=bool)

    def scalars(self, plastic_pixels: int, pixels: int) -> dict[str, Any]:
        """Nothing beyond the geometry's scalars."""
        return {}

    def fields(self, gap: np.ndarray, plastic: np.ndarray) -> dict[str, np.ndarray]:
        """Nothing beyond the geometry's fields."""
        return {}

    def check_nominal(self, pressure: float, what: str) -> None:
        """Any finite nominal pressure, tension too (whether the surfaces then stay together
        is what the solve finds)."""
        if not np.isfinite(pressure):
            raise ValueError(f"{what}: a nominal pressure of {pressure} is not a finite number")
