"""Surface Green's functions of the elastic half-space and of a layer on a rigid base (pure
numpy).

Periodic (paper Appendix A): in Fourier space the pressure that holds a surface displacement
``u(q)`` is ``p(q) = E* |q| / 2 u(q)`` for ``q != 0``; the ``q = 0`` mode carries the mean
load and no displacement, so the stiffness kernel is 0 there.  Evaluated on the DFT
wavevectors this is exact for a single sine wave.  A layer of thickness ``T`` multiplies it by
:func:`layer_factor` of ``|q| T`` (docs/formulation.md, "A layer on a rigid base").
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..conventions.grid import fft_order
from ..conventions.validation import per_axis, positive


def periodic_stiffness(q: Any, modulus: float) -> Any:
    """Stiffness kernel ``E* |q| / 2`` (pressure per displacement), 0 at ``q = 0``; ``q`` a
    float or a float array of any array module (the kernel is made where it is)."""
    return 0.5 * modulus * q


BASES = ("bonded", "frictionless")
"""How a layer rests on its rigid base: bonded (``u = 0`` there) or sliding freely on it
(``u_z = 0``, no shear)."""

SERIES_BELOW = 0.5  # 2 |q| T below which sinh(2 |q| T) - 2 |q| T is summed as its series


def _sinh_excess(s: Any, t: Any) -> Any:
    """``1 - t^2 - 4 s t = 2 t (sinh 2s - 2s)`` with ``t = exp(-2s)``, free of cancellation:
    below :data:`SERIES_BELOW` from the series of ``sinh x - x`` (to ``x^13``, whose next
    term is ``1e-15`` of the sum there), above it as written (at most 40 times ``eps``)."""
    x2 = (2 * s) ** 2
    tail = 1 + x2 / 20 * (1 + x2 / 42 * (1 + x2 / 72 * (1 + x2 / 110 * (1 + x2 / 156))))
    series = 2 * t * (2 * s) ** 3 / 6 * tail
    return np.where(2 * s < SERIES_BELOW, series, 1 - t * t - 4 * s * t)


def layer_factor(s: Any, poisson: float, base: str) -> Any:
    """``f(s)``, ``s = |q| T > 0``, of a layer's surface stiffness ``K = E* |q| / 2 f``: the
    frictionless top of an isotropic layer of thickness ``T`` and Poisson ratio ``nu`` on a
    rigid base (:data:`BASES`), in plane strain along ``q`` (docs/formulation.md).

    With ``t = exp(-2s)`` and ``kappa = 3 - 4 nu``:

    - bonded: ``f = [kappa (1 + t^2) + (1 + kappa^2 + 4 s^2) t] / [(kappa - 1)(1 - t^2)
      + 1 - t^2 - 4 s t]``, that is ``(2 kappa cosh 2s + 1 + kappa^2 + 4 s^2) /
      (2 kappa sinh 2s - 4 s)``;
    - frictionless: ``f = (1 - t^2 + 4 s t) / (1 - t)^2 = (sinh 2s + 2s) / (cosh 2s - 1)``,
      which does not depend on ``nu``.

    Each term is non-negative for ``0 <= nu <= 1/2``, so no digits cancel at any ``s``
    (:func:`_sinh_excess`); ``f -> 1`` as ``s -> infinity`` and the thin limits are
    ``K -> M/T`` (bonded, ``M`` the oedometric modulus), ``3 E*/(4 q^2 T^3)`` (bonded,
    ``nu = 1/2``) and ``E*/T`` (frictionless).  ``s`` of any array module (made where it is).
    """
    t = np.exp(-2 * s)
    if base == "frictionless":
        return (-np.expm1(-4 * s) + 4 * s * t) / np.expm1(-2 * s) ** 2
    kappa = 3 - 4 * poisson
    top = kappa * (1 + t * t) + (1 + kappa * kappa + 4 * s * s) * t
    return top / ((kappa - 1) * -np.expm1(-4 * s) + _sinh_excess(s, t))


def periodic_compliance(q: np.ndarray | float, modulus: float, q_zero: float) -> np.ndarray:
    """Compliance kernel ``2 / (E* |q|)``, with ``|q| = q_zero`` used at ``q = 0``.

    The ``q = 0`` value is a convention (the stiffness is singular there); it is only used
    to precondition, where any positive value keeps the preconditioner positive definite.
    """
    q = np.asarray(q, dtype=float)
    return 2.0 / (modulus * np.where(q > 0, q, q_zero))


def mean_mode_compliance(modulus: float, q0: float, interfacial_stiffness: float) -> float:
    """The compliance a preconditioner gives the mean mode ``q = 0``: the package's one
    convention for it.

    The periodic stiffness vanishes at ``q = 0``, so its inverse has no value there.  Held
    by an interfacial stiffness ``K > 0`` the mean gap moves by ``dp0/K``, so the entry is
    ``1/K`` (:func:`held_compliance`); with no support it is the free compliance of the
    longest wavelength, ``2/(E* q0)`` (:func:`periodic_compliance`).
    """
    if interfacial_stiffness > 0:
        return 1.0 / interfacial_stiffness
    return float(periodic_compliance(0.0, modulus, q0))


def held_compliance(q: np.ndarray, modulus: float, interfacial_stiffness: float) -> np.ndarray:
    """Compliance ``1 / (E* |q|/2 + K)`` of the open surface of a contact of stiffness ``K``.

    The contact spots hold the surface like a uniform layer of springs of stiffness ``K``
    per area (the interfacial stiffness ``-dp0/du_bar``), in parallel with the half-space.
    The homogenised picture is exact for the mean mode (``1/K`` at ``q = 0``: a uniform
    pressure change moves the mean gap by ``dp0/K``) and becomes the free compliance
    ``2/(E*|q|)`` at wavelengths much shorter than ``E*/K``.  Used only to precondition
    problems restricted to the open pixels, where it is positive for any ``K > 0``.
    """
    positive("interfacial stiffness", interfacial_stiffness)
    return 1.0 / (periodic_stiffness(q, modulus) + interfacial_stiffness)


def _corner_primitive(xi: np.ndarray, eta: np.ndarray) -> np.ndarray:
    """``G(xi, eta) = int_0^xi int_0^eta dx dy / sqrt(x^2 + y^2)``, odd in each argument.

    For ``s, t > 0``: ``G = s asinh(t/s) + t asinh(s/t)``; ``G = 0`` on the axes.
    """
    s, t = np.abs(xi), np.abs(eta)
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.where((s > 0) & (t > 0), s * np.arcsinh(t / s) + t * np.arcsinh(s / t), 0.0)
    return np.sign(xi) * np.sign(eta) * g


def love_pixel_displacement(
    x: np.ndarray, y: np.ndarray, pixel: float | tuple[float, float], modulus: float
) -> np.ndarray:
    """Normal surface displacement at ``(x, y)`` under unit pressure on one pixel.

    The pixel ``[-a/2, a/2] x [-b/2, b/2]`` (``pixel = a`` for a square one, ``(a, b)`` for a
    rectangle) carries a uniform unit pressure on an elastic half-space of contact modulus
    ``E*``; Boussinesq's point-force solution integrated over the pixel (Love 1929; Johnson,
    Contact Mechanics, 1985, eq. 3.25) gives

        u(x, y) = 1/(pi E*) sum_corners (+-) G(x - x_c, y - y_c)

    with the primitive ``G`` of ``1/r`` (see :func:`_corner_primitive`).  At the centre of a
    square pixel ``u = 4 a asinh(1) / (pi E*)``.
    """
    hx, hy = (0.5 * v for v in per_axis(pixel, "pixel"))
    total = (
        _corner_primitive(x + hx, y + hy)
        - _corner_primitive(x + hx, y - hy)
        - _corner_primitive(x - hx, y + hy)
        + _corner_primitive(x - hx, y - hy)
    )
    return total / (np.pi * modulus)


def hockney_kernel(
    n: int | tuple[int, int],
    pixel: float | tuple[float, float],
    modulus: float,
    rows: slice = slice(None),
) -> np.ndarray:
    """The pixel influence function on the ``2nx x 2ny`` zero-padding grid (Hockney 1970).

    ``n`` and ``pixel`` are one value for a square grid of square pixels, or the pairs
    ``(nx, ny)`` and ``(a, b)``.  Entry ``[i, j]`` is the displacement at offset
    ``(i a, j b)`` with offsets taken periodically in ``[-nx, nx) x [-ny, ny)`` (numpy's
    ``fftfreq`` order).  Circular convolution of a pressure zero-padded from ``nx x ny`` to
    ``2nx x 2ny`` with this kernel, read back on the first ``nx x ny`` block, is the exact
    non-periodic (free-boundary) convolution, because no offset between two footprint
    pixels exceeds ``nx - 1`` (``ny - 1``).  ``rows`` selects the rows to evaluate (a rank's
    slab).
    """
    (nx, ny), (a, b) = per_axis(n, "grid"), per_axis(pixel, "pixel")
    x = fft_order(2 * nx)[rows] * a
    y = fft_order(2 * ny) * b
    return love_pixel_displacement(x[:, None], y[None, :], (a, b), modulus)
