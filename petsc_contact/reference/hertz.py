"""A rigid sphere of radius ``R`` pressed on an elastic half-space (Hertz 1882).

For a contact modulus ``E*`` and an approach ``delta``: contact radius ``a = sqrt(R delta)``,
force ``F = 4/3 E* sqrt(R) delta^(3/2)``, pressure ``p0 sqrt(1 - r^2/a^2)`` with the peak
``p0 = 3F/(2 pi a^2)``, and normal stiffness ``dF/d delta = 2 E* a`` (Johnson, section 4.2).

In a square periodic cell of side ``L`` whose displacements have zero mean (the cell of the
periodic simulations), the other cells' loads and the zero mean add a uniform displacement
near the load: the zero-mean periodic Green's function is
``u(r) = F [1/(pi E* r) - c/(E* L)] + O(r^2/L^3)`` with ``c = -4 zeta(1/2) beta(1/2)/pi``
(:data:`PERIODIC_SELF`, the regularised square-lattice sum of ``1/|k|``; Zucker, J. Phys. A 7,
1568, 1974), so a contact of radius ``a << L`` is stiffer than in a half-space:
``1/K = 1/(2 E* a) - c/(E* L)`` (:func:`periodic_stiffness`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..conventions.validation import non_negative, positive

ZETA_HALF = -1.4603545088095868  # Riemann's zeta(1/2)
BETA_HALF = 0.6676914571896092  # Dirichlet's beta(1/2)
PERIODIC_SELF = -4 * ZETA_HALF * BETA_HALF / np.pi
"""``c`` = 1.24149: the uniform part ``-c F/(E* L)`` of the zero-mean periodic Green's
function of a square cell of side ``L`` at its load (module docstring)."""


def contact_radius(approach: float, radius: float) -> float:
    """``a = sqrt(R delta)``."""
    return float(np.sqrt(positive("radius", radius) * non_negative("approach", approach)))


def force(approach: float, radius: float, modulus: float) -> float:
    """``F = 4/3 E* sqrt(R) delta^(3/2)``."""
    d = non_negative("approach", approach)
    return float(
        4 / 3 * positive("modulus", modulus) * np.sqrt(positive("radius", radius)) * d**1.5
    )


def radius_at_force(force_: Any, radius: float, modulus: float) -> Any:
    """Contact radius under a force (scalar or array): ``a = (3 F R/(4 E*))^(1/3)``."""
    f = np.asarray(force_, dtype=float)
    if not np.all(np.isfinite(f) & (f >= 0)):
        raise ValueError(f"force must be non-negative and finite, got {force_}")
    a = (3 * f * positive("radius", radius) / (4 * positive("modulus", modulus))) ** (1 / 3)
    return float(a) if a.ndim == 0 else a


def pressure(r: np.ndarray, approach: float, radius: float, modulus: float) -> np.ndarray:
    """Pressure at distance ``r`` from the axis: ``3F/(2 pi a^2) sqrt(1 - r^2/a^2)``."""
    a = contact_radius(approach, radius)
    peak = 3 * force(approach, radius, modulus) / (2 * np.pi * a * a)
    rr = np.asarray(r, dtype=float)
    return peak * np.sqrt(np.clip(1 - (rr / a) ** 2, 0.0, None))


def stiffness(approach: float, radius: float, modulus: float) -> float:
    """Normal stiffness ``dF/d delta = 2 E* a``."""
    return 2 * positive("modulus", modulus) * contact_radius(approach, radius)


def periodic_stiffness(radius_a: Any, modulus: float, cell: float) -> Any:
    """Normal stiffness of a Hertz contact of radius ``a`` in a square periodic cell of side
    ``L`` with zero-mean displacement: ``1/K = 1/(2 E* a) - c/(E* L)``, ``c`` =
    :data:`PERIODIC_SELF` (module docstring; valid while ``a << L``).  ``radius_a`` may be
    an array."""
    e, length = positive("modulus", modulus), positive("cell", cell)
    a = np.asarray(radius_a, dtype=float)
    k = 1.0 / (1.0 / (2 * e * a) - PERIODIC_SELF / (e * length))
    return float(k) if k.ndim == 0 else k
