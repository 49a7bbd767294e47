"""Preparing a measured height map for contact: missing data, detrending and plausibility.

Pure numpy on the whole map (the rank that reads it holds it before the grid's slabs are sent):

- :func:`fill_undefined` replaces NaN heights (``mean``, or ``harmonic``: the solution of
  Laplace's equation on the missing pixels with the measured ones around them as boundary
  values, the smoothest surface that agrees with the data);
- :func:`detrend` removes the least-squares mean (``height``), plane (``slope``) or
  quadratic (``curvature``) in physical coordinates, as a measured map's tilt and the
  instrument's bow are not part of the roughness;
- :func:`edge_mismatch` and :func:`rms_slope` are the checks behind the warnings: a map that
  is not periodic has a step at its edges when treated as periodic, and an rms slope far
  from 1e-3..1 usually means mistaken units.  They take the map where it lives, NumPy's or
  CuPy's (a GPU run checks it on the device), from the sums of :func:`step_squares`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

DETREND_MODES = ("none", "height", "slope", "curvature")
FILL_MODES = ("error", "mean", "harmonic")
SLOPE_RANGE = (1e-3, 1.0)  # rms slopes outside this usually mean wrong units
EDGE_MISMATCH_LIMIT = 5.0  # edge step over typical neighbour step that draws a warning
_CHUNK = 512  # rows per pass of the detrending and step sums (bounds the memory at large maps)


def fill_undefined(heights: np.ndarray, mode: str = "error") -> np.ndarray:
    """A map with its undefined (NaN or infinite) heights filled.

    Parameters
    ----------
    heights
        The ``nx x ny`` map, NaN where the instrument recorded nothing.
    mode
        ``error`` (``ValueError`` naming the count), ``mean`` (the mean of the defined
        heights) or ``harmonic`` (the discrete Laplace equation on the missing points, the
        measured ones around them fixed: a plane is reproduced exactly; module docstring).

    Returns
    -------
    numpy.ndarray
        A filled copy, or ``heights`` itself when nothing is undefined.
    """
    if mode not in FILL_MODES:
        raise ValueError(f"fill mode must be one of {', '.join(FILL_MODES)}, got '{mode}'")
    missing = ~np.isfinite(heights)
    count = int(np.count_nonzero(missing))
    if count == 0:
        return heights
    if count == heights.size:
        raise ValueError("every height is undefined (NaN)")
    if mode == "error":
        raise ValueError(
            f"{count} heights are undefined (NaN or inf); choose --fill-undefined mean or harmonic"
        )
    filled = np.array(heights, dtype=float)
    if mode == "mean":
        filled[missing] = filled[~missing].mean()
    else:
        filled[missing] = _harmonic(filled, missing)
    return filled


def _harmonic(h: np.ndarray, missing: np.ndarray) -> np.ndarray:
    """Values on ``missing`` solving the discrete Laplace equation with the rest fixed."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.linalg import spsolve

    index = -np.ones(h.shape, dtype=np.int64)
    rows, cols = np.nonzero(missing)
    index[rows, cols] = np.arange(rows.size)
    entries_i, entries_j, values = [], [], []
    degree = np.zeros(rows.size)
    rhs = np.zeros(rows.size)
    for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        ni, nj = rows + di, cols + dj
        inside = (ni >= 0) & (ni < h.shape[0]) & (nj >= 0) & (nj < h.shape[1])
        me, ni, nj = np.flatnonzero(inside), ni[inside], nj[inside]
        degree[me] += 1
        other = index[ni, nj]
        unknown = other >= 0
        entries_i.append(me[unknown])
        entries_j.append(other[unknown])
        values.append(-np.ones(np.count_nonzero(unknown)))
        np.add.at(rhs, me[~unknown], h[ni[~unknown], nj[~unknown]])
    n = rows.size
    i = np.concatenate([np.arange(n), *entries_i])
    j = np.concatenate([np.arange(n), *entries_j])
    a = coo_matrix((np.concatenate([degree, *values]), (i, j)), shape=(n, n)).tocsr()
    return np.asarray(spsolve(a, rhs))


def _basis(mode: str, x: np.ndarray, y: np.ndarray) -> list[np.ndarray]:
    one = np.ones_like(x * y)
    if mode == "height":
        return [one]
    if mode == "slope":
        return [one, x * one, y * one]
    return [one, x * one, y * one, x * x * one, x * y, y * y * one]


def detrend(heights: np.ndarray, spacing: tuple[float, float], mode: str = "slope") -> np.ndarray:
    """A map minus its least-squares polynomial.

    Parameters
    ----------
    heights
        The ``nx x ny`` map (no undefined points: fill them first).
    spacing
        The pixel size ``(Lx/nx, Ly/ny)``: coordinates are physical and centred on the map,
        so the fit does not depend on the pixel aspect ratio.
    mode
        ``none``, ``height`` (the mean), ``slope`` (a plane) or ``curvature`` (a quadratic).

    Returns
    -------
    numpy.ndarray
        A new array (``heights`` itself for ``none``).
    """
    if mode not in DETREND_MODES:
        raise ValueError(f"detrend mode must be one of {', '.join(DETREND_MODES)}, got '{mode}'")
    if mode == "none":
        return heights
    nx, ny = heights.shape
    y = (np.arange(ny) - (ny - 1) / 2) * spacing[1]
    k = len(_basis(mode, np.zeros(1), np.zeros(1)))
    normal, moment = np.zeros((k, k)), np.zeros(k)
    for start in range(0, nx, _CHUNK):  # normal equations, a block of rows at a time
        x = (np.arange(start, min(start + _CHUNK, nx)) - (nx - 1) / 2)[:, None] * spacing[0]
        b = np.array([f.ravel() for f in _basis(mode, x, y[None, :])])
        normal += b @ b.T
        moment += b @ np.asarray(heights[start : start + _CHUNK], dtype=float).ravel()
    coefficients = np.linalg.solve(normal, moment)
    out = np.array(heights, dtype=float)
    for start in range(0, nx, _CHUNK):
        x = (np.arange(start, min(start + _CHUNK, nx)) - (nx - 1) / 2)[:, None] * spacing[0]
        basis = _basis(mode, x, y[None, :])
        out[start : start + _CHUNK] -= sum(c * f for c, f in zip(coefficients, basis, strict=True))
    return out


def rms_slope(
    heights: Any, spacing: tuple[float, float], steps: tuple[float, float] | None = None
) -> float:
    """The rms slope from forward differences inside the map (its edges not wrapped);
    ``steps``: the map's :func:`step_squares` where already summed."""
    return slope_rms(*slope_squares(heights, spacing, steps=steps), heights.shape)


def slope_squares(
    rows: Any,
    spacing: tuple[float, float],
    below: Any = None,
    steps: tuple[float, float] | None = None,
) -> tuple[float, float]:
    """The sums of the squared forward-difference slopes inside ``rows`` along ``x`` and
    ``y``; with ``below`` (the row after the last) the ``x`` slopes down to it too: a slab's
    share of :func:`rms_slope` (from ``steps``, the :func:`step_squares`, where given)."""
    along_x, along_y = step_squares(rows, below) if steps is None else steps
    return along_x / spacing[0] ** 2, along_y / spacing[1] ** 2


def step_squares(rows: Any, below: Any = None) -> tuple[float, float]:
    """The sums of the squared steps between neighbours inside ``rows`` along ``x`` and
    ``y`` (and from the last row down to ``below``, where given): :data:`_CHUNK` rows at a
    time (each with the next block's first row), so that the temporaries stay small;
    ``rows`` of any array module (NumPy's or CuPy's: the map is checked where it lives)."""
    along_x = along_y = 0.0
    count = len(rows)
    for start in range(0, count, _CHUNK):
        block = rows[start : min(start + _CHUNK + 1, count)].astype(float, copy=False)
        step = block[1:] - block[:-1]
        along_x += float((step * step).sum())
        own = block[: min(_CHUNK, count - start)]
        step = own[:, 1:] - own[:, :-1]
        along_y += float((step * step).sum())
    if below is not None and count:
        step = below - rows[-1].astype(float, copy=False)
        along_x += float((step * step).sum())
    return along_x, along_y


def slope_rms(along_x: float, along_y: float, shape: tuple[int, ...]) -> float:
    """The rms slope of a map of ``shape`` from its :func:`slope_squares` sums."""
    nx, ny = shape[0], shape[1]
    return float(np.sqrt(along_x / ((nx - 1) * ny) + along_y / (nx * (ny - 1))))


def edge_mismatch(heights: Any, steps: tuple[float, float] | None = None) -> float:
    """The step at the periodic seam over the typical neighbour step, the larger of the two
    axes: about 1 for a periodic map, large for a map whose opposite edges differ.
    ``steps``: the map's :func:`step_squares` where already summed; ``heights`` of any
    array module."""
    nx, ny = heights.shape
    along_x, along_y = step_squares(heights) if steps is None else steps
    ratios = []
    for inside_sum, inside_count, seam in (
        (along_x, (nx - 1) * ny, heights[0].astype(float, copy=False) - heights[-1]),
        (along_y, nx * (ny - 1), heights[:, 0].astype(float, copy=False) - heights[:, -1]),
    ):
        inside = np.sqrt(inside_sum / inside_count) if inside_count else 0.0
        seam_rms = np.sqrt(float((seam * seam).mean()))
        ratios.append(seam_rms / inside if inside > 0 else (0.0 if seam_rms == 0 else np.inf))
    return float(max(ratios))
