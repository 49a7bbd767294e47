"""The hard wall: non-adhesive, frictionless contact (the paper's model).

The gap is never negative, the pressure never tensile, and one of them vanishes on every
pixel (``g >= 0, p >= 0, p g = 0``): the KKT conditions of the bound-constrained problem,
whose bound is ``g >= 0`` posed in the gap and ``p >= 0`` (zero off a punch's footprint)
posed in the pressure.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

BOUND_ROUNDING = 1e-12  # a gap this far below zero, relative to the scale length, is rounding


@dataclass(frozen=True)
class HardWall:
    """The hard wall (:class:`~petsc_contact.interactions.interaction.Interaction`)."""

    name = "hard wall"

    @property
    def field_names(self) -> tuple[str, ...]:
        """None beyond the geometry's."""
        return ()

    @property
    def gap_lower(self) -> float:
        """The gap's lower bound, 0."""
        return 0.0

    @property
    def pressure_lower(self) -> float:
        """The pressure's lower bound, 0: no tension."""
        return 0.0

    def pressure_upper(self, footprint: Any, xp: Any) -> Any:
        """Unbounded on the footprint, 0 off it."""
        return xp.where(footprint, np.inf, 0.0)

    def violation(self, min_gap: float, scale_length: float) -> str | None:
        """``bound violated: min gap ...`` for a gap below zero by more than rounding."""
        if min_gap < -BOUND_ROUNDING * scale_length:
            return f"bound violated: min gap {min_gap:.3e}"
        return None

    def residual(self, gap: np.ndarray, pressure: np.ndarray, stiffness: float) -> np.ndarray:
        """The natural residual in units of the gap, ``min(g, p/k)``."""
        return np.minimum(gap, pressure / stiffness)

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
        """Any nominal pressure: the wall carries every load."""


HARD_WALL = HardWall()
"""The hard wall every geometry has by default."""
