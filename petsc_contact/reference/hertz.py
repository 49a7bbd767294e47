"""A rigid sphere of radius ``R`` pressed on an elastic half-space (Hertz 1882).

For a contact modulus ``E*`` and an approach ``delta``: contact radius ``a = sqrt(R delta)``,
force ``F = 4/3 E* sqrt(R) delta^(3/2)``, pressure ``p0 sqrt(1 - r^2/a^2)`` with the peak
``p0 = 3F/(2 pi a^2)``, and normal stiffness ``dF/d delta = 2 E* a`` (Johnson, section 4.2).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..conventions.validation import non_negative, positive


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
