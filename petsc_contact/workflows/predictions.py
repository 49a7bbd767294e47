"""What theory predicts for a given height map: Persson's ``u_bar(p)`` and ``K(p)``, the
exponential law's ``u0`` and ``beta``, and the finite-size crossover ``p_c``.

This is the comparison the paper's experiment section makes, and an experimentalist's
first question about a measured surface.  The map's radially averaged spectrum
(:func:`~petsc_contact.physics.surface.radial_psd`, the map taken as periodic) feeds Persson's
integrals (:mod:`~petsc_contact.physics.theory`), with ``C`` held at its first bin's value down to
``q0 = 2 pi/L`` (the first bin's mean ``|q|`` lies above ``q0``, and Persson's integrals
weigh the lowest wavevectors most).  ``p_c`` (paper Eq. 13) needs a Hurst exponent:
it is fitted to the spectrum's power law ``C ~ q^(-2-2H)`` between ``2 q0`` and half the
Nyquist wavevector, and the map is taken as ``L = lambda_r`` (no roll-off inside it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..conventions.fft import FFT, SerialFFT
from ..conventions.grid import Grid, grid_for
from ..io.topography import SurfaceTopographyMap, map_and_lengths
from ..physics import theory
from ..physics.surface import radial_psd, rms_of

DEFAULT_LOADS = (1e-7, 1e-1, 25)  # p/E* from, to, how many (log-spaced)
ROUNDING = 1e-24  # C(q) below this times its largest value is rounding noise (eps^2 ~ 5e-32)


@dataclass(frozen=True)
class Prediction:
    """Theory for one map (lengths in the map's unit, pressures in the modulus's)."""

    wavevector: np.ndarray
    psd: np.ndarray
    nominal_pressure: np.ndarray
    mean_gap: np.ndarray
    stiffness: np.ndarray
    u0: float
    beta: float
    hurst_fit: float
    fit_range: tuple[float, float]
    rms_height: float
    rms_slope: float
    crossover_pressure: float  # paper Eq. 13 as printed
    crossover_pressure_appendix: float  # with the appendix's q_r ~ pi/L and theta ~ 1

    def scalars(self) -> dict[str, float | list[float]]:
        """The single numbers, for a file's attributes or a printout."""
        return {
            "u0": self.u0,
            "beta": self.beta,
            "hurst_fit": self.hurst_fit,
            "fit_range": list(self.fit_range),
            "rms_height": self.rms_height,
            "rms_slope": self.rms_slope,
            "crossover_pressure": self.crossover_pressure,
            "crossover_pressure_appendix": self.crossover_pressure_appendix,
        }


def hurst_from_spectrum(
    q: np.ndarray, psd: np.ndarray, window: tuple[float, float]
) -> tuple[float, tuple[float, float]]:
    """``H`` of the least-squares power law ``C ~ q^(-2-2H)`` on ``window`` (log-log), and the
    window used (clipped to the data)."""
    keep = (q >= window[0]) & (q <= window[1]) & (psd > 0)
    if np.count_nonzero(keep) < 3:
        raise ValueError("too few spectrum points to fit a Hurst exponent (a map this small?)")
    slope = np.polyfit(np.log(q[keep]), np.log(psd[keep]), 1)[0]
    return float(-slope / 2 - 1), (float(q[keep][0]), float(q[keep][-1]))


def predict(
    grid: Grid, fft: FFT, heights: np.ndarray, modulus: float, pressures: np.ndarray
) -> Prediction:
    """Persson's theory and the finite-size estimates from the spectrum of ``heights``."""
    q, c = radial_psd(grid, fft, heights)
    if not c.max() > 0:
        raise ValueError("the map is flat (h_rms = 0): it has no spectrum to predict from")
    keep = c > ROUNDING * c.max()  # beyond a cut-off the spectrum is FFT rounding
    q, c = q[keep], c[keep]
    if q[0] > grid.q0:  # the first bin's mean |q| lies above q0: hold C down to q0
        q, c = np.r_[grid.q0, q], np.r_[c[0], c]
    nyquist = np.pi / max(grid.spacing)
    hurst, window = hurst_from_spectrum(q, c, (2 * grid.q0, nyquist / 2))
    beta, u0 = theory.persson_exponential(q, c)
    h_rms = rms_of(grid, fft, heights)
    length = max(grid.lengths)
    p_c = {
        convention: theory.crossover_pressure(
            modulus, h_rms, float(np.clip(hurst, 0.05, 1.0)), length, 1.0, convention=convention
        )
        for convention in theory.CONVENTIONS
    }
    p = np.asarray(pressures, dtype=float)
    return Prediction(
        wavevector=q,
        psd=c,
        nominal_pressure=p,
        mean_gap=np.atleast_1d(theory.persson_mean_gap(p, q, c, modulus)),
        stiffness=np.atleast_1d(theory.persson_stiffness(p, q, c, modulus)),
        u0=u0,
        beta=beta,
        hurst_fit=hurst,
        fit_range=window,
        rms_height=h_rms,
        rms_slope=rms_of(grid, fft, heights, slope=True),
        crossover_pressure=p_c["printed"],
        crossover_pressure_appendix=p_c["appendix"],
    )


def predict_map(
    heights: np.ndarray | SurfaceTopographyMap,
    length: float | tuple[float, float] | None = None,
    modulus: float = 1.0,
    pressures: np.ndarray | None = None,
) -> Prediction:
    """Persson's theory and the finite-size estimates for a whole map, in one process.

    Parameters
    ----------
    heights
        An ``nx x ny`` array (prepared: no undefined points), or a SurfaceTopography
        ``Topography`` (its sides and unit).
    length
        The sides (``L`` or ``(Lx, Ly)``); optional for a topography.
    modulus
        The contact modulus ``E*``; pressures are in its unit.
    pressures
        Nominal pressures for ``u_bar(p)`` and ``K(p)`` (default: 25 from 1e-7 to 1e-1 E*).
    """
    array, length = map_and_lengths(heights, length)
    grid = grid_for(array.shape, length)
    if grid.comm.size > 1:
        from mpi4py import MPI

        grid = grid_for(array.shape, length, MPI.COMM_SELF)
    lo, hi, n = DEFAULT_LOADS
    p = np.geomspace(lo * modulus, hi * modulus, n) if pressures is None else pressures
    values = np.asarray(array, dtype=float)
    if not np.all(np.isfinite(values)):
        raise ValueError("the map has undefined heights: fill them first")
    return predict(grid, SerialFFT(grid), values, modulus, np.asarray(p, dtype=float))
