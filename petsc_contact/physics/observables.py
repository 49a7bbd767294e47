"""What one converged (or not) load step measures, on distributed fields of any device.

Written once against the device's array module (NumPy on the ``cpu`` device, CuPy on a GPU):
the fields stay where they are, and only scalars, histograms and the contact patches' sizes
and edge labels come to the host (:class:`~petsc_contact.devices.device.Device`).

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
from ..devices.device import CPU, Device

MIN_CONTACT_PIXELS = 16


def contact_resolved(
    area_fraction: Any, points_per_map: int, min_contact_pixels: int = MIN_CONTACT_PIXELS
) -> np.ndarray:
    """Steps whose contact is resolved: at least ``min_contact_pixels``
    (:data:`MIN_CONTACT_PIXELS`) of the map's ``points_per_map`` pixels in contact (a step
    records it as ``contact_resolved``).

    A contact of a few pixels does not resolve its own stiffness: the flat punch's grid
    stiffness converges like ``1/n`` (docs/figures.md), so a spot a few pixels wide is off by
    tens of percent, and a single asperity of 16 pixels (radius about 2.3 pixels) already by
    a few.  Unresolved steps are drawn apart in the figures and never fitted.
    """
    pixels = np.rint(np.asarray(area_fraction, dtype=float) * points_per_map)  # its count
    return pixels >= min_contact_pixels


def contact_mask(gap: np.ndarray, pressure: np.ndarray, pixel_stiffness: float) -> np.ndarray:
    """Pixels in contact: ``p > k g`` (see module docstring)."""
    return pressure > pixel_stiffness * gap


def natural_residual(
    gap: np.ndarray, pressure: np.ndarray, pixel_stiffness: float, device: Device = CPU
) -> np.ndarray:
    """``min(k g, p)``: zero exactly where ``g >= 0, p >= 0, g p = 0`` (pressure units)."""
    return device.xp.minimum(pixel_stiffness * gap, pressure)


def contact_patches(
    grid: Grid, contact: np.ndarray, periodic: bool = True, device: Device = CPU
) -> int:
    """Number of contact patches: clusters of contact pixels joined through their edges
    (4-connected), across the cell's edges when ``periodic`` (same on every rank)."""
    return int(patch_sizes(grid, contact, periodic, device).size)


def patch_sizes(
    grid: Grid, contact: np.ndarray, periodic: bool = True, device: Device = CPU
) -> np.ndarray:
    """The size (pixels) of every contact patch (see :func:`contact_patches`), on every rank,
    on the host.

    Each rank labels its row slab (on its device, :meth:`~petsc_contact.devices.device.
    Device.label`) and sends its boundary rows and columns and its labels' sizes; rank 0
    joins the labels that touch across slabs (and across the periodic edges) and adds up the
    sizes of each joined patch.  Only those edges and sizes leave the device.
    """
    labels, count = device.label(contact)
    sizes = device.to_host(device.xp.bincount(labels.ravel(), minlength=count + 1)[1:])
    ends = tuple(
        device.to_host(e) for e in (labels[:1], labels[-1:], labels[:, :1].T, labels[:, -1:].T)
    )
    gathered = grid.comm.gather((count, ends, sizes), root=0)
    total = np.zeros(0, dtype=np.int64)
    if gathered is not None:
        slabs = [(n, e, z) for n, e, z in gathered if e[0].size]  # ranks with rows
        offsets = np.cumsum([0] + [n for n, _, _ in slabs])
        rows = [
            [np.where(a > 0, a + o, 0) for a in e]
            for (_, e, _), o in zip(slabs, offsets[:-1], strict=True)
        ]
        touching = [(rows[i][1], rows[i + 1][0]) for i in range(len(rows) - 1)]
        if periodic:
            touching += [(rows[-1][1], rows[0][0])] + [(r[2], r[3]) for r in rows]
        every = np.concatenate([z for _, _, z in slabs]) if slabs else total
        total = _joined_sizes(touching, every)
    return np.asarray(grid.comm.bcast(total, root=0))


BLOCK_POINTS = 1 << 20
"""The points of the row blocks the observables are reduced over: their temporaries are a
block's (8 MiB a float field), not a field's, so that they add nothing to a run's peak."""


def row_blocks(shape: tuple[int, ...]) -> list[slice]:
    """Blocks of whole rows of a slab of ``shape`` of about :data:`BLOCK_POINTS` points each
    (none for an empty slab)."""
    rows = max(1, BLOCK_POINTS // max(shape[1], 1))
    return [slice(i, i + rows) for i in range(0, shape[0], rows)]


def _larger(a: float, b: float) -> float:
    """The larger of two numbers, NaN if either is (as ``np.maximum``)."""
    return float(np.maximum(a, b))


PRESSURE_BINS = 40  # equal bins from zero to the largest contact pressure
GAP_BINS = 40  # equal bins from zero to the largest gap


def distributions(
    grid: Grid,
    gap: np.ndarray,
    pressure: np.ndarray,
    contact: np.ndarray,
    sizes: np.ndarray,
    inside: np.ndarray | None = None,
    filled: np.ndarray | None = None,
    device: Device = CPU,
) -> dict[str, Any]:
    """How one step's pressure, gap and contact patches are distributed (same on every rank).

    Parameters
    ----------
    gap, pressure, contact
        This rank's slabs (the contact mask as the step decided it).
    sizes
        Every contact patch's size in pixels (:func:`patch_sizes`).
    inside
        The pixels that count (the punch's footprint); default every pixel.
    filled
        The pixels whose heights were filled (``--fill-undefined``), if any.
    device
        Where the fields (and ``inside``, ``filled``) live; the results are on the host.

    Returns
    -------
    dict
        ``pressure_histogram`` (contact pixels per bin) on ``pressure_bins`` (edges from 0 to
        the largest contact pressure); ``gap_histogram`` (open pixels per bin) on
        ``gap_bins``; ``patch_size_histogram`` (patches per bin of sizes 1, 2-3, 4-7, ...
        pixels: bins of powers of two up to the grid's size); ``largest_patch`` (pixels) and
        ``largest_patch_fraction`` (of the pixels that count); with ``filled``,
        ``filled_contact_fraction`` (of the contact pixels) and ``filled_load_fraction`` (of
        the force) on filled pixels.
    """
    xp = device.xp
    inside = xp.ones(contact.shape, bool) if inside is None else inside
    pixels = int(grid.sum(xp.count_nonzero(inside))[0])
    s_edges = 2.0 ** np.arange(int(np.ceil(np.log2(max(grid.size, 2)))) + 2)
    out: dict[str, Any] = {
        **_histograms(grid, gap, pressure, contact, inside, device),
        "patch_size_histogram": np.histogram(sizes, s_edges)[0].astype(np.int64),
        "largest_patch": int(sizes.max(initial=0)),
        "largest_patch_fraction": float(sizes.max(initial=0)) / pixels,
    }
    if filled is not None:
        out |= _on_filled(grid, pressure, contact, filled, device)
    return out


def largest(values: Any) -> float:
    """This rank's largest entry of a field, and zero if that is larger or it is empty (NaN
    if it holds one, as NumPy's ``max(initial=0.0)``, which CuPy does not have)."""
    return float(np.maximum(float(values.max()), 0.0)) if values.size else 0.0


def _histograms(
    grid: Grid,
    gap: np.ndarray,
    pressure: np.ndarray,
    contact: np.ndarray,
    inside: np.ndarray,
    device: Device,
) -> dict[str, Any]:
    """The contact pixels' pressures and the open pixels' gaps (of those ``inside``), in
    equal bins from zero to the largest (same on every rank), a row block at a time."""
    xp = device.xp

    def chosen(rows: slice) -> tuple[Any, Any]:  # the block's contact pressures, open gaps
        in_contact = contact[rows]
        return pressure[rows][in_contact], gap[rows][inside[rows] & ~in_contact]

    p_top = g_top = 0.0
    blocks = row_blocks(gap.shape)
    for rows in blocks:
        p, g = chosen(rows)
        p_top, g_top = _larger(p_top, largest(p)), _larger(g_top, largest(g))
    p_top, g_top = grid.max(p_top), grid.max(g_top)
    p_range = (0.0, p_top if p_top > 0 else 1.0)
    g_range = (0.0, g_top if g_top > 0 else 1.0)
    # equal bins given by their number and range: numpy's fast path (edges need a search);
    # each value's bin does not depend on the others, so the blocks' counts add up
    none = xp.empty(0)
    p_hist, p_edges = xp.histogram(none, PRESSURE_BINS, p_range)
    g_hist, g_edges = xp.histogram(none, GAP_BINS, g_range)
    for rows in blocks:
        p, g = chosen(rows)
        p_hist += xp.histogram(p, PRESSURE_BINS, p_range)[0]
        g_hist += xp.histogram(g, GAP_BINS, g_range)[0]
    counts = grid.sum(*device.to_host(p_hist), *device.to_host(g_hist)).astype(np.int64)
    return {
        "pressure_histogram": counts[:PRESSURE_BINS],
        "pressure_bins": device.to_host(p_edges),
        "gap_histogram": counts[PRESSURE_BINS:],
        "gap_bins": device.to_host(g_edges),
    }


def _on_filled(
    grid: Grid, pressure: np.ndarray, contact: np.ndarray, filled: np.ndarray, device: Device
) -> dict[str, float]:
    """The fractions of the contact pixels and of the force on ``filled`` pixels."""
    xp = device.xp
    n_contact, on_filled, load, load_filled = grid.sum(
        xp.count_nonzero(contact),
        xp.count_nonzero(contact & filled),
        xp.where(contact, pressure, 0.0).sum(),
        xp.where(contact & filled, pressure, 0.0).sum(),
    )
    return {
        "filled_contact_fraction": on_filled / n_contact if n_contact else 0.0,
        "filled_load_fraction": load_filled / load if load > 0 else 0.0,
    }


def _joined_sizes(touching: list[tuple[np.ndarray, np.ndarray]], sizes: np.ndarray) -> np.ndarray:
    """The sizes of the patches left when the labels facing each other in ``touching`` (0 for
    no contact) are merged; ``sizes[k]`` is the size of label ``k + 1``."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = sizes.size
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    pairs = [np.stack([a.ravel(), b.ravel()], 1) for a, b in touching]
    edges = np.concatenate(pairs).reshape(-1, 2) if pairs else np.empty((0, 2), dtype=int)
    edges = edges[(edges > 0).all(axis=1)] - 1
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), (n, n))
    _, component = connected_components(graph, directed=False)
    return np.bincount(component, weights=sizes).astype(np.int64)


def _block_sums(
    gap: Any,
    pressure: Any,
    contact: Any,
    heights: Any,
    nominal_pressure: float,
    pixel_stiffness: float,
    device: Device,
) -> tuple[Any, ...]:
    """This rank's sums of :func:`step_observables`, a block of rows at a time (the
    temporaries a block's): the contact pressure's sum and largest entry, ``(g + h).(p -
    p0)``, ``p+.g``, ``sum(p+)`` and the natural residual's ``r.r``."""
    xp = device.xp
    pc_sum: Any = 0.0
    pc_largest = work = pg = p_sum = r2 = pc_sum
    for rows in row_blocks(gap.shape):
        g, p = gap[rows], pressure[rows]
        p_plus = xp.maximum(p, 0.0)
        p_contact = xp.where(contact[rows], p_plus, 0.0)
        pc_sum += p_contact.sum()
        pc_largest = _larger(pc_largest, largest(p_contact))
        pg += xp.vdot(p_plus, g)
        p_sum += p_plus.sum()
        r = natural_residual(g, p, pixel_stiffness, device)
        r2 += xp.vdot(r, r)
        work += xp.vdot(g + heights[rows], p - nominal_pressure)
    return pc_sum, pc_largest, work, pg, p_sum, r2


def step_observables(
    grid: Grid,
    gap: np.ndarray,
    pressure: np.ndarray,
    heights: np.ndarray,
    nominal_pressure: float,
    pixel_stiffness: float,
    filled: np.ndarray | None = None,
    device: Device = CPU,
) -> dict[str, Any]:
    """Scalars (and :func:`distributions`) of one load step (same on every rank), from the
    fields of ``device`` (``filled`` too), with only scalars and histograms brought to the host.

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
        contact mask on the device (not a scalar: callers pop it).
    """
    xp = device.xp
    contact = contact_mask(gap, pressure, pixel_stiffness)
    sizes = patch_sizes(grid, contact, device=device)
    pc_sum, pc_largest, work, pg, p_sum, r2 = _block_sums(
        gap, pressure, contact, heights, nominal_pressure, pixel_stiffness, device
    )
    sums = grid.sum(
        gap.sum(), xp.count_nonzero(contact), pc_sum, work, pg, p_sum, r2, xp.vdot(heights, heights)
    )
    g_sum, n_contact, pc_sum, work, pg, p_sum, r2, h2 = sums
    n = grid.size
    h_rms = np.sqrt(h2 / n)
    return {
        "mean_gap": g_sum / n,
        "area_fraction": n_contact / n,
        "contact_resolved": bool(contact_resolved(n_contact / n, n)),
        "contact_patches": sizes.size,
        "contact_pressure_mean": pc_sum / n,
        "elastic_energy": 0.5 * work / n,
        "max_pressure": grid.max(pc_largest),
        "min_gap": grid.min(float(gap.min())),
        "min_pressure": grid.min(float(pressure.min())),
        "complementarity": pg / (p_sum * h_rms) if p_sum > 0 and h_rms > 0 else 0.0,
        "kkt_residual": np.sqrt(r2 / n) / nominal_pressure,
        **distributions(grid, gap, pressure, contact, sizes, filled=filled, device=device),
        "contact": contact,
    }
