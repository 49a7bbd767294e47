"""An elastic layer of finite thickness on a rigid base, under a periodic cell
(docs/formulation.md, "A layer on a rigid base")."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..conventions.validation import positive
from ..physics.greens import BASES, layer_factor, mean_mode_compliance, periodic_stiffness

DEFAULT_POISSON = 0.3
"""The Poisson ratio of a layer none is given for (``--poisson``'s default: docs/cli.md says
why)."""


def check_layer(poisson: float, base: str) -> None:
    """``ValueError`` in one line for a Poisson ratio outside ``[0, 1/2]`` or a base not among
    :data:`~petsc_contact.physics.greens.BASES`."""
    if not 0 <= poisson <= 0.5:  # NaN too
        raise ValueError(f"--poisson must be from 0 to 0.5, got {poisson}")
    if base not in BASES:
        raise ValueError(f"--base must be one of {', '.join(BASES)}, not '{base}'")


@dataclass(frozen=True)
class PeriodicLayer:
    """A layer of thickness ``thickness`` under a periodic cell, on a rigid base (``bonded`` or
    ``frictionless``): stiffness ``E* |q| / 2 f(|q| T, nu)``
    (:func:`~petsc_contact.physics.greens.layer_factor`), zero at ``q = 0``
    (:class:`~petsc_contact.substrates.substrate.PeriodicSubstrate`).

    The layer's own uniform stiffness (``q = 0``) is finite, but under load control the mean
    pressure is prescribed: it moves the base's approach by ``p0 / K(0)`` and neither the gap
    nor the pressure, so the mean mode stays the gap problem's, as on the half-space.
    """

    modulus: float
    thickness: float
    poisson: float = DEFAULT_POISSON
    base: str = "bonded"
    name = "layer"

    def __post_init__(self) -> None:
        positive("modulus", self.modulus)
        positive("--thickness", self.thickness)
        check_layer(self.poisson, self.base)

    def factor(self, q: Any) -> Any:
        """``f(|q| T, nu)`` at wavevector magnitudes ``q > 0`` (1 where ``q = 0``)."""
        s = np.where(q > 0, q * self.thickness, 1.0)
        return layer_factor(s, self.poisson, self.base)

    def stiffness(self, q: Any) -> Any:
        """``E* |q| / 2 f(|q| T, nu)``, 0 at ``q = 0``."""
        return periodic_stiffness(q, self.modulus) * self.factor(q)

    def mean_mode_compliance(self, q0: float, interfacial_stiffness: float) -> float:
        """The half-space's convention (:func:`~petsc_contact.physics.greens.
        mean_mode_compliance`) with the layer's stiffness at ``q0``: its free compliance
        ``1/K(q0)``."""
        stiffer = self.modulus * float(self.factor(np.float64(q0)))
        return mean_mode_compliance(stiffer, q0, interfacial_stiffness)
