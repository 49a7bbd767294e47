"""The elastic half-space, the substrate of the paper: under a periodic cell and with a free
surface (paper Eqs. 3-4; Johnson 1985)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..conventions.validation import positive
from ..physics.greens import hockney_kernel, mean_mode_compliance, periodic_stiffness


@dataclass(frozen=True)
class PeriodicHalfSpace:
    """A half-space under a periodic cell: stiffness ``E* |q| / 2``, zero at ``q = 0``
    (:class:`~petsc_contact.substrates.substrate.PeriodicSubstrate`)."""

    modulus: float
    name = "half-space"

    def __post_init__(self) -> None:
        positive("modulus", self.modulus)

    def stiffness(self, q: Any) -> Any:
        """``E* |q| / 2`` (:func:`~petsc_contact.physics.greens.periodic_stiffness`)."""
        return periodic_stiffness(q, self.modulus)

    def mean_mode_compliance(self, q0: float, interfacial_stiffness: float) -> float:
        """:func:`~petsc_contact.physics.greens.mean_mode_compliance`."""
        return mean_mode_compliance(self.modulus, q0, interfacial_stiffness)


@dataclass(frozen=True)
class FreeHalfSpace:
    """A half-space with a free surface around the contact: Boussinesq's pixel influence
    function on the zero-padded grid (:func:`~petsc_contact.physics.greens.hockney_kernel`;
    :class:`~petsc_contact.substrates.substrate.FreeSubstrate`)."""

    modulus: float
    name = "half-space"

    def __post_init__(self) -> None:
        positive("modulus", self.modulus)

    def compliance_kernel(
        self, shape: tuple[int, int], spacing: tuple[float, float], rows: slice
    ) -> np.ndarray:
        """:func:`~petsc_contact.physics.greens.hockney_kernel` of ``E*``."""
        return hockney_kernel(shape, spacing, self.modulus, rows)
