"""Periodic contact of the wave ``h(x) = Delta cos(2 pi x / L)`` (Westergaard 1939).

A rigid sinusoid pressed on an elastic half-space of contact modulus ``E*`` under a nominal
pressure ``p0`` touches over the strip ``|x| < c`` around each crest until the full-contact
pressure ``p* = pi E* Delta / L`` is reached (Johnson, *Contact Mechanics*, section 13.2).
"""

from __future__ import annotations

import numpy as np

from ..conventions.validation import positive


def full_contact_pressure(amplitude: float, wavelength: float, modulus: float) -> float:
    """``p* = pi E* Delta / L``: the nominal pressure that closes the gap everywhere."""
    return float(np.pi * modulus * amplitude / wavelength)


def _ratio(p0: float, amplitude: float, wavelength: float, modulus: float) -> float:
    ratio = positive("nominal pressure", p0) / full_contact_pressure(amplitude, wavelength, modulus)
    if ratio > 1:
        raise ValueError(f"p0 exceeds the full-contact pressure by {ratio:.3g}x")
    return ratio


def half_width(p0: float, amplitude: float, wavelength: float, modulus: float) -> float:
    """Half-width ``c`` of the contact strip: ``sin^2(pi c/L) = p0/p*``."""
    ratio = _ratio(p0, amplitude, wavelength, modulus)
    return float(wavelength / np.pi * np.arcsin(np.sqrt(ratio)))


def pressure(
    x: np.ndarray, p0: float, amplitude: float, wavelength: float, modulus: float
) -> np.ndarray:
    """Contact pressure at ``x`` (crest at ``x = 0``, periodic in ``L``).

    ``p = 2 p0 cos(pi x/L) sqrt(sin^2(pi c/L) - sin^2(pi x/L)) / sin^2(pi c/L)`` inside the
    strip, zero outside; its mean over a period is ``p0``.
    """
    c = half_width(p0, amplitude, wavelength, modulus)
    xs = (np.asarray(x, dtype=float) + wavelength / 2) % wavelength - wavelength / 2
    s2 = np.sin(np.pi * c / wavelength) ** 2
    phase = np.pi * xs / wavelength
    inside = np.abs(xs) < c
    root = np.sqrt(np.clip(s2 - np.sin(phase) ** 2, 0.0, None))
    return np.where(inside, 2 * p0 * np.cos(phase) * root / s2, 0.0)


def mean_gap(p0: float, amplitude: float, wavelength: float, modulus: float) -> float:
    """``u_bar = Delta (1 - r + r ln r)``, ``r = p0/p*`` (the work done on the crest strips)."""
    r = _ratio(p0, amplitude, wavelength, modulus)
    return float(amplitude * (1 - r + r * np.log(r)))


def stiffness(p0: float, amplitude: float, wavelength: float, modulus: float) -> float:
    """``K = -dp0/du_bar = p*/(Delta ln(p*/p0))`` per area."""
    r = _ratio(p0, amplitude, wavelength, modulus)
    p_star = full_contact_pressure(amplitude, wavelength, modulus)
    return float(p_star / (amplitude * np.log(1 / r))) if r < 1 else float("inf")
