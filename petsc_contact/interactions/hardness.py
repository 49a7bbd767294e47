"""A hardness cap: the hard wall whose pressure cannot exceed a hardness ``H``.

Kato's perfectly plastic surface layer: a pixel carries at most ``H``; where the elastic
answer would press harder the surface flows, its pressure stays at ``H`` and the rigid body
sinks into it by the plastic displacement ``w >= 0``.  The conditions on every pixel are

    0 <= p <= H,   g >= 0 where p < H,   g = 0 where 0 < p < H,   w = -g >= 0 where p = H,

the KKT conditions of the bound-constrained problem posed in the pressure with the box
``0 <= p <= H`` (docs/formulation.md): the gradient (the gap) is zero between the bounds,
non-negative at ``p = 0`` and non-positive at ``p = H``, where ``-g`` is the plastic
displacement.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..conventions.validation import positive
from .hard_wall import HARD_WALL


@dataclass(frozen=True)
class HardnessCap:
    """The hard wall with the pressure capped at ``hardness``
    (:class:`~petsc_contact.interactions.interaction.Interaction`).

    Parameters
    ----------
    hardness
        The largest pressure the surface carries, ``H > 0`` (in the modulus' unit).
    """

    hardness: float
    name = "hardness cap"

    def __post_init__(self) -> None:
        positive("--hardness", self.hardness)

    @property
    def field_names(self) -> tuple[str, ...]:
        """``plastic_displacement`` (:meth:`fields`)."""
        return ("plastic_displacement",)

    @property
    def gap_lower(self) -> float:
        """The gap's lower bound off the cap, 0."""
        return HARD_WALL.gap_lower

    @property
    def pressure_lower(self) -> float:
        """The pressure's lower bound, 0: no tension."""
        return HARD_WALL.pressure_lower

    def pressure_upper(self, footprint: Any, xp: Any) -> Any:
        """The hardness on the footprint, 0 off it."""
        return xp.where(footprint, self.hardness, 0.0)

    def violation(self, min_gap: float, scale_length: float) -> str | None:
        """The hard wall's check, on the gaps of the pixels below the cap."""
        return HARD_WALL.violation(min_gap, scale_length)

    def residual(self, gap: np.ndarray, pressure: np.ndarray, stiffness: float) -> np.ndarray:
        """The natural residual of the box ``0 <= p <= H`` in units of the gap,
        ``(p - clip(p - k g, 0, H)) / k = max(min(g, p/k), (p - H)/k)``."""
        elastic = HARD_WALL.residual(gap, pressure, stiffness)
        return np.maximum(elastic, (pressure - self.hardness) / stiffness)

    def plastic(self, gap: np.ndarray, pressure: np.ndarray, stiffness: float) -> np.ndarray:
        """The pixels at the cap, ``p - k g > H``: the projection of the natural residual
        picks the upper bound (on an exact answer: ``p = H`` and ``g < 0``)."""
        return np.asarray(pressure - stiffness * gap > self.hardness)

    def scalars(self, plastic_pixels: int, pixels: int) -> dict[str, Any]:
        """``plastic_area_fraction``: the share of the ``pixels`` at the cap."""
        return {"plastic_area_fraction": plastic_pixels / pixels}

    def fields(self, gap: np.ndarray, plastic: np.ndarray) -> dict[str, np.ndarray]:
        """``plastic_displacement``: ``-g`` on the pixels at the cap, 0 elsewhere."""
        return {"plastic_displacement": np.where(plastic, np.maximum(-gap, 0.0), 0.0)}

    def check_nominal(self, pressure: float, what: str) -> None:
        """``ValueError`` in one line for a nominal ``pressure`` the cap cannot carry (at or
        above ``H``: the whole surface would flow); ``what`` names the load."""
        if not pressure < self.hardness:
            raise ValueError(
                f"{what}: a nominal pressure of {pressure:.4g} is not below the hardness "
                f"{self.hardness:.4g}: the whole surface would flow"
            )
