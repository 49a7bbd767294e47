"""Ensembles over surface realisations and power-law fits of K(p) (pure numpy on results).

:func:`~petsc_contact.io.results.ensemble_statistics` reduces per-seed sweeps (arrays
``seeds x steps``) to mean, standard deviation and standard error; :func:`power_law_fit`
fits ``K = c p^alpha`` to the lowest points of a stiffness curve, as the paper does with four
points (Figs. 3-4).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..io.results import ensemble_statistics as ensemble_statistics  # importable here too


@dataclass
class PowerLaw:
    """``K = prefactor * p^alpha`` fitted in log-log; ``alpha_error`` is one standard error."""

    alpha: float
    alpha_error: float
    prefactor: float
    points: int


def power_law_fit(pressure: np.ndarray, stiffness: np.ndarray, points: int = 4) -> PowerLaw:
    """Least-squares line through ``(ln p, ln K)`` of the ``points`` lowest pressures.

    The standard error of the slope is ``s / sqrt(sum (x - x_mean)^2)`` with ``s^2`` the
    residual variance over ``points - 2`` degrees of freedom (0 for an exact power law;
    ``nan`` with two points, where it cannot be estimated).
    """
    p = np.asarray(pressure, dtype=float)
    k = np.asarray(stiffness, dtype=float)
    keep = np.isfinite(p) & np.isfinite(k) & (p > 0) & (k > 0)
    p, k = p[keep], k[keep]
    if p.size < points or points < 2:
        raise ValueError(f"need at least {max(points, 2)} positive finite points, got {p.size}")
    order = np.argsort(p)[:points]
    x, y = np.log(p[order]), np.log(k[order])
    xm = x - x.mean()
    slope = float(_slopes(x, y))
    intercept = float(y.mean() - slope * x.mean())
    if points > 2:
        resid = y - (intercept + slope * x)
        error = float(np.sqrt(np.dot(resid, resid) / (points - 2) / np.dot(xm, xm)))
    else:
        error = float("nan")
    return PowerLaw(slope, error, float(np.exp(intercept)), points)


def power_law_alphas(pressure: np.ndarray, stiffness: np.ndarray, points: int = 4) -> np.ndarray:
    """:func:`power_law_fit`'s ``alpha`` of each row of ``stiffness`` (rows x pressures) at
    the same ``pressure``, all rows at once where every value is positive and finite (the
    fits then take the same points), else row by row."""
    p = np.asarray(pressure, dtype=float)
    k = np.atleast_2d(np.asarray(stiffness, dtype=float))
    usable = np.isfinite(p).all() and (p > 0).all() and np.isfinite(k).all() and (k > 0).all()
    if not usable or p.size < points or points < 2:  # as power_law_fit takes (or refuses) them
        return np.array([power_law_fit(p, row, points).alpha for row in k])
    order = np.argsort(p)[:points]
    return _slopes(np.log(p[order]), np.log(k[:, order]))


def _slopes(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The least-squares slope of ``y`` on ``x`` along ``y``'s last axis (one per row)."""
    xm = x - x.mean()
    return np.asarray((y - y.mean(axis=-1, keepdims=True)) @ xm / np.dot(xm, xm))
