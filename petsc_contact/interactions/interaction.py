"""What a geometry asks of an interaction: the bounds of its unknowns and the check of an
answer against them (docs/formulation.md)."""

from __future__ import annotations

from typing import Any, Protocol


class Interaction(Protocol):
    """The law at the surface, as bounds of a bound-constrained problem.

    Attributes
    ----------
    name
        What the run's record calls it.
    """

    name: str

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
