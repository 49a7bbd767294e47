"""Self-affine random surfaces with a roll-off (paper Eq. 5) and their statistics.

Conventions (docs/formulation.md): for the DFT ``H(q) = sum_x h(x) exp(-i q.x)``,
``C(q) = (ax ay)^2 |H(q)|^2 / ((2 pi)^2 A0)`` so that
``h_rms^2 = sum_q C(q) (2 pi)^2/(Lx Ly)``, the discrete form of ``integral d^2q C(q)``.
On a rectangle the ratios ``L/lambda_r`` and ``L/lambda_1`` refer to the longer side
``L = max(Lx, Ly)``, whose wavevector ``q0 = 2 pi/L`` is the spectrum's smallest.

Generation is Fourier filtering of Gaussian white noise: the DFT of real white noise has
Hermitian symmetry, complex Gaussian coefficients (Gaussian real and imaginary parts, uniform
phases), and it is multiplied by ``sqrt(C(q))``.  The white noise of row ``i`` is drawn from
``numpy.random.default_rng([seed, i])``, so a seed gives the same surface for any number of
MPI ranks and on any machine with the same numpy stream.
"""

from __future__ import annotations

import numpy as np

from ..conventions.grid import Grid
from ..conventions.validation import non_negative
from ..devices.fft import FFT, half_spectrum_weights, wavevector_magnitude


def psd_shape(q: np.ndarray, q0: float, qr: float, q1: float, hurst: float) -> np.ndarray:
    """``C(q)/C0`` of paper Eq. (5).

    ``0`` for ``q < q0``; ``1`` for ``q0 <= q < qr``; ``(q/qr)^(-2-2H)`` for ``qr <= q < q1``;
    ``0`` for ``q >= q1``.
    """
    q = np.asarray(q, dtype=float)
    with np.errstate(divide="ignore"):
        tail = (np.maximum(q, qr) / qr) ** (-2.0 - 2.0 * hurst)
    shape = np.where(q < qr, 1.0, tail)
    return np.where((q >= q0 * (1 - 1e-12)) & (q < q1), shape, 0.0)


def nyquist_ratio(grid: Grid) -> float:
    """The largest ``L/lambda_1`` the grid resolves: ``lambda_1`` two of its longer pixel sides
    (``n/2`` on a square grid)."""
    return max(grid.lengths) / (2 * max(grid.spacing))


def check_spectrum_parameters(
    nyquist: float, hurst: float, rolloff_ratio: float, cutoff_ratio: float
) -> None:
    """Raise ``ValueError`` with a one-line reason for an impossible spectrum (``nyquist`` is
    :func:`nyquist_ratio`)."""
    if not 0.0 <= hurst <= 1.0:
        raise ValueError(f"Hurst exponent must be in [0, 1], got {hurst}")
    if not 1.0 <= rolloff_ratio <= cutoff_ratio:
        raise ValueError(
            "need 1 <= L/lambda_r <= L/lambda_1, got "
            f"L/lambda_r = {rolloff_ratio}, L/lambda_1 = {cutoff_ratio}"
        )
    if cutoff_ratio > nyquist * (1 + 1e-12):
        raise ValueError(f"L/lambda_1 = {cutoff_ratio} exceeds the Nyquist limit {nyquist:g}")


def white_noise(grid: Grid, seed: int) -> np.ndarray:
    """Unit-variance Gaussian white noise on this rank's rows, independent of the rank count."""
    noise = np.empty(grid.local_shape)  # each row drawn in place: no row's copy left behind
    for row, i in zip(noise, range(grid.rows.start, grid.rows.stop), strict=True):
        np.random.default_rng([seed, i]).standard_normal(out=row)
    return noise


def spectrum_sums(grid: Grid, fft: FFT, shape: np.ndarray) -> tuple[float, float]:
    """``(sum C, sum q^2 C) (2 pi)^2/(Lx Ly)`` over the full spectrum for a half-spectrum
    ``C``."""
    w = half_spectrum_weights(grid, fft) * shape
    q2 = wavevector_magnitude(grid, fft) ** 2
    dq2 = grid.dq[0] * grid.dq[1]
    s0, s2 = grid.sum(w.sum(), (w * q2).sum())
    return s0 * dq2, s2 * dq2


LARGEST_TARGET = 1e100


def self_affine(
    grid: Grid,
    fft: FFT,
    *,
    hurst: float,
    rolloff_ratio: float,
    cutoff_ratio: float,
    seed: int,
    rms_height: float | None = None,
    rms_slope: float | None = None,
    exact: bool = False,
) -> np.ndarray:
    """A seeded self-affine surface with roll-off, this rank's row slab.

    Parameters
    ----------
    grid, fft
        The grid and its FFT.
    hurst
        Hurst exponent ``H``.
    rolloff_ratio, cutoff_ratio
        ``L/lambda_r`` and ``L/lambda_1`` (paper Eq. 5).
    seed
        Random seed (any non-negative integer).
    rms_height, rms_slope
        Exactly one target: ``C0`` is chosen so that the *expected* ``h_rms^2`` (or
        ``h'_rms^2 = integral q^2 C d^2q``) of the discrete spectrum equals the target.
    exact
        Rescale the realisation so that the realised value equals the target exactly.

    Returns
    -------
    numpy.ndarray
        Heights, mean zero, shape ``grid.local_shape``.
    """
    check_spectrum_parameters(nyquist_ratio(grid), hurst, rolloff_ratio, cutoff_ratio)
    target, slope = _rms_target(rms_height, rms_slope)
    q0 = grid.q0
    shape = psd_shape(
        wavevector_magnitude(grid, fft), q0, q0 * rolloff_ratio, q0 * cutoff_ratio, hurst
    )
    s0, s2 = spectrum_sums(grid, fft, shape)
    c0 = target**2 / (s2 if slope else s0)
    device = fft.device  # the noise is drawn on the host: the same surface on every device
    fft.real[...] = device.asarray(white_noise(grid, seed))
    fft.forward()
    fft.spectrum *= device.asarray(
        np.sqrt(c0 * shape * grid.dq[0] * grid.dq[1] * grid.size) / grid.size
    )
    fft.backward()
    h = np.array(device.to_host(fft.result))
    if exact and target > 0:
        realised = rms_of(grid, fft, h, slope=slope)
        h *= target / realised
    return h


def _rms_target(rms_height: float | None, rms_slope: float | None) -> tuple[float, bool]:
    """The one rms target given, and whether it is the slope's (``ValueError`` unless exactly
    one is given, not negative and not too large)."""
    if rms_height is not None and rms_slope is None:
        target, slope = non_negative("rms target", rms_height), False
    elif rms_slope is not None and rms_height is None:
        target, slope = non_negative("rms target", rms_slope), True
    else:
        raise ValueError("give exactly one of rms_height and rms_slope")
    if target > LARGEST_TARGET:  # its square, the spectrum's scale, would overflow
        raise ValueError(f"rms target {target:g} is too large (at most {LARGEST_TARGET:g})")
    return target, slope


def fourier_power(grid: Grid, fft: FFT, h: np.ndarray) -> np.ndarray:
    """``C(q)`` of a realisation on the local half-spectrum block (docs/formulation.md)."""
    fft.real[...] = h
    fft.forward()
    return np.abs(fft.spectrum) ** 2 * grid.pixel_area**2 / ((2 * np.pi) ** 2 * grid.area)


def rms_of(grid: Grid, fft: FFT, h: np.ndarray, slope: bool = False) -> float:
    """Realised rms height, or rms slope from the spectrum (exact spectral derivative)."""
    if not slope:
        return grid.rms(h - grid.mean(h))
    return float(np.sqrt(spectrum_sums(grid, fft, fourier_power(grid, fft, h))[1]))


def radial_psd(
    grid: Grid, fft: FFT, h: np.ndarray, bins: int | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Radially averaged PSD of a realisation.

    One ``q`` grid for squares, rectangles and oblong pixels: bins of the coarser of the two
    lattice spacings ``max(2 pi/Lx, 2 pi/Ly)``, so that every bin holds wavevectors of every
    direction (finer bins on a rectangle hold the long side's modes only, every other bin,
    and the averages split into two branches), up to the smaller of the two Nyquist
    wavevectors ``pi/max(ax, ay)`` (beyond it a bin holds only the directions of the finer
    axis: the spectrum turns up there).

    Parameters
    ----------
    bins
        Number of logarithmic bins between ``q0`` and that Nyquist wavevector; ``None``
        gives linear bins of the lattice's coarser spacing ``dq``, centred on ``k dq``.

    Returns
    -------
    q, C
        Mean ``|q|`` and mean ``C(q)`` of the non-empty bins (same on every rank).
    """
    c = fourier_power(grid, fft, h)
    q = wavevector_magnitude(grid, fft)
    w = half_spectrum_weights(grid, fft) * np.where(q > 0, 1.0, 0.0)
    dq = max(grid.dq)
    qmax = np.pi / max(grid.spacing)
    if bins is None:
        index = np.rint(q / dq).astype(int)
        nbins = int(np.floor(qmax / dq + 0.5)) + 1
    else:
        edges = np.geomspace(grid.q0 * 0.999, qmax * 1.001, bins + 1)
        index = np.searchsorted(edges, q) - 1
        nbins = bins + 1
    w = np.where(q <= qmax * (1 + 1e-12), w, 0.0)  # only the disc every direction fills
    index = np.clip(index, 0, nbins - 1)
    stats = [
        np.bincount(index.ravel(), weights=(w * x).ravel(), minlength=nbins)
        for x in (np.ones_like(q), q, c)
    ]
    count, qsum, csum = grid.sum(*np.concatenate(stats)).reshape(3, nbins)
    keep = (count > 0) & (qsum > 0)
    return qsum[keep] / count[keep], csum[keep] / count[keep]
