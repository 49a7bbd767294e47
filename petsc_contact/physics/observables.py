"""What one converged (or not) load step measures: pure numpy on distributed fields.

Contact rule: a pixel is in contact when ``p > k g``, with ``k`` the diagonal of the
stiffness operator (the pressure a pixel's own unit gap would produce).  It is the
projection of the natural residual ``min(k g, p)``: on an exact solution it picks exactly
the pixels with ``g = 0`` and ``p > 0``; near one it decides by which of ``k g`` and ``p``
is smaller, never by a tolerance on the gap alone.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..conventions.grid import Grid


def contact_mask(gap: np.ndarray, pressure: np.ndarray, pixel_stiffness: float) -> np.ndarray:
    """Pixels in contact: ``p > k g`` (see module docstring)."""
    return pressure > pixel_stiffness * gap


def natural_residual(gap: np.ndarray, pressure: np.ndarray, pixel_stiffness: float) -> np.ndarray:
    """``min(k g, p)``: zero exactly where ``g >= 0, p >= 0, g p = 0`` (pressure units)."""
    return np.minimum(pixel_stiffness * gap, pressure)


def contact_patches(grid: Grid, contact: np.ndarray, periodic: bool = True) -> int:
    """Number of contact patches: clusters of contact pixels joined through their edges
    (4-connected), across the cell's edges when ``periodic`` (same on every rank).

    Each rank labels its row slab and sends its boundary rows and columns; rank 0 joins
    the labels that touch across slabs (and across the periodic edges).
    """
    from scipy import ndimage

    labels, count = ndimage.label(contact)
    ends = (labels[:1], labels[-1:], labels[:, :1].T, labels[:, -1:].T)
    gathered = grid.comm.gather((count, ends), root=0)
    total = 0
    if gathered is not None:
        slabs = [(n, e) for n, e in gathered if e[0].size]  # ranks with rows
        offsets = np.cumsum([0] + [n for n, _ in slabs])
        rows = [
            [np.where(a > 0, a + o, 0) for a in e]
            for (_, e), o in zip(slabs, offsets[:-1], strict=True)
        ]
        touching = [(rows[i][1], rows[i + 1][0]) for i in range(len(rows) - 1)]
        if periodic:
            touching += [(rows[-1][1], rows[0][0])] + [(r[2], r[3]) for r in rows]
        total = int(offsets[-1]) - _joined(touching)
    return int(grid.comm.bcast(total, root=0))


def _joined(touching: list[tuple[np.ndarray, np.ndarray]]) -> int:
    """How many labels disappear when the labels facing each other in ``touching`` (pairs
    of equal-shape arrays, 0 for no contact) are merged."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    pairs = [np.stack([a.ravel(), b.ravel()], 1) for a, b in touching]
    edges = np.concatenate(pairs).reshape(-1, 2) if pairs else np.empty((0, 2), dtype=int)
    edges = edges[(edges > 0).all(axis=1)]
    nodes, index = np.unique(edges, return_inverse=True)
    index = index.reshape(-1, 2)
    graph = coo_matrix((np.ones(len(index)), (index[:, 0], index[:, 1])), (nodes.size,) * 2)
    return int(nodes.size - connected_components(graph, directed=False)[0])


def step_observables(
    grid: Grid,
    gap: np.ndarray,
    pressure: np.ndarray,
    heights: np.ndarray,
    nominal_pressure: float,
    pixel_stiffness: float,
) -> dict[str, Any]:
    """Scalars of one load step (same on every rank).

    Returns
    -------
    dict
        ``mean_gap``; ``area_fraction``; ``contact_patches``; ``contact_pressure_mean``
        (mean of the pressure on contact pixels, zero elsewhere: force balance says it
        equals ``p0``);
        ``elastic_energy`` per apparent area, ``1/2 mean((g + h)(p - p0))``;
        ``max_pressure``; ``min_gap``; ``min_pressure`` (over all pixels; negative values
        are tension); ``complementarity`` ``sum(p+ g) / (sum(p+) h_rms)`` as Tamaas reports
        it; ``kkt_residual`` ``rms(min(k g, p)) / p0``; ``contact``, the local boolean
        contact mask (not a scalar: callers pop it).
    """
    contact = contact_mask(gap, pressure, pixel_stiffness)
    p_plus = np.maximum(pressure, 0.0)
    p_contact = np.where(contact, p_plus, 0.0)
    r = natural_residual(gap, pressure, pixel_stiffness)
    sums = grid.sum(
        gap.sum(),
        np.count_nonzero(contact),
        p_contact.sum(),
        np.vdot(gap + heights, pressure - nominal_pressure),
        np.vdot(p_plus, gap),
        p_plus.sum(),
        np.vdot(r, r),
        np.vdot(heights, heights),
    )
    g_sum, n_contact, pc_sum, work, pg, p_sum, r2, h2 = sums
    n = grid.size
    h_rms = np.sqrt(h2 / n)
    return {
        "mean_gap": g_sum / n,
        "area_fraction": n_contact / n,
        "contact_patches": contact_patches(grid, contact),
        "contact_pressure_mean": pc_sum / n,
        "elastic_energy": 0.5 * work / n,
        "max_pressure": grid.max(float(p_contact.max(initial=0.0))),
        "min_gap": grid.min(float(gap.min())),
        "min_pressure": grid.min(float(pressure.min())),
        "complementarity": pg / (p_sum * h_rms) if p_sum > 0 and h_rms > 0 else 0.0,
        "kkt_residual": np.sqrt(r2 / n) / nominal_pressure,
        "contact": contact,
    }
