"""Building blocks of the paper's figures (``examples/``): stiffness curves and spectra.

Each function is one step of a figure script: make the surface, sweep it with the exact
stiffness, compare with theory, save the numbers behind the plot.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..backend.stiffness import sweep_stiffness
from ..conventions.grid import Grid, fundamental_wavevector, self_comm
from ..devices.fft import make_fft
from ..io.atomic import atomic_h5
from ..io.names import is_partial
from ..io.partial import opened
from ..io.results import trusted
from ..io.schema import write_attributes
from ..physics import theory
from ..physics.observables import MIN_CONTACT_PIXELS, contact_resolved
from ..physics.surface import psd_shape, rms_of, self_affine
from ..workflows.periodic_sweep import periodic_contact
from ..workflows.punch_sweep import punch_contact

# a sweep's columns in the figures (contact_patches: NaN in files of versions before it)
_CURVE_KEYS = ("nominal_pressure", "mean_gap", "area_fraction", "stiffness", "contact_patches")


def surface(
    n: int,
    hurst: float,
    rolloff_ratio: float,
    cutoff_ratio: float,
    seed: int,
    rms_slope: float = 0.1,
    length: float = 1.0,
) -> tuple[np.ndarray, float]:
    """A full ``n x n`` self-affine surface (paper Eq. 5) and its realised ``h_rms``.

    Generated on one rank (``COMM_SELF``), so a figure script can run under any launcher.
    """
    grid = Grid(n, length, self_comm())
    fft = make_fft(grid)
    h = self_affine(
        grid,
        fft,
        hurst=hurst,
        rolloff_ratio=rolloff_ratio,
        cutoff_ratio=cutoff_ratio,
        seed=seed,
        rms_slope=rms_slope,
    )
    return h, rms_of(grid, fft, h)


def refined(heights: np.ndarray, factor: int) -> np.ndarray:
    """The same band-limited surface on a grid ``factor`` times finer: its spectrum padded
    with zeros (exact trigonometric interpolation; the heights at the old pixels kept), so
    that a grid refinement changes the discretisation and nothing of the surface."""
    n = heights.shape[0]
    m = n * factor
    spectrum = np.fft.fft2(heights)
    keep = np.r_[0 : n // 2, m - n // 2 : m]
    source = np.r_[0 : n // 2, n - n // 2 : n]
    padded = np.zeros((m, m), dtype=complex)
    padded[np.ix_(keep, keep)] = spectrum[np.ix_(source, source)]
    return np.real(np.fft.ifft2(padded)) * factor * factor


def stiffness_curve(
    heights: np.ndarray,
    pressures: Sequence[float],
    length: float = 1.0,
    modulus: float = 1.0,
    options: Sequence[str] | None = None,
) -> dict[str, np.ndarray]:
    """Periodic sweep with both stiffnesses: exact (contact set fixed) and ``-p dln p/du``.

    Steps that did not converge are ``nan`` (and counted in ``converged``).
    """
    steps = periodic_contact(
        heights,
        length=length,
        modulus=modulus,
        pressures=pressures,
        options=options,
        stiffness=True,
    )
    ok = np.array([s.converged for s in steps])
    col = {k: np.array([s.scalars[k] for s in steps], dtype=float) for k in _CURVE_KEYS}
    for k in _CURVE_KEYS[1:]:
        col[k][~ok] = np.nan
    col["converged"] = ok
    return with_sweep_stiffness(col)


def with_sweep_stiffness(col: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Add ``stiffness_sweep``, ``-dp/du_bar`` along the sweep (``nan`` where not converged)."""
    ok = col["converged"].astype(bool)
    good = ok & np.isfinite(col["mean_gap"])
    col["stiffness_sweep"] = np.full(ok.size, np.nan)
    if good.sum() >= 3:
        col["stiffness_sweep"][good] = sweep_stiffness(
            col["nominal_pressure"][good], col["mean_gap"][good]
        )
    return col


def resolved(area_fraction: np.ndarray, n: int) -> np.ndarray:
    """:func:`contact_resolved` on an ``n x n`` map with the study's :data:`MIN_CONTACT_PIXELS`."""
    return contact_resolved(area_fraction, n * n)


def ensemble_curves(
    n: int,
    hurst: float,
    rolloff_ratio: float,
    cutoff_ratio: float,
    seeds: Sequence[int],
    pressures: Sequence[float],
    rms_slope: float = 0.1,
    options: Sequence[str] | None = None,
    points: int = 4,
    min_contact_pixels: int = MIN_CONTACT_PIXELS,
    progress: bool = True,
) -> dict[str, Any]:
    """Stiffness curves of several seeds, their mean, and power-law fits of the lowest points
    (:func:`finite_size_fit`).

    Returns arrays ``seeds x pressures`` (``mean_gap``, ``stiffness``, ...), the realised
    ``h_rms`` and the ``seed`` of each surface, with the fit's entries.
    """
    rows, h_rms = [], []
    for seed in seeds:
        h, rms = surface(n, hurst, rolloff_ratio, cutoff_ratio, seed, rms_slope)
        rows.append(stiffness_curve(h, pressures, options=options))
        h_rms.append(rms)
        if progress:
            print(
                f"#   H = {hurst}, L/lambda_r = {rolloff_ratio}, L/lambda_1 = {cutoff_ratio}, "
                f"seed {seed}: {int(rows[-1]['converged'].sum())}/{len(pressures)} converged",
                flush=True,
            )
    out: dict[str, Any] = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    out["h_rms"], out["seed"] = np.array(h_rms), np.array(seeds)
    p_c = crossover(out["h_rms"], hurst, rolloff_ratio)
    return out | finite_size_fit(out, n * n, p_c, points, min_contact_pixels)


def crossover(h_rms: np.ndarray, hurst: float, rolloff_ratio: float) -> float:
    """The seeds' mean ``p_c`` (paper Eq. 13 in the recipe of the paper's quoted values,
    ``convention="paper"`` of :func:`~petsc_contact.physics.theory.crossover_pressure`, with
    each seed's realised ``h_rms``) for ``E* = L = 1``."""
    return float(
        np.mean(
            [
                theory.crossover_pressure(1.0, h, hurst, 1.0, rolloff_ratio, convention="paper")
                for h in h_rms
            ]
        )
    )


def finite_size_fit(
    curves: dict[str, Any],
    points_per_map: int,
    crossover: float,
    fit_points: int = 4,
    min_contact_pixels: int = MIN_CONTACT_PIXELS,
) -> dict[str, Any]:
    """``alpha`` of ``K ~ p^alpha`` from the lowest ``fit_points`` resolved loads below the
    crossover.

    ``curves`` holds ``nominal_pressure`` (per load, or seeds x loads), ``area_fraction`` and
    ``stiffness`` (seeds x loads).  A load is resolved when every seed has at least
    ``min_contact_pixels`` contact pixels (:func:`contact_resolved`); the fit takes the lowest
    ``fit_points`` resolved loads below ``crossover``, or, when fewer lie there, the lowest
    ``fit_points`` resolved ones (``below_crossover`` counts those under it).  Returns
    ``alpha`` (fit of the seed-averaged ``K``), ``alpha_error`` (its standard error combined
    with the standard error of the per-seed fits), ``alphas``, ``prefactor``,
    ``stiffness_mean``, ``fitted`` (the loads used), ``resolved`` and ``alpha_interval``,
    the 68% percentile interval of ``alpha`` over the seeds resampled with replacement
    (:func:`seed_bootstrap`; with four seeds a coarse one, 35 distinct resamples).
    """
    from .fits import ensemble_statistics, power_law_alphas, power_law_fit

    p = np.asarray(curves["nominal_pressure"], dtype=float)
    p = p[0] if p.ndim == 2 else p
    stiffness = np.asarray(curves["stiffness"], dtype=float)
    mean_k = ensemble_statistics(stiffness)["mean"]
    ok = np.all(contact_resolved(curves["area_fraction"], points_per_map, min_contact_pixels), 0)
    ok &= np.all(np.isfinite(stiffness), axis=0)
    below = ok & (p < crossover)
    window = below if np.count_nonzero(below) >= fit_points else ok
    fitted = np.zeros_like(ok)
    fitted[np.flatnonzero(window)[:fit_points]] = True
    fit = power_law_fit(p[fitted], mean_k[fitted], fit_points)
    alphas = np.array([power_law_fit(p[fitted], k[fitted], fit_points).alpha for k in stiffness])
    spread = alphas.std(ddof=1) / np.sqrt(alphas.size) if alphas.size > 1 else 0.0

    def alphas_of(rows: np.ndarray) -> np.ndarray:  # resamples x seeds: their mean's alpha
        k = ensemble_statistics(stiffness[rows.T])["mean"]
        return power_law_alphas(p[fitted], k[:, fitted], fit_points)

    return {
        "stiffness_mean": mean_k,
        "resolved": ok,
        "fitted": fitted,
        "below_crossover": int(np.count_nonzero(fitted & (p < crossover))),
        "crossover": crossover,
        "alpha": fit.alpha,
        "alphas": alphas,
        "alpha_error": float(np.hypot(np.nan_to_num(fit.alpha_error), spread)),
        "alpha_interval": seed_bootstrap(len(stiffness), alphas_of, batched=True),
        "prefactor": fit.prefactor,
    }


BOOTSTRAP_RESAMPLES = 4000
BOOTSTRAP_SEED = 20261126  # a fixed stream: the same interval from the same files


def seed_resamples(seeds: int) -> np.ndarray:
    """:func:`seed_bootstrap`'s resamples of ``seeds`` rows with replacement: an array
    :data:`BOOTSTRAP_RESAMPLES` x ``seeds`` of row indices, drawn one resample at a time
    from the fixed stream :data:`BOOTSTRAP_SEED`."""
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    return np.array([rng.integers(0, seeds, seeds) for _ in range(BOOTSTRAP_RESAMPLES)])


def seed_bootstrap(
    seeds: int, statistic: Callable[[np.ndarray], Any], level: float = 0.68, batched: bool = False
) -> np.ndarray:
    """The ``level`` percentile interval of ``statistic(rows)`` over :data:`BOOTSTRAP_RESAMPLES`
    resamples of the ``seeds`` rows with replacement (Efron's percentile bootstrap,
    :func:`seed_resamples`); ``[nan, nan]`` for one seed. ``batched``: ``statistic`` takes
    every resample at once (an array resamples x seeds) and returns one value per resample."""
    if seeds < 2:
        return np.full(2, np.nan)
    rows = seed_resamples(seeds)
    values = statistic(rows) if batched else [statistic(row) for row in rows]
    tail = 50 * (1 - level)
    return np.percentile(values, [tail, 100 - tail])


SAME_LOAD = 1e-12  # loads equal to this: one sweep (numpy 1 and 2 round geomspace apart)


def curves_from_files(paths: Sequence[str]) -> dict[str, Any]:
    """A study's periodic sweeps of several seeds (``petsc-contact study`` files) as the
    arrays of :func:`ensemble_curves` (steps that did not converge are ``nan``), with each
    file's ``seed``.  An unfinished piece's ``.partial`` file is read as far as it goes, and
    then every file only over the loads they all have; files that do not sweep the same loads
    (complete ones of different lengths, or values apart by more than :data:`SAME_LOAD`
    relative) are a ``ValueError``."""
    rows: list[dict[str, np.ndarray]] = []
    h_rms, seeds = [], []
    for path in paths:
        with opened(path, locking=False) as f:  # a .partial may be committed meanwhile
            if not (f.attrs.get("complete", False) or is_partial(path)):
                raise ValueError(f"'{path}' is not complete")
            ok = trusted(f)
            row = {k: f[k][:].astype(float) for k in _CURVE_KEYS if k in f}
            if "contact_patches" not in f:  # files of versions before the count
                row["contact_patches"] = np.full(ok.size, np.nan)
            row["contact_patches"][row["contact_patches"] < 0] = np.nan
            for k in _CURVE_KEYS[1:]:
                row[k][~ok] = np.nan
            rows.append(row | {"converged": ok})
            h_rms.append(float(f.attrs["rms_height"]))
            seeds.append(int(f.attrs["seed"]))
    shared = min(r["converged"].size for r in rows)
    complete_sizes = {
        r["converged"].size for r, path in zip(rows, paths, strict=True) if not is_partial(path)
    }
    loads = np.array([r["nominal_pressure"][:shared] for r in rows])
    same = np.allclose(loads, loads[0], rtol=SAME_LOAD, atol=0)
    if len(complete_sizes) > 1 or not same:
        raise ValueError(f"the files {list(paths)} do not sweep the same loads")
    out: dict[str, Any] = {k: np.array([r[k][:shared] for r in rows]) for k in rows[0]}
    out["h_rms"], out["seed"] = np.array(h_rms), np.array(seeds)
    return out


def punch_curve(
    heights: np.ndarray, approaches: Sequence[float], length: float = 1.0, modulus: float = 1.0
) -> dict[str, np.ndarray]:
    """Rigid rough punch: force, ``F/Lp^2`` and the interfacial stiffness (Eq. 2) per step."""
    steps = punch_contact(heights, length=length, modulus=modulus, approaches=approaches)
    keys = (
        "approach force nominal_pressure area_fraction total_stiffness interfacial_stiffness"
    ).split()
    col = {k: np.array([s.scalars[k] for s in steps], dtype=float) for k in keys}
    col["converged"] = np.array([s.converged for s in steps])
    return col


def ideal_spectrum(
    length: float,
    hurst: float,
    rolloff_ratio: float,
    cutoff_ratio: float,
    h_rms: float | None = None,
    points: int = 4000,
    *,
    rms_slope: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Paper Eq. 5 on a fine log grid from ``q0`` to ``q1``: the continuous spectrum Persson
    theory needs.

    Parameters
    ----------
    h_rms, rms_slope
        Exactly one: ``C0`` such that ``h_rms^2 = 2 pi int q C dq``, or such that
        ``h'_rms^2 = 2 pi int q^3 C dq``.  A surface generated for an rms slope
        (:func:`surface`, the paper's surfaces) was drawn from the spectrum of that slope:
        give ``rms_slope``.  Its realised ``h_rms`` differs from the spectrum's by the
        scatter of its few lowest modes (1.2 times the expectation for the study's
        ``L = lambda_r``, H = 0.7, seed 1), so ``C`` normalised to it lies above the
        prescribed one at every ``q`` by that factor squared.
    """
    if h_rms is not None and rms_slope is None:
        moment, target = 1, h_rms
    elif rms_slope is not None and h_rms is None:
        moment, target = 3, rms_slope
    else:
        raise ValueError("give exactly one of h_rms and rms_slope")
    q0 = fundamental_wavevector(length)
    q = np.geomspace(q0, cutoff_ratio * q0, points)
    c = psd_shape(q, q0, rolloff_ratio * q0, cutoff_ratio * q0 * (1 + 1e-12), hurst)
    return q, c * target**2 / (2 * np.pi * np.trapezoid(q**moment * c, q))


def save(path: str, data: dict[str, Any], **attributes: Any) -> None:
    """Write a figure's numbers: nested dicts become groups, arrays datasets, rest attrs."""

    def put(group: Any, items: dict[str, Any]) -> None:
        for key, value in items.items():
            if isinstance(value, dict):
                put(group.create_group(key), value)
            else:
                group[key] = np.asarray(value)

    with atomic_h5(path) as f:
        put(f, data)
        write_attributes(f, attributes)


def linear_width(p: np.ndarray, ratio: np.ndarray, tolerance: float) -> tuple[float, float, float]:
    """The widest run of consecutive loads over which ``K/p`` stays within ``1 +- tolerance``
    of its geometric middle (``max/min <= (1 + tol)/(1 - tol)``): its width in decades of
    load and its first and last load (0 and NaN without two such loads)."""
    good = np.isfinite(ratio) & (ratio > 0)
    best = (0.0, float("nan"), float("nan"))
    limit = (1 + tolerance) / (1 - tolerance)
    for i in np.flatnonzero(good):
        for j in range(i + 1, p.size):
            if not good[j]:
                break
            window = ratio[i : j + 1]
            if window.max() / window.min() > limit:
                break
            width = float(np.log10(p[j] / p[i]))
            if width > best[0]:
                best = (width, float(p[i]), float(p[j]))
    return best


def log_interp(x: np.ndarray, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """``ys(xs)`` at ``x``, interpolated linearly in ``ln x`` and ``ln y`` over the finite
    positive points, taken in order of ``xs``; ``nan`` outside their range."""
    ok = np.isfinite(xs) & np.isfinite(ys) & (xs > 0) & (ys > 0)
    if ok.sum() < 2:
        return np.full(np.shape(x), np.nan)
    order = np.argsort(xs[ok])
    lx, lxs = np.log(np.asarray(x, dtype=float)), np.log(xs[ok][order])
    return np.exp(np.interp(lx, lxs, np.log(ys[ok][order]), left=np.nan, right=np.nan))


def kept_seed(path: str, settings: np.ndarray, holds: str) -> dict[str, np.ndarray] | None:
    """The arrays a figure script kept for one seed in ``path`` (an ``.npz`` with the
    ``settings`` they were computed for), or ``None`` where there is no such file.

    Raises
    ------
    ValueError
        One line, naming ``path``, when it cannot be read or holds another run's ``holds``
        (its settings differ): the script refuses it rather than tabulate other numbers.
    """
    if not os.path.exists(path):
        return None
    try:
        with np.load(path) as kept:
            arrays = dict(kept)
    except (OSError, ValueError, EOFError) as exc:
        raise ValueError(f"{path} is damaged ({exc}): remove it to solve that seed again") from None
    if "settings" not in arrays or not np.array_equal(arrays["settings"], settings):
        raise ValueError(f"{path} holds another run's {holds}: remove it or give another --output")
    return arrays
