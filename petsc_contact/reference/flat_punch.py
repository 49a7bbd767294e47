"""Rigid flat punches on an elastic half-space: their normal stiffness (paper Eq. 2's ``K_flat``).

A rigid flat punch of footprint area ``A`` pressed into a half-space of contact modulus ``E*``
has the stiffness ``K = beta 2 E* sqrt(A/pi)``, with a shape factor ``beta`` of its outline:

* the circle, ``beta = 1`` exactly (Boussinesq): ``K = 2 E* r``;
* the square of side ``L``, ``beta = 1.0212`` (:data:`SQUARE_BETA`): ``K = pi C E* L =
  1.15230 E* L``, with ``C = 0.3667874`` (:data:`SQUARE_CAPACITANCE`) the capacitance of a
  unit square plate in units of ``4 pi eps0 L`` (Read 1997).  The rigid punch and the charged
  plate solve the same integral equation (a disk of radius ``a``: ``C = 8 eps0 a`` and
  ``K = 2 E* a``), so ``K = pi C E* L``;
* King's finite-element estimate for the square, ``beta = 1.012`` (:data:`KING_BETA`, King
  1987, as Pharr, Oliver & Brotzen 1992 quote it): ``K = 1.142 E* L``, 0.9% below the exact
  value.

References
----------
F. H. Read, "Improved extrapolation technique in the boundary element method to find the
capacitances of the unit square and cube", J. Comput. Phys. 133, 1-5 (1997).

R. B. King, "Elastic analysis of some punch problems for a layered medium", Int. J. Solids
Struct. 23, 1657-1664 (1987).

G. M. Pharr, W. C. Oliver and F. R. Brotzen, "On the generality of the relationship among
contact stiffness, contact area, and elastic modulus during indentation", J. Mater. Res. 7,
613-617 (1992).
"""

from __future__ import annotations

import numpy as np

from ..conventions.validation import positive

SQUARE_CAPACITANCE: float = 0.3667874
"""The capacitance of a unit square plate, in units of ``4 pi eps0 L`` (Read 1997)."""

SQUARE_BETA: float = float(np.pi**1.5 * SQUARE_CAPACITANCE / 2)
"""The square's exact shape factor, ``pi C / (2/sqrt(pi)) = 1.0212``."""

KING_BETA: float = 1.012
"""King's (1987) finite-element estimate of the square's shape factor, as Pharr et al. quote it."""

CIRCLE_BETA: float = 1.0
"""The circle's shape factor (Boussinesq), exact."""


def circular_stiffness(radius: float, modulus: float) -> float:
    """The rigid circular punch's stiffness, ``K = 2 E* r`` (Boussinesq).

    Parameters
    ----------
    radius
        The punch's radius ``r``.
    modulus
        The contact modulus ``E*``.

    Returns
    -------
    float
        ``2 E* r``.
    """
    return 2 * positive("modulus", modulus) * positive("radius", radius)


def square_stiffness(side: float, modulus: float) -> float:
    """The rigid square punch's exact stiffness, ``K = pi C E* L = 1.15230 E* L``.

    Parameters
    ----------
    side
        The square's side ``L``.
    modulus
        The contact modulus ``E*``.

    Returns
    -------
    float
        ``pi C E* L`` with ``C`` = :data:`SQUARE_CAPACITANCE`.
    """
    return float(np.pi * SQUARE_CAPACITANCE * positive("modulus", modulus) * positive("side", side))


def stiffness(area: float, modulus: float, beta: float = SQUARE_BETA) -> float:
    """A rigid flat punch's stiffness from its footprint's area, ``K = beta 2 E* sqrt(A/pi)``.

    Parameters
    ----------
    area
        The footprint's area ``A``.
    modulus
        The contact modulus ``E*``.
    beta
        The footprint's shape factor: :data:`SQUARE_BETA` (default, exact), :data:`KING_BETA`
        (King's estimate for the square) or :data:`CIRCLE_BETA`.

    Returns
    -------
    float
        ``beta 2 E* sqrt(A/pi)``.
    """
    return float(beta * circular_stiffness(np.sqrt(positive("area", area) / np.pi), modulus))
