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
  from 1e-3..1 usually means mistaken units.
"""

from __future__ import annotations

import numpy as np

DETREND_MODES = ("none", "height", "slope", "curvature")
FILL_MODES = ("error", "mean", "harmonic")
SLOPE_RANGE = (1e-3, 1.0)  # rms slopes outside this usually mean wrong units
EDGE_MISMATCH_LIMIT = 5.0  # edge step over typical neighbour step that draws a warning
_CHUNK = 512  # rows per pass of the detrending sums (bounds the memory at large maps)


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


def rms_slope(heights: np.ndarray, spacing: tuple[float, float]) -> float:
    """The rms slope from forward differences inside the map (its edges not wrapped)."""
    return slope_rms(*slope_squares(heights, spacing), heights.shape)


def slope_squares(
    rows: np.ndarray, spacing: tuple[float, float], below: np.ndarray | None = None
) -> tuple[float, float]:
    """The sums of the squared forward-difference slopes inside ``rows`` along ``x`` and
    ``y``; with ``below`` (the row after the last) the ``x`` slopes down to it too: a slab's
    share of :func:`rms_slope`."""
    sx = np.diff(rows, axis=0) / spacing[0]
    sy = np.diff(rows, axis=1) / spacing[1]
    along_x = float(np.sum(sx**2))
    if below is not None and len(rows):
        along_x += float(np.sum(((below - rows[-1]) / spacing[0]) ** 2))
    return along_x, float(np.sum(sy**2))


def slope_rms(along_x: float, along_y: float, shape: tuple[int, ...]) -> float:
    """The rms slope of a map of ``shape`` from its :func:`slope_squares` sums."""
    nx, ny = shape[0], shape[1]
    return float(np.sqrt(along_x / ((nx - 1) * ny) + along_y / (nx * (ny - 1))))


def edge_mismatch(heights: np.ndarray) -> float:
    """The step at the periodic seam over the typical neighbour step, the larger of the two
    axes: about 1 for a periodic map, large for a map whose opposite edges differ."""
    ratios = []
    for axis in (0, 1):
        h = np.moveaxis(np.asarray(heights, dtype=float), axis, 0)
        inside = np.sqrt(np.mean(np.diff(h, axis=0) ** 2))
        seam = np.sqrt(np.mean((h[0] - h[-1]) ** 2))
        ratios.append(seam / inside if inside > 0 else (0.0 if seam == 0 else np.inf))
    return float(max(ratios))
