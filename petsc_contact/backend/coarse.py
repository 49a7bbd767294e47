"""A coarse space for the contact reactions: the two-level form of the Schur preconditioner.

The exact Schur form (:mod:`petsc_contact.numerics.schur`) solves for one reaction per contact
pixel.  Here the reactions are restricted to piecewise constants on *aggregates*: the contact
pixels of each ``b x b`` block of pixels, ``lambda = W a`` with ``W`` the aggregates'
indicator columns.  With ``G`` the Fourier compliance (``q = 0`` entry zero), the
preconditioner is

    z = G (r + W a) + c,     [ E     W^T 1 ] [a]   [ -W^T (G r)_B ]
                             [ 1^T W   0   ] [c] = [ -sum(r)      ],     E = W^T G_BB W,

the exact minimiser of ``1/2 z^T K z - r^T z`` on ``{W^T z_B = 0}``: symmetric and positive
semi-definite for *any* aggregate set, so a coarse space built on an older contact set is
less accurate, never wrong (docs/solvers.md).  Its cost is two FFT round trips per
application, a ``k x k`` Cholesky factorisation per build and two triangular solves per
application (``k`` aggregates).

``E`` comes from one column of ``G`` (the kernel is periodic and even, :func:`schur.quarter`;
on several ranks each rank makes the entries from its own rows of it, :func:`coarse_matrix`,
and its own contact pixels and those of the block rows near its own,
:func:`distributed_aggregates`):
exactly between aggregates of neighbouring blocks (pixel pair by pixel pair where the blocks
hold few contact pixels, by FFTs on ``2b x 2b`` cells where they hold many,
:func:`coarse_matrix`); as the
monopole ``|A_I| |A_J| G(c_I - c_J)`` of the aggregates' centroids (``G`` interpolated
bilinearly) between all others, where the neighbour blocks in between make the pixels at
least ``b`` apart.  The monopoles' error is about 1% of ``E`` (relative eigenvalues of 0.99
to 1.01 on a 256^2 contact); an ``E`` below the exact one in any direction makes the
preconditioner indefinite, so the diagonal is raised by :data:`DIAGONAL_INFLATION`.  At
2048^2 and ``p0 = 1e-3 E*`` (paper bandwidth) the CG stopped on a non-positive ``r.z``
without it, took 45 iterations with 0.02, and 29-31 with anything from 0.1 to 0.5.  With
``b = 1`` every aggregate is a pixel, the monopoles are exact, nothing is raised, and the
form is the exact Schur form.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType
from typing import Any

import numpy as np
import scipy.fft

from ..conventions.grid import Grid, block_rows
from ..devices.device import CPU, Device
from ..numerics.aggregates import (
    centroids,
    grouped,
    half_spectrum_weights,
    monopoles,
    monopoles_array,
    near_pairs,
    near_pairs_array,
    offset_kernels,
    pair_sums_cells,
    pair_sums_direct,
    spectral_dots,
)
from ..numerics.schur import BorderedSystem, allgather, held_rows, sum_over_ranks
from ..solver.driver import SolveSettings
from .operator import ShellInterface

DIAGONAL_INFLATION = 0.2  # relative: keeps E above the exact one (monopole error ~1%; measured)
NEAR_REACH = 1  # blocks this far apart (Chebyshev, in blocks) are summed pixel pair by pair
BLOCK = 16  # the aggregates' block side (pixels)
MAX_FRACTION = 0.1  # the largest contact fraction the two-level form is used at (measured)
FFT_PRODUCTS = 8  # per b^2 and near pair: the FFT pair sums' cost in direct products (measured)


@dataclass(frozen=True)
class TwoLevelOptions:
    """Whether and how the two-level form is used (``-petsc_contact_two_level*`` options).

    Attributes
    ----------
    enabled
        ``-petsc_contact_two_level`` (default true; ``0`` or ``false``: never).
    block
        ``-petsc_contact_two_level_block``: the aggregates' block side in pixels.
    max_fraction
        ``-petsc_contact_two_level_max_fraction``: the largest fraction of the grid in contact
        at which it is used.  Above 10% it takes fewer iterations but pays in time only where
        the held compliance alone is slow (docs/solvers.md).
    """

    enabled: bool = True
    block: int = BLOCK
    max_fraction: float = MAX_FRACTION

    @classmethod
    def from_settings(cls, settings: SolveSettings) -> TwoLevelOptions:
        """The options a solve's ``settings`` give (the defaults where they are unset)."""
        return cls(
            enabled=settings.two_level,
            block=settings.block or BLOCK,
            max_fraction=MAX_FRACTION if settings.max_fraction is None else settings.max_fraction,
        )

    def covers(self, bound_count: int, size: int) -> bool:
        """Whether the form is used for ``bound_count`` contact pixels of ``size``."""
        return self.enabled and bound_count <= self.max_fraction * size


AGGREGATES_PER_BATCH = 128  # the FFT pair sums transform this many aggregates at a time


def _pair_sums_fft(
    rows: np.ndarray,
    cols: np.ndarray,
    starts: np.ndarray,
    origin: np.ndarray,
    pairs: np.ndarray,
    quarter: np.ndarray,
    shape: tuple[int, int],
    block: int,
) -> np.ndarray:
    """The sums of :func:`~petsc_contact.numerics.aggregates.pair_sums_direct` by FFTs on
    ``2b x 2b`` cells.

    With ``u``, ``v`` the pixels' positions in their blocks (``origin``: each aggregate's
    block corner), a pair's sum is ``sum_{u,v} A(u) B(v) T(u - v)``, ``T(w) = G(o_I - o_J + w)``
    for ``|w| < b``: a circular correlation on a ``2b x 2b`` cell, where the offsets do not
    alias, so ``(1/M^2) Re sum_k conj(A^(k)) T^(k) B^(k)`` (``M = 2b``; half spectra, each
    column but the first and the Nyquist one counted twice).  Its cost per pair is about
    ``2 b^2`` products against ``|A_I| |A_J|``: it pays where the blocks are well filled.
    The aggregates are transformed in batches of :data:`AGGREGATES_PER_BATCH` (with the
    partners of their pairs), so the memory stays small.
    """
    nx, ny = shape
    m = 2 * block
    offsets = origin[pairs[:, 0]] - origin[pairs[:, 1]]
    keys, kind = np.unique(
        np.stack([offsets[:, 0] % nx, offsets[:, 1] % ny], axis=1), axis=0, return_inverse=True
    )
    kernels = offset_kernels(np, scipy.fft.rfft2, keys, quarter, shape, block)
    weight = half_spectrum_weights(np, m)
    out = np.empty(len(pairs))
    order = np.argsort(pairs[:, 0], kind="stable")
    first = pairs[order, 0]
    for low in range(0, starts.size - 1, AGGREGATES_PER_BATCH):
        lo, hi = np.searchsorted(first, [low, low + AGGREGATES_PER_BATCH])
        if lo == hi:
            continue
        chosen = order[lo:hi]
        members, index = np.unique(pairs[chosen].ravel(), return_inverse=True)
        cells = np.zeros((len(members), m, m))
        for i, a in enumerate(members):
            s, e = starts[a], starts[a + 1]
            cells[i, rows[s:e] - origin[a, 0], cols[s:e] - origin[a, 1]] = 1.0
        spectra = scipy.fft.rfft2(cells)
        spectral_dots(spectra, kernels, index.reshape(-1, 2), kind[chosen], weight, out, chosen)
    return out


def coarse_matrix(parts: Aggregates, quarter: np.ndarray, grid: Grid) -> np.ndarray:
    """``E = W^T G_BB W`` for the aggregates ``parts``: exact between blocks at most
    :data:`NEAR_REACH` blocks apart, monopoles beyond; only the upper triangle is filled, in
    Fortran order (factorised in place, :meth:`~petsc_contact.devices.device.Device.cho_factor`).

    The near sums are taken pixel pair by pixel pair where the aggregates are small and by
    FFTs on ``2b x 2b`` cells where they are large (:func:`_pair_sums_fft`), whichever
    costs fewer products (``|A_I| |A_J|`` against :data:`FFT_PRODUCTS` ``b^2`` per pair).
    On several ranks (``quarter``: this rank's rows, :func:`~petsc_contact.numerics.schur.quarter`)
    each rank makes the monopoles whose folded row offset it holds and the near pairs
    ``(I, J)``, ``I <= J``, of the aggregates ``I`` it owns (``parts.owned``), and the ranks'
    matrices are summed (each entry made on one rank).
    """
    nx, ny = shape = grid.shape
    held, comm, block = held_rows(grid), grid.comm, parts.block
    e_mat = monopoles(parts.sizes, parts.centre, quarter, nx, ny, held.start, held.stop)
    block_rc, lookup = block_lookup(np, parts.ids, shape, block)
    pairs = near_pairs(block_rc, lookup, NEAR_REACH)
    direct = float(np.dot(parts.sizes[pairs[:, 0]], parts.sizes[pairs[:, 1]]))
    near = near_corner(quarter, grid, (NEAR_REACH + 1) * block)
    mine = pairs[slice(*np.searchsorted(pairs[:, 0], [parts.owned.start, parts.owned.stop]))]
    rows, cols, starts = parts.rows, parts.cols, parts.starts
    if direct > FFT_PRODUCTS * block**2 * len(pairs):
        sums = _pair_sums_fft(rows, cols, starts, block_rc * block, mine, near, shape, block)
    else:
        sums = pair_sums_direct(rows, cols, starts, mine, near, nx, ny)
    if comm.size > 1:  # the near pairs' monopoles, made where their rows are held
        e_mat[pairs[:, 0], pairs[:, 1]] = 0.0
    e_mat[mine[:, 0], mine[:, 1]] = sums
    return sum_over_ranks(e_mat, comm)


def near_corner(quarter: np.ndarray, grid: Grid, reach: int) -> np.ndarray:
    """The corner ``[:reach, :reach]`` of ``G``'s quarter (the offsets of near pairs, at most
    ``reach - 1``), contiguous and whole on every rank: gathered from the ranks holding its
    rows (``quarter``: this rank's, :func:`~petsc_contact.numerics.schur.quarter`)."""
    if grid.comm.size == 1:
        return np.ascontiguousarray(quarter[:reach, :reach])
    held = held_rows(grid)
    mine = np.ascontiguousarray(quarter[: max(0, min(held.stop, reach) - held.start), :reach])
    corner = np.empty((min(reach, grid.shape[0] // 2 + 1), mine.shape[1]))
    grid.comm.Allgatherv(mine, [corner, grid.comm.allgather(mine.size)])
    return corner


@dataclass(frozen=True)
class CoarseMatrix:
    """The aggregates of a bound set and their coarse matrix, before its factorisation.

    Attributes
    ----------
    local
        This rank's bound pixels (flat local indices), on the device.
    labels
        Each of them its aggregate, on the device.
    block
        The block side used.
    sizes
        The pixels of each aggregate (floats): on the host from :func:`host_coarse_matrix`,
        on the device from :func:`array_coarse_matrix`.
    matrix
        ``E`` (:func:`coarse_matrix`), the diagonal raised (upper triangle only, in Fortran
        order, on the host; full and symmetric on the device).
    """

    local: Any
    labels: Any
    block: int
    sizes: Any
    matrix: Any


def aggregate(
    xp: ModuleType, rows: Any, cols: Any, shape: tuple[int, int], block: int, max_size: int
) -> tuple[int, Any, Any, Any]:
    """The aggregates of the pixels ``(rows, cols)`` (global indices, arrays of ``xp``): the
    block side ``b >= block`` grown until at most ``max_size`` blocks hold pixels; returns
    ``b``, each pixel's aggregate, the blocks that hold pixels (flat block indices, in order:
    aggregate ``I`` is block ``ids[I]``) and the pixels of every block."""
    nx, ny = shape
    while True:
        bx, by = -(-nx // block), -(-ny // block)
        block_id = block_of(rows, cols, ny, block)
        counts = xp.bincount(block_id, minlength=bx * by)
        ids = xp.flatnonzero(counts)
        if ids.size <= max_size:
            break
        block = grown(block, int(ids.size), max_size)
    return block, (xp.cumsum(counts > 0) - 1)[block_id], ids, counts


def block_of(rows: Any, cols: Any, ny: int, block: int) -> Any:
    """The flat index of the block of side ``block`` holding each pixel ``(rows, cols)``."""
    return (rows // block) * -(-ny // block) + cols // block


def grown(block: int, count: int, max_size: int) -> int:
    """The next block side tried where ``block`` leaves ``count > max_size`` blocks holding
    pixels: scaled by ``sqrt(count / max_size)``, at least one more."""
    return max(block + 1, int(np.ceil(block * np.sqrt(count / max_size))))


def block_lookup(xp: ModuleType, ids: Any, shape: tuple[int, int], block: int) -> tuple[Any, Any]:
    """Each aggregate's block ``(bi, bj)`` and the aggregate of each block (``-1``: none)."""
    bx, by = (-(-n // block) for n in shape)
    block_rc = xp.stack([ids // by, ids % by], axis=1)
    lookup = xp.full((bx, by), -1, dtype=np.int64)
    lookup[block_rc[:, 0], block_rc[:, 1]] = xp.arange(ids.size)
    return block_rc, lookup


def _raise_diagonal(xp: ModuleType, matrix: Any, block: int) -> None:
    """Raise ``E``'s diagonal by :data:`DIAGONAL_INFLATION` (not for single pixels, where the
    monopoles are exact)."""
    if block > 1:
        d = xp.arange(matrix.shape[0])
        matrix[d, d] *= 1.0 + DIAGONAL_INFLATION


@dataclass(frozen=True)
class Aggregates:
    """The aggregates of a bound set as one rank holds them: every aggregate's block, size and
    centroid (``k`` of each, ``k`` at most the coarse space's cap), and the pixels of those
    whose near pairs it sums.

    Attributes
    ----------
    block
        The block side ``b``.
    ids
        Each aggregate's block (flat block indices, :func:`block_of`), in order.
    sizes
        Each aggregate's pixel count (floats).
    centre
        Each aggregate's centroid (``k x 2``, :func:`~petsc_contact.numerics.aggregates.centroids`).
    rows, cols
        The bound pixels this rank holds (global indices), grouped by aggregate, each
        aggregate's in the order of their flat global indices.
    starts
        Aggregate ``I`` holds the pixels ``starts[I]:starts[I+1]`` of them (none where this
        rank does not hold its pixels).
    owned
        The aggregates whose near pairs this rank sums (all of them on one rank).
    """

    block: int
    ids: np.ndarray
    sizes: np.ndarray
    centre: np.ndarray
    rows: np.ndarray
    cols: np.ndarray
    starts: np.ndarray
    owned: range


def whole_aggregates(
    rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int], block: int, max_size: int
) -> tuple[Aggregates, np.ndarray]:
    """The aggregates of the bound pixels ``(rows, cols)``, all of them on one rank
    (:func:`aggregate`), and each pixel's aggregate."""
    block, labels, ids, counts = aggregate(np, rows, cols, shape, block, max_size)
    starts = np.concatenate([[0], np.cumsum(counts[ids])]).astype(np.int64)
    order = grouped(labels, starts)
    rows, cols = rows[order], cols[order]
    sizes = counts[ids].astype(float)
    centre = centroids(rows, cols, starts)
    return Aggregates(block, ids, sizes, centre, rows, cols, starts, range(len(ids))), labels


def distributed_aggregates(
    grid: Grid, rows: np.ndarray, cols: np.ndarray, block: int, max_size: int
) -> tuple[Aggregates, np.ndarray]:
    """The aggregates of every rank's bound pixels (this rank's: ``(rows, cols)``, global
    indices) and the aggregate of each of this rank's, on several ranks, with no rank holding
    them all: :func:`whole_aggregates`' blocks, numbering, sizes and centroids.

    Each rank owns the block rows whose first pixel row is in its slab
    (:func:`_owned_bands`) and the aggregates in them, receives the bound pixels of the
    block rows within :data:`NEAR_REACH` of those (:func:`_halo`: those of its near pairs),
    and makes its aggregates' sizes and centroids; the blocks, sizes and centroids are
    gathered on every rank (``k`` of each, bounded by ``max_size``).  The block side grows as
    in :func:`aggregate`, from the count of aggregates summed over the ranks.
    """
    comm, ny = grid.comm, grid.shape[1]
    while True:
        near = _halo(grid, rows, cols, block)
        mine = _owned_blocks(near, grid.rows, ny, block)
        count = comm.allreduce(mine.size)
        if count <= max_size:
            break
        block = grown(block, count, max_size)
    pieces = comm.allgather(mine)
    first = sum(len(p) for p in pieces[: comm.rank])
    ids = np.concatenate(pieces)
    labels = np.searchsorted(ids, block_of(near[:, 0], near[:, 1], ny, block))
    starts = np.concatenate([[0], np.cumsum(np.bincount(labels, minlength=ids.size))])
    starts = starts.astype(np.int64)
    order = grouped(labels, starts)
    near_rows, near_cols = near[order, 0], near[order, 1]  # contiguous copies
    owned = range(first, first + mine.size)
    bounds = starts[owned.start : owned.stop + 1]
    made = allgather(
        np.column_stack([np.diff(bounds), centroids(near_rows, near_cols, bounds)]), comm
    )
    sizes, centre = np.ascontiguousarray(made[:, 0]), np.ascontiguousarray(made[:, 1:])
    parts = Aggregates(block, ids, sizes, centre, near_rows, near_cols, starts, owned)
    return parts, np.searchsorted(ids, block_of(rows, cols, ny, block))


def _owned_bands(slab: slice, block: int) -> range:
    """The block rows (of side ``block``) whose first pixel row is in the rows ``slab``."""
    return range(-(-slab.start // block), -(-slab.stop // block))


def _owned_blocks(pixels: np.ndarray, slab: slice, ny: int, block: int) -> np.ndarray:
    """The blocks holding the pixels ``pixels`` (``(row, col)`` pairs) in the block rows owned
    by the slab ``slab`` (:func:`_owned_bands`): flat block indices, in order."""
    bands = _owned_bands(slab, block)
    on = (pixels[:, 0] >= bands.start * block) & (pixels[:, 0] < bands.stop * block)
    return np.unique(block_of(pixels[on, 0], pixels[on, 1], ny, block))


def _near_bands(nx: int, slab: slice, block: int) -> np.ndarray:
    """The block rows within :data:`NEAR_REACH` block rows (periodic) of those the slab
    ``slab`` owns (:func:`_owned_bands`; none where it owns none)."""
    bands = _owned_bands(slab, block)
    if not bands:
        return np.empty(0, dtype=np.int64)
    return np.unique(np.arange(bands.start - NEAR_REACH, bands.stop + NEAR_REACH) % -(-nx // block))


def _halo(grid: Grid, rows: np.ndarray, cols: np.ndarray, block: int) -> np.ndarray:
    """The bound pixels of every rank in the block rows near this rank's (:func:`_near_bands`),
    as ``(row, col)`` pairs (global indices) in rank order, so that each block's are in the
    order of their flat indices: one ``Alltoallv``, each rank sending each other its pixels
    ``(rows, cols)`` in that rank's near block rows."""
    comm, nx = grid.comm, grid.shape[0]
    bands = rows // block
    chosen = [
        np.flatnonzero(np.isin(bands, _near_bands(nx, block_rows(nx, comm.size, q), block)))
        for q in range(comm.size)
    ]
    send = np.stack([rows, cols], axis=1)[np.concatenate(chosen)]
    sent = [2 * len(c) for c in chosen]
    taken = comm.alltoall(sent)
    near = np.empty((sum(taken) // 2, 2), dtype=np.int64)
    comm.Alltoallv([send, sent], [near, taken])
    return near


def host_coarse_matrix(
    grid: Grid, quarter: np.ndarray, bound: Any, block: int, max_size: int, device: Device
) -> CoarseMatrix:
    """The coarse matrix summed on the host by the numba loops: the ``cpu`` device's build.
    On several ranks no rank holds every bound pixel, only its own and those of the block
    rows near the ones it owns (:func:`distributed_aggregates`)."""
    local = np.flatnonzero(device.to_host(bound))
    rows, cols = np.divmod(local, grid.shape[1])
    rows += grid.rows.start
    if grid.comm.size == 1:
        parts, labels = whole_aggregates(rows, cols, grid.shape, block, max_size)
    else:
        parts, labels = distributed_aggregates(grid, rows, cols, block, max_size)
    matrix = coarse_matrix(parts, np.ascontiguousarray(quarter, dtype=float), grid)
    _raise_diagonal(np, matrix, parts.block)
    return CoarseMatrix(
        device.asarray(local), device.asarray(labels), parts.block, parts.sizes, matrix
    )


def array_coarse_matrix(
    grid: Grid, quarter: Any, bound: Any, block: int, max_size: int, device: Device
) -> CoarseMatrix:
    """The coarse matrix summed with the array operations of ``device`` where the bound set
    lives (one rank): the same ``E`` as :func:`host_coarse_matrix` to rounding, its near
    pairs always by FFTs on cells (:func:`~petsc_contact.numerics.aggregates.pair_sums_cells`).
    Nothing crosses to the host but scalars (counts)."""
    xp, shape = device.xp, grid.shape
    local = xp.flatnonzero(device.asarray(bound).reshape(-1))
    rows, cols = local // shape[1], local % shape[1]
    block, labels, ids, counts = aggregate(xp, rows, cols, shape, block, max_size)
    sizes = counts[ids].astype(float)
    block_rc, lookup = block_lookup(xp, ids, shape, block)
    near = device.asarray(quarter, dtype=float)
    matrix = monopoles_array(xp, rows, cols, labels, sizes, near, shape)
    pairs = near_pairs_array(xp, block_rc, lookup, NEAR_REACH)
    sums = pair_sums_cells(xp, rows, cols, labels, block_rc * block, pairs, near, shape, block)
    matrix[pairs[:, 0], pairs[:, 1]] = sums
    matrix[pairs[:, 1], pairs[:, 0]] = sums
    _raise_diagonal(xp, matrix, block)
    return CoarseMatrix(local, labels, block, sizes, matrix)


class CoarseSpace:
    """The aggregates of a bound set and the factorised coarse system (module docstring).

    Parameters
    ----------
    grid
        The row-slab layout.
    quarter
        ``G`` at offsets ``0 .. nx/2`` and ``0 .. ny/2``, an array of ``device``: this rank's
        rows of it (:func:`~petsc_contact.numerics.schur.quarter`).
    bound
        This rank's slab of the bound-set mask (``True`` on ``B``; an array of ``device`` or
        of the host); not empty on all ranks.
    block
        The aggregates' smallest block side ``b`` in pixels.
    max_size
        The most aggregates: ``b`` grows until there are at most this many.
    device
        Where the fields it corrects live.  On the ``cpu`` device, and on several ranks, the
        matrix is summed by the numba loops (:func:`host_coarse_matrix`); on the array
        devices on one rank by array operations on the device (:func:`array_coarse_matrix`).
        It is factorised and solved on the device
        (:class:`~petsc_contact.numerics.schur.BorderedSystem`).

    Attributes
    ----------
    local
        This rank's bound pixels (flat local indices), the support of the reactions.
    size
        The number of aggregates ``k``.
    block
        The block side used.
    factorised
        Whether ``E`` was positive definite (otherwise :meth:`solve` must not be used).
    system
        The :class:`~petsc_contact.numerics.schur.BorderedSystem` of ``E``.
    """

    def __init__(
        self, grid: Grid, quarter: Any, bound: Any, block: int, max_size: int, device: Device = CPU
    ) -> None:
        self.grid = grid
        self.device = device
        several = grid.comm.size > 1  # the array build holds every bound pixel: one rank
        build = host_coarse_matrix if device.compiled or several else array_coarse_matrix
        built = build(grid, quarter, bound, block, max_size, device)
        self.local, self.labels, self.block = built.local, built.labels, built.block
        self.size = int(built.sizes.size)
        self.system = BorderedSystem(built.matrix, device.asarray(built.sizes), device)
        # E not positive definite: no coarse space (alike on every rank, which all factorise E)
        self.factorised = bool(grid.min(float(self.system.factorised)))

    def solve(self, g_r: Any, r_sum: float) -> tuple[Any, float]:
        """``(W a on this rank's bound pixels, c)`` for ``G r`` (local slab) and ``sum(r)``."""
        xp = self.device.xp
        f = xp.bincount(self.labels, weights=-g_r.reshape(-1)[self.local], minlength=self.size)
        if self.grid.comm.size > 1:
            f = self.grid.comm.allreduce(f)
        a, c = self.system.solve(f, r_sum)
        return a[self.labels], c


def input_sum(grid: Grid, x: Any) -> float:
    """The sum of a field over every rank of ``grid`` (collective): what
    :func:`add_correction` needs of the input, taken before ``G x`` may overwrite it."""
    return float(grid.sum(x.sum())[0])


def add_correction(
    apply: Any, correction: Any, total: float, out: np.ndarray, work: Any
) -> np.ndarray:
    """``out <- out + G (reactions) + c`` for ``out = G x``: the Schur or two-level form.

    ``apply(x, out)`` applies ``G``; ``correction`` is a :class:`CoarseSpace` or a
    :class:`~petsc_contact.numerics.schur.ContactSchur` (``solve`` and ``local``);
    ``total`` is the sum of ``x`` over every rank (:func:`input_sum`: all the correction
    needs of ``x``, so that ``out`` may be ``x``); ``work`` is two flat field-sized arrays,
    overwritten (:meth:`~petsc_contact.backend.preconditioner.MeanModePreconditioner.
    work_fields`: the FFT's input buffer twice; not ``out``).
    Returns the reactions on this rank's pixels of ``correction.local``.
    """
    reactions, shift = correction.solve(out, total)
    spread, response = work
    spread.fill(0.0)
    spread[correction.local] = reactions
    out += apply(spread, response).reshape(out.shape)
    out += shift
    return reactions


class CoarseCorrected(ShellInterface):
    """``G`` with the correction of a fixed coarse space: the two-level (or, with single-pixel
    aggregates, the exact Schur) preconditioner of a held-set solve.

    Parameters
    ----------
    compliance
        ``G``, with a zero ``q = 0`` entry (``apply_array`` and ``diagonal``).
    correction
        The coarse space of the held contact set.
    work
        Two flat field-sized arrays to compute in (:func:`add_correction`).
    """

    def __init__(self, compliance: Any, correction: CoarseSpace, work: Any) -> None:
        self.op = compliance
        self.grid = compliance.grid
        self.correction = correction
        self._work = work
        self.applications = 0

    @property
    def input_field(self) -> Any:
        """The first work field: :func:`add_correction` reads its input before it writes
        there (:class:`~petsc_contact.solver.linear.ReadsInputFirst`)."""
        return self._work[0]

    def apply_array(self, x: np.ndarray, out: np.ndarray) -> np.ndarray:
        self.applications += 1
        total = input_sum(self.grid, x)
        self.op.apply_array(x, out)
        add_correction(self.op.apply_array, self.correction, total, out, self._work)
        return out

    def diagonal(self) -> float:
        return float(self.op.diagonal())
