"""What a geometry asks of an interaction: the bounds of its unknowns and the check of an
answer against them (docs/formulation.md)."""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np


class Interaction(Protocol):
    """The law at the surface, as bounds of a bound-constrained problem.

    Attributes
    ----------
    name
        What the run's record calls it.
    """

    name: str

    @property
    def field_names(self) -> tuple[str, ...]:
        """The fields it adds to a step's (:meth:`fields`)."""
        ...

    @property
    def gap_lower(self) -> float:
        """The lower bound of the gap (a problem posed in the gap)."""
        ...

    @property
    def pressure_lower(self) -> float:
        """The lower bound of the pressure (a problem posed in the pressure)."""
        ...

    def pressure_upper(self, footprint: Any, xp: Any) -> Any:
        """The upper bound of the pressure on each pixel of a boolean ``footprint`` (an
        array of the array module ``xp``): what the surface can carry there."""
        ...

    def violation(self, min_gap: float, scale_length: float) -> str | None:
        """Why a solution whose smallest gap is ``min_gap`` breaks the law (``None``: it
        does not); ``scale_length`` sets what rounding allows."""
        ...

    def residual(self, gap: np.ndarray, pressure: np.ndarray, stiffness: float) -> np.ndarray:
        """The natural residual of the law on each pixel, in units of the gap, for a pixel
        stiffness ``stiffness`` (the pressure of a unit gap)."""
        ...

    def plastic(self, gap: np.ndarray, pressure: np.ndarray, stiffness: float) -> np.ndarray:
        """The pixels held at the pressure's upper bound (not in the held set of the exact
        stiffness: their pressure does not change with the load)."""
        ...

    def scalars(self, plastic_pixels: int, pixels: int) -> dict[str, Any]:
        """What a step adds to its scalars, from its count of :meth:`plastic` pixels."""
        ...

    def fields(self, gap: np.ndarray, plastic: np.ndarray) -> dict[str, np.ndarray]:
        """What a step adds to its fields (named by :attr:`field_names`)."""
        ...

    def check_nominal(self, pressure: float, what: str) -> None:
        """``ValueError`` in one line for a nominal pressure the law cannot carry; ``what``
        names the load."""
        ...
