"""Rigid flat punches on an elastic half-space: their normal stiffness.

A circular punch of radius ``r`` has ``K = 2 E* r`` exactly (Boussinesq).  Other footprints of
area ``A`` follow ``K = beta 2 E* sqrt(A/pi)``; for a square ``beta = 1.012`` (Pharr, Oliver &
Brotzen, J. Mater. Res. 7, 613 (1992)).
"""

from __future__ import annotations

import numpy as np

from ..conventions.validation import positive

SQUARE_BETA = 1.012


def circular_stiffness(radius: float, modulus: float) -> float:
    """``K = 2 E* r``."""
    return 2 * positive("modulus", modulus) * positive("radius", radius)


def stiffness(area: float, modulus: float, beta: float = SQUARE_BETA) -> float:
    """``K = beta 2 E* sqrt(A/pi)`` (``beta = 1`` for the circle, 1.012 for the square)."""
    return float(beta * circular_stiffness(np.sqrt(positive("area", area) / np.pi), modulus))
