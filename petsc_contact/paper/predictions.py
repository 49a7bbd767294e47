"""What theory predicts for a given height map: Persson's ``u_bar(p)``, ``K(p)`` and
``A(p)/A0``, the exponential law's ``u0`` and ``beta``, and the finite-size crossover ``p_c``.

This is the comparison the paper's experiment (Appendix C) makes, and an experimentalist's
first question about a measured surface.  The map's radially averaged spectrum
(:func:`~petsc_contact.physics.surface.radial_psd`, the map taken as periodic) feeds Persson's
integrals (:mod:`~petsc_contact.physics.theory`), with ``C`` held at its first bin's value down to
``q0 = 2 pi/L`` (the first bin's mean ``|q|`` lies above ``q0``, and Persson's integrals
weigh the lowest wavevectors most): the realised spectrum, not a prescribed one.  ``p_c``
(paper Eq. 13, as printed and in the recipe of the paper's quoted values,
``theory.crossover_pressure``) needs a Hurst exponent: it is fitted to the spectrum's power law
``C ~ q^(-2-2H)`` between ``2 q0`` and half the Nyquist wavevector, and the map is taken as
``L = lambda_r`` (no roll-off inside it).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..conventions.grid import Grid, grid_for, self_comm
from ..conventions.validation import keywords_after_first
from ..conventions.warnings import PetscContactWarning, user_level
from ..devices.fft import FFT, SerialFFT
from ..io.topography import Channel, Heights, as_topography, check_given
from ..physics import theory
from ..physics.surface import radial_psd, rms_of

DEFAULT_LOADS = (1e-7, 1e-1, 25)  # p/E* from, to, how many (log-spaced)
ROUNDING = 1e-24  # C(q) below this times its largest value is rounding noise (eps^2 ~ 5e-32)
HURST_RANGE = (0.05, 1.0)  # a fitted H outside this is no self-affine spectrum
GOOD_FIT = 0.9  # a power law explaining less of log C (R^2) than this is a poor fit
SMALLEST_GAP = 1e-6  # Persson's u_bar below this times h_rms: contact is all but complete
SPECTRUM_2D = "2D map, radially averaged"
SPECTRUM_1D = "1D profile, taken as isotropic (C_2D = C_1D Gamma(1+H)/(sqrt(pi) Gamma(1/2+H) q))"


class TheoryWarning(PetscContactWarning):
    """A prediction the theory can make only with reservations (a poor fit, underflow)."""


@dataclass(frozen=True)
class Prediction:
    """Theory for one map (lengths in the map's unit, pressures in the modulus's)."""

    wavevector: np.ndarray
    psd: np.ndarray
    nominal_pressure: np.ndarray
    mean_gap: np.ndarray
    stiffness: np.ndarray
    area_fraction: np.ndarray  # A/A0 (theory.persson_area)
    spectrum_rms_slope: float  # h'_rms of the spectrum (q0 to q1), which A/A0 takes
    u0: float
    beta: float
    hurst_fit: float
    fit_range: tuple[float, float]
    rms_height: float
    rms_slope: float
    crossover_pressure: float  # paper Eq. 13 as printed
    crossover_pressure_appendix: float  # deprecated reading: q_r = pi/lambda_r, theta = 1
    hurst_fit_r2: float = 1.0  # the share of log C's variance the power law explains
    spectrum: str = SPECTRUM_2D  # how C(q) was obtained
    crossover_pressure_paper: float = float("nan")  # the recipe of the paper's quoted p_c

    def scalars(self) -> dict[str, float | str | list[float]]:
        """The single numbers, for a file's attributes or a printout."""
        return {
            "u0": self.u0,
            "beta": self.beta,
            "hurst_fit": self.hurst_fit,
            "hurst_fit_r2": self.hurst_fit_r2,
            "spectrum": self.spectrum,
            "fit_range": list(self.fit_range),
            "rms_height": self.rms_height,
            "rms_slope": self.rms_slope,
            "spectrum_rms_slope": self.spectrum_rms_slope,
            "crossover_pressure": self.crossover_pressure,
            "crossover_pressure_paper": self.crossover_pressure_paper,
            "crossover_pressure_appendix": self.crossover_pressure_appendix,
        }

    def _repr_html_(self) -> str:
        """A notebook's display: the single numbers and the loads predicted."""
        from ..io.tables import html_table

        p = self.nominal_pressure
        loads = f"{len(p)} nominal pressures" + (f", {p[0]:.3g} to {p[-1]:.3g}" if len(p) else "")
        return html_table("Prediction", {**self.scalars(), "loads": loads})


def hurst_from_spectrum(
    q: np.ndarray, psd: np.ndarray, window: tuple[float, float], dimension: int = 2
) -> tuple[float, tuple[float, float], float]:
    """``H`` of the least-squares power law ``C ~ q^(-dimension-2H)`` on ``window``
    (log-log), the window used (clipped to the data), and the fit's ``R^2`` in log-log."""
    keep = (q >= window[0]) & (q <= window[1]) & (psd > 0)
    if np.count_nonzero(keep) < 3:
        raise ValueError("too few spectrum points to fit a Hurst exponent (a map this small?)")
    x, y = np.log(q[keep]), np.log(psd[keep])
    slope, intercept = np.polyfit(x, y, 1)
    residual = y - (slope * x + intercept)
    spread = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - float(np.sum(residual**2)) / spread if spread > 0 else 1.0
    return float(-(slope + dimension) / 2), (float(q[keep][0]), float(q[keep][-1])), r2


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
    fit = hurst_from_spectrum(q, c, (2 * grid.q0, nyquist / 2))
    h_rms = rms_of(grid, fft, heights)
    slope = rms_of(grid, fft, heights, slope=True)
    return _persson(q, c, fit, h_rms, slope, max(grid.lengths), modulus, pressures, SPECTRUM_2D)


def predict_profile(
    heights: np.ndarray, length: float, modulus: float = 1.0, pressures: np.ndarray | None = None
) -> Prediction:
    """Persson's theory from a line scan, the surface taken as isotropic.

    The profile's spectrum ``C_1D(q)`` (the profile taken as periodic) is fitted with
    ``C_1D ~ q^(-1-2H)``, and the isotropic ``C_2D(q) = C_1D(q) Gamma(1+H) /
    (sqrt(pi) Gamma(1/2+H) q)`` (exact for a power law: ``C_1D`` is ``C_2D`` integrated across
    the profile) feeds Persson's integrals.  The prediction says so in its ``spectrum``.
    """
    from scipy.special import gamma as gamma_function

    h = np.asarray(heights, dtype=float)
    if h.ndim != 1 or h.size < 8 or not np.all(np.isfinite(h)):
        raise ValueError("a line scan needs at least 8 defined heights")
    pixel = length / h.size
    h = h - h.mean()
    spectrum = np.fft.rfft(h)
    q = 2 * np.pi * np.arange(spectrum.size) / length
    # two-sided: h_rms^2 = int C_1D dq over all q, and C_1D is C_2D integrated across
    c1 = pixel**2 * np.abs(spectrum) ** 2 / (2 * np.pi * length)
    q, c1 = _log_binned(q[1:], c1[1:])  # one mode's power scatters like an exponential
    if not c1.max() > 0:
        raise ValueError("the profile is flat (h_rms = 0): it has no spectrum to predict from")
    nyquist = np.pi / pixel
    fit = hurst_from_spectrum(q, c1, (2 * q[0], nyquist / 2), dimension=1)
    hurst = float(np.clip(fit[0], *HURST_RANGE))
    c2 = c1 * gamma_function(1 + hurst) / (np.sqrt(np.pi) * gamma_function(0.5 + hurst) * q)
    slope = float(np.sqrt(np.mean((np.diff(np.r_[h, h[0]]) / pixel) ** 2)))
    p = np.geomspace(*(DEFAULT_LOADS[0] * modulus, DEFAULT_LOADS[1] * modulus), DEFAULT_LOADS[2])
    loads = p if pressures is None else np.asarray(pressures, dtype=float)
    return _persson(q, c2, fit, float(h.std()), slope, length, modulus, loads, SPECTRUM_1D)


PROFILE_BINS = 20  # logarithmic bins per decade of a profile's spectrum


def _log_binned(q: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Means of ``q`` and ``c`` in logarithmic bins (:data:`PROFILE_BINS` per decade); the
    lowest modes, fewer than one per bin, stay as they are."""
    decades = np.log10(q[-1] / q[0])
    edges = q[0] * 10 ** (np.arange(int(np.ceil(decades * PROFILE_BINS)) + 2) / PROFILE_BINS)
    index = np.searchsorted(edges, q * (1 + 1e-12), side="right") - 1
    count = np.bincount(index)
    keep = count > 0
    return (
        np.bincount(index, weights=q)[keep] / count[keep],
        np.bincount(index, weights=c)[keep] / count[keep],
    )


def _persson(
    q: np.ndarray,
    c: np.ndarray,
    fit: tuple[float, tuple[float, float], float],
    h_rms: float,
    rms_slope: float,
    length: float,
    modulus: float,
    pressures: np.ndarray,
    spectrum: str,
) -> Prediction:
    """Persson's integrals on the spectrum ``(q, c)``, with the fit's warnings, and the
    loads where the theory underflows (its mean gap below ``SMALLEST_GAP h_rms``) left out."""
    hurst, window, r2 = fit
    _check_fit(hurst, window, r2)
    beta, u0 = theory.persson_exponential(q, c)
    p_c = {  # every reading, the deprecated one too (files keep its name)
        name: theory.crossover_pressure(
            modulus, h_rms, float(np.clip(hurst, *HURST_RANGE)), length, 1.0, convention=reading
        )
        for name, reading in theory.READINGS.items()
    }
    p = np.asarray(pressures, dtype=float)
    gap, stiffness, valid = _resolved_loads(p, q, c, modulus, h_rms)
    return Prediction(
        wavevector=q,
        psd=c,
        nominal_pressure=p[valid],
        mean_gap=gap[valid],
        stiffness=stiffness[valid],
        area_fraction=theory.persson_area(p[valid], q, c, modulus),
        spectrum_rms_slope=theory.spectrum_rms_slope(q, c),
        u0=u0,
        beta=beta,
        hurst_fit=hurst,
        fit_range=window,
        rms_height=h_rms,
        rms_slope=rms_slope,
        crossover_pressure=p_c["printed"],
        crossover_pressure_appendix=p_c["appendix"],
        hurst_fit_r2=r2,
        spectrum=spectrum,
        crossover_pressure_paper=p_c["paper"],
    )


def _check_fit(hurst: float, window: tuple[float, float], r2: float) -> None:
    """A :class:`TheoryWarning` when the power law fitted to the spectrum (exponent ``hurst``
    between the wavevectors ``window``, explaining ``r2`` of it) is no self-affine surface's
    or explains the spectrum poorly."""
    if not HURST_RANGE[0] < hurst < HURST_RANGE[1]:
        warnings.warn(
            f"the fitted Hurst exponent H = {hurst:.3g} lies outside {HURST_RANGE[0]:g}..."
            f"{HURST_RANGE[1]:g}: the spectrum is no power law of a self-affine surface between "
            f"q = {window[0]:.3g} and {window[1]:.3g}; p_c, which needs H, is not meaningful",
            TheoryWarning,
            stacklevel=user_level(),
        )
    elif r2 < GOOD_FIT:
        warnings.warn(
            f"the power law explains only R^2 = {r2:.2f} of log C(q) between q = "
            f"{window[0]:.3g} and {window[1]:.3g} (a good fit: above {GOOD_FIT}): H = "
            f"{hurst:.3g} and p_c are doubtful",
            TheoryWarning,
            stacklevel=user_level(),
        )


def _resolved_loads(
    p: np.ndarray, q: np.ndarray, c: np.ndarray, modulus: float, h_rms: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Persson's mean gap and stiffness at the loads ``p`` on the spectrum ``(q, c)``, and
    the loads where the theory does not underflow (its mean gap above ``SMALLEST_GAP
    h_rms``): ``ValueError`` when there are none, a :class:`TheoryWarning` when some are
    left out."""
    with np.errstate(all="ignore"):
        gap = np.atleast_1d(theory.persson_mean_gap(p, q, c, modulus))
        stiffness = np.atleast_1d(theory.persson_stiffness(p, q, c, modulus))
    valid = np.isfinite(gap) & np.isfinite(stiffness) & (gap > SMALLEST_GAP * h_rms)
    if not valid.any():
        raise ValueError(
            f"Persson's theory underflows at every load given (its mean gap below "
            f"{SMALLEST_GAP:g} h_rms: contact all but complete): give smaller loads"
        )
    if not valid.all():
        first = p[~valid][0]
        warnings.warn(
            f"Persson's mean gap falls below {SMALLEST_GAP:g} h_rms (contact all but complete) "
            f"from p0 = {first:.3g}: the {np.count_nonzero(~valid)} loads from there are left "
            "out, their values would be rounding",
            TheoryWarning,
            stacklevel=user_level(),
        )
    return gap, stiffness, valid


@keywords_after_first("length", "modulus", "pressures")
def predict_map(
    heights: Heights,
    *,
    length: float | tuple[float, float] | str | None = None,
    modulus: float | str = 1.0,
    pressures: float | Sequence[float] | None = None,
    channel: Channel = None,
    height_unit: str | None = None,
    override_metadata: bool = False,
    fill_undefined: str = "error",
    detrend: str = "none",
) -> Prediction:
    """Persson's theory (gap, stiffness, area) and the finite-size estimates for a whole map.

    The parameters after ``heights`` are keywords, named as
    :class:`~petsc_contact.workflows.description.Run`'s fields (given by position they still
    work until 0.3.0, with a ``DeprecationWarning``).  The map is prepared as a run prepares
    it (:func:`~petsc_contact.workflows.scene.measured`: filled, detrended, put in the unit of
    its sides, with the same warnings about its slope and edges); lengths of the prediction
    are in the unit of its sides, pressures in the modulus's.

    Parameters
    ----------
    heights
        The ``nx x ny`` map in any form (:func:`~petsc_contact.io.topography.as_topography`):
        an array, :func:`~petsc_contact.io.topography.read_topography`'s result, a
        SurfaceTopography ``Topography`` or a file's path.  A map with sides of its own gives
        them.
    length
        The sides (``L``, ``(Lx, Ly)`` or text with a unit, ``"100um"``); optional for a map
        with sides.
    modulus
        The contact modulus ``E*`` (``1e9``, or ``"1GPa"``); pressures are in its unit.
    pressures
        Nominal pressures for ``u_bar(p)``, ``K(p)`` and ``A(p)/A0`` (default: 25 from 1e-7
        to 1e-1 E*).
    channel, height_unit, override_metadata, fill_undefined, detrend
        The map's preparation, as :class:`~petsc_contact.workflows.description.Run`'s fields
        of those names.
    """
    from ..workflows.description import Run
    from ..workflows.scene import given_lengths, measured

    topo = as_topography(heights, channel)
    check_given(topo, length, fill_undefined, override_metadata)
    run = Run(
        heights=topo,
        length=length,
        modulus=modulus,
        height_unit=height_unit,
        override_metadata=override_metadata,
        fill_undefined=fill_undefined,
        detrend=detrend,
    )
    full, lengths, _, _ = measured(run, given_lengths(run), self_comm())
    grid = grid_for(full.shape, lengths.pair, self_comm())
    (lo, hi, n), modulus_value = DEFAULT_LOADS, run.modulus_value
    p = np.geomspace(lo * modulus_value, hi * modulus_value, n) if pressures is None else pressures
    loads = np.atleast_1d(np.asarray(p, dtype=float))
    return predict(grid, SerialFFT(grid), np.asarray(full, float), modulus_value, loads)
