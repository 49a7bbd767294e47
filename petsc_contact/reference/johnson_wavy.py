"""Adhesive contact of the wave ``h(x) = Delta cos(2 pi x / L)`` in the JKR limit (Johnson 1995).

K. L. Johnson, "The adhesion of two elastic bodies with slightly wavy surfaces", Int. J.
Solids Struct. 32 (1995) 423.  A short-range attraction of work ``w`` (its range far below the
contact's size) turns the edges of Westergaard's contact strips ``|x| < a`` into cracks: the
Westergaard pressure of the strip (:mod:`~petsc_contact.reference.westergaard`, bounded at
its edges, of mean ``p* sin^2(psi)``, ``psi = pi a / L``, ``p* = pi E* Delta / L``) is
superposed on the periodic flat strips' ``p_f cos(pi x/L) / sqrt(sin^2 psi - sin^2(pi x/L))``
(of mean ``p_f``), whose stress intensity at the edges is ``K = p_f sqrt(L / tan psi)``.
Griffith's balance ``K^2 / (2 E*) = w`` (the crack tension, ``p_f < 0``) gives the mean
pressure at a half-width ``a``,

    p0(a) = p* sin^2(psi) - sqrt(2 E* w tan(psi) / L),

which at ``w = 0`` is Westergaard's and for ``a << L`` the JKR cylinder's (Barquins 1988) of
radius ``R = L^2 / (4 pi^2 Delta)`` per wavelength, ``p0 L = pi E* a^2 / (4 R) - sqrt(2 pi E* w
a)``.  Under load control the contact is stable where ``p0`` grows with ``a``: from the
pull-off, ``p0``'s minimum (:func:`pull_off`), to its maximum, where the surfaces jump into
full contact (none where the attraction is so strong that ``p0`` never grows).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from ..conventions.validation import positive
from .westergaard import full_contact_pressure

_EDGE = 1e-9  # psi's distance from 0 and pi/2, where p0's slope is unbounded


def mean_pressure(
    half_width: float, amplitude: float, wavelength: float, modulus: float, work: float
) -> float:
    """``p0(a) = p* sin^2(pi a/L) - sqrt(2 E* w tan(pi a/L) / L)`` (module docstring)."""
    psi = np.pi * half_width / wavelength
    p_star = full_contact_pressure(amplitude, wavelength, modulus)
    return float(p_star * np.sin(psi) ** 2 - np.sqrt(2 * modulus * work * np.tan(psi) / wavelength))


def _slope(psi: float, amplitude: float, wavelength: float, modulus: float, work: float) -> float:
    """``dp0/dpsi``."""
    p_star = full_contact_pressure(amplitude, wavelength, modulus)
    adhesive = np.sqrt(2 * modulus * work / wavelength) / (2 * np.sqrt(np.tan(psi)))
    return float(p_star * np.sin(2 * psi) - adhesive / np.cos(psi) ** 2)


def stable_branch(
    amplitude: float, wavelength: float, modulus: float, work: float
) -> tuple[float, float]:
    """The half-widths ``(a_off, a_max)`` between which ``p0(a)`` grows (load control's stable
    contact), from its minimum (the pull-off) to its maximum; ``ValueError`` where it never
    grows.  At ``w = 0``: ``(0, L/2)``."""
    positive("amplitude", amplitude)
    if work == 0:
        return 0.0, wavelength / 2
    positive("work of adhesion", work)
    args = (amplitude, wavelength, modulus, work)
    grid = np.linspace(_EDGE, np.pi / 2 - _EDGE, 2001)
    slopes = np.array([_slope(psi, *args) for psi in grid])
    rising = np.flatnonzero(slopes > 0)
    if rising.size == 0:
        raise ValueError("the attraction is so strong that no partial contact is stable")
    lo, hi = rising[0], rising[-1]
    psi_off = brentq(_slope, grid[lo - 1], grid[lo], args=args, xtol=1e-15)
    psi_max = brentq(_slope, grid[hi], grid[hi + 1], args=args, xtol=1e-15)
    return wavelength * psi_off / np.pi, wavelength * psi_max / np.pi


def pull_off(amplitude: float, wavelength: float, modulus: float, work: float) -> float:
    """The pull-off pressure under load control: ``p0``'s minimum on the stable branch."""
    a_off, _ = stable_branch(amplitude, wavelength, modulus, work)
    return mean_pressure(a_off, amplitude, wavelength, modulus, work)


def half_width(
    p0: float, amplitude: float, wavelength: float, modulus: float, work: float
) -> float:
    """The half-width ``a`` of the stable contact under the mean pressure ``p0``: the root of
    ``p0(a) = p0`` on :func:`stable_branch`; ``ValueError`` where ``p0`` is beyond it (below
    the pull-off, or above the jump into full contact)."""
    a_off, a_max = stable_branch(amplitude, wavelength, modulus, work)
    args = (amplitude, wavelength, modulus, work)
    low, high = mean_pressure(a_off, *args), mean_pressure(a_max, *args)
    if not low <= p0 <= high:
        raise ValueError(f"p0 = {p0:.4g} is off the stable branch [{low:.4g}, {high:.4g}]")
    return float(brentq(lambda a: mean_pressure(a, *args) - p0, a_off, a_max, xtol=1e-15))
