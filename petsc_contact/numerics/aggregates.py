"""Sums of the compliance over aggregates of contact pixels: the loops of the coarse matrix of
the two-level preconditioner (:mod:`petsc_contact.backend.coarse`), without PETSc, in numba for
the ``cpu`` device and in array operations for the array devices (the ``*_array`` functions,
for any array module ``xp`` with NumPy's interface: NumPy or CuPy).

An aggregate ``I`` holds the pixels ``starts[I]:starts[I+1]`` of ``(rows, cols)`` (global
pixel indices, grouped by :func:`grouped`); ``quarter`` is the compliance ``G`` at the offsets
``0 .. nx/2`` and ``0 .. ny/2`` (the kernel is periodic and even,
:func:`~petsc_contact.numerics.schur.quarter`; on several ranks the rows one rank holds,
:func:`monopoles`).  Compiled once, with the passes of
:mod:`~petsc_contact.numerics.kernels` (:func:`~petsc_contact.numerics.kernels.compile_kernels`).
"""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType
from typing import Any

import numpy as np
from numba import njit, prange


@njit(cache=True, nogil=True)
def grouped(labels: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """The indices of ``labels`` grouped by label, in order within each (a counting sort;
    label ``I`` has the places ``starts[I]:starts[I+1]``)."""
    order = np.empty(labels.size, dtype=np.int64)
    place = starts[:-1].copy()
    for i in range(labels.size):
        order[place[labels[i]]] = i
        place[labels[i]] += 1
    return order


@njit(cache=True, nogil=True)
def _fold(d: int, n: int) -> int:
    """The offset ``|d| < n`` of two pixels folded into the even kernel's quarter."""
    d = abs(d)
    return min(d, n - d)


@njit(cache=True, nogil=True)
def _interpolate(
    quarter: np.ndarray, dx: float, dy: float, nx: int, ny: int, first: int, stop: int
) -> float:
    """``G`` at a real offset ``|dx| < nx``, ``|dy| < ny``, bilinear in the folded quarter, of
    which ``quarter`` holds the rows ``first .. stop - 1`` and the next one (where there is
    one); zero where the folded offset's row ``i`` is not among them (made on another rank)."""
    dx = abs(dx)
    dy = abs(dy)
    dx = min(dx, nx - dx)
    dy = min(dy, ny - dy)
    hx, hy = nx // 2, quarter.shape[1] - 1
    i, j = min(int(dx), hx), min(int(dy), hy)
    if i < first or i >= stop:
        return 0.0
    i1, j1 = min(i + 1, hx), min(j + 1, hy)
    fx, fy = dx - i, dy - j
    i, i1 = i - first, i1 - first
    if fx == 0.0 and fy == 0.0:  # a pixel offset (single-pixel aggregates)
        return quarter[i, j]
    return (1.0 - fx) * ((1.0 - fy) * quarter[i, j] + fy * quarter[i, j1]) + fx * (
        (1.0 - fy) * quarter[i1, j] + fy * quarter[i1, j1]
    )


@njit(cache=True, nogil=True)
def centroids(rows: np.ndarray, cols: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """The centroid ``c_I`` of each aggregate ``I`` holding the pixels ``starts[I]:starts[I+1]``
    of ``(rows, cols)`` (an aggregate lies in one block, which does not wrap): ``k x 2``."""
    k = starts.size - 1
    centre = np.empty((k, 2))
    for a in range(k):
        s, e = starts[a], starts[a + 1]
        centre[a, 0] = rows[s:e].astype(np.float64).mean()
        centre[a, 1] = cols[s:e].astype(np.float64).mean()
    return centre


@njit(cache=True, nogil=True, parallel=True)
def monopoles(
    sizes: np.ndarray,
    centre: np.ndarray,
    quarter: np.ndarray,
    nx: int,
    ny: int,
    first: int,
    stop: int,
) -> np.ndarray:
    """``|A_I| |A_J| G(c_I - c_J)`` for aggregates ``I`` of ``sizes[I]`` pixels (floats) and
    centroids ``centre[I]`` (:func:`centroids`), upper triangle only, in Fortran order
    (columns in parallel): LAPACK factorises it in place, with no copy of the ``k x k``
    matrix.  ``quarter`` holds the rows ``first .. stop - 1`` of ``G``'s quarter and the next
    (:func:`~petsc_contact.numerics.schur.quarter`): the entries whose folded row offset is
    elsewhere are zero (``0, nx // 2 + 1`` on one rank: none)."""
    k = sizes.size
    e_mat = np.zeros((k, k)).T
    for b in prange(k):
        rb, cb, sb = centre[b, 0], centre[b, 1], sizes[b]
        for a in range(b + 1):
            dx, dy = centre[a, 0] - rb, centre[a, 1] - cb
            e_mat[a, b] = sizes[a] * sb * _interpolate(quarter, dx, dy, nx, ny, first, stop)
    return e_mat


@njit(cache=True, nogil=True)
def near_pairs(block_rc: np.ndarray, lookup: np.ndarray, reach: int) -> np.ndarray:
    """The pairs ``(I, J)``, ``I <= J``, of aggregates whose blocks are at most ``reach``
    blocks apart (``lookup[bi, bj]``: the aggregate of a block, ``-1`` for none), each once
    (a small grid's blocks wrap onto the same neighbour)."""
    k = block_rc.shape[0]
    bx, by = lookup.shape
    width = (2 * reach + 1) ** 2
    found = np.full((k, width), -1, dtype=np.int64)
    for a in range(k):
        count = 0
        for di in range(-reach, reach + 1):
            for dj in range(-reach, reach + 1):
                b = lookup[(block_rc[a, 0] + di) % bx, (block_rc[a, 1] + dj) % by]
                if b < a:  # none, or found from b's side
                    continue
                known = False
                for t in range(count):
                    known = known or found[a, t] == b
                if not known:
                    found[a, count] = b
                    count += 1
    total = 0
    for a in range(k):
        for t in range(width):
            total += found[a, t] >= 0
    pairs = np.empty((total, 2), dtype=np.int64)
    i = 0
    for a in range(k):
        for t in range(width):
            if found[a, t] >= 0:
                pairs[i, 0] = a
                pairs[i, 1] = found[a, t]
                i += 1
    return pairs


@njit(cache=True, nogil=True, parallel=True)
def pair_sums_direct(
    rows: np.ndarray,
    cols: np.ndarray,
    starts: np.ndarray,
    pairs: np.ndarray,
    near: np.ndarray,
    nx: int,
    ny: int,
) -> np.ndarray:
    """``sum G(p - q)`` over the pixels ``p`` of ``I`` and ``q`` of ``J`` for each pair, pixel
    pair by pixel pair; ``near`` is the corner of ``G``'s quarter the offsets reach."""
    out = np.empty(pairs.shape[0])
    for t in prange(pairs.shape[0]):
        a, b = pairs[t, 0], pairs[t, 1]
        total = 0.0
        for p in range(starts[a], starts[a + 1]):
            rp, cp = rows[p], cols[p]
            for q in range(starts[b], starts[b + 1]):
                total += near[_fold(rp - rows[q], nx), _fold(cp - cols[q], ny)]
        out[t] = total
    return out


@njit(cache=True, nogil=True, parallel=True)
def spectral_dots(
    spectra: np.ndarray,
    kernels: np.ndarray,
    pairs: np.ndarray,
    kind: np.ndarray,
    weight: np.ndarray,
    out: np.ndarray,
    where: np.ndarray,
) -> None:
    """``out[where[t]] = sum_k weight Re(conj(A^) T^ B^)`` for the ``t``-th pair of rows
    ``(A, B)`` of ``spectra`` and its kernel ``kernels[kind[t]]`` (half spectra)."""
    rows, cols = spectra.shape[1], spectra.shape[2]
    for t in prange(pairs.shape[0]):
        a, b, c = pairs[t, 0], pairs[t, 1], kind[t]
        total = 0.0
        for i in range(rows):
            for j in range(cols):
                z = np.conj(spectra[a, i, j]) * kernels[c, i, j] * spectra[b, i, j]
                total += weight[j] * z.real
        out[where[t]] = total


CHUNK_ENTRIES = 1 << 22  # the array functions' temporaries hold at most this many entries


def monopoles_array(
    xp: ModuleType,
    rows: Any,
    cols: Any,
    labels: Any,
    sizes: Any,
    quarter: Any,
    shape: tuple[int, int],
) -> Any:
    """:func:`monopoles` on arrays of ``xp``, for the pixels ``(rows, cols)`` of aggregates
    ``labels`` (``sizes``: their pixel counts, floats): the full symmetric ``k x k`` matrix,
    in bands of rows of at most :data:`CHUNK_ENTRIES` entries.  The centroids are exact
    sums of integers over the counts, as :func:`centroids`' means, and the interpolation is
    its formula term by term."""
    k = sizes.size
    centre_r = xp.bincount(labels, weights=rows.astype(float), minlength=k) / sizes
    centre_c = xp.bincount(labels, weights=cols.astype(float), minlength=k) / sizes
    out = xp.empty((k, k))
    band = max(1, CHUNK_ENTRIES // max(k, 1))
    for lo in range(0, k, band):
        hi = min(k, lo + band)
        g = _interpolate_array(
            xp, quarter, centre_r[lo:hi, None] - centre_r, centre_c[lo:hi, None] - centre_c, shape
        )
        out[lo:hi] = sizes[lo:hi, None] * sizes * g
    return out


def _interpolate_array(
    xp: ModuleType, quarter: Any, dx: Any, dy: Any, shape: tuple[int, int]
) -> Any:
    """:func:`_interpolate` element by element on arrays of offsets ``|dx| < nx``, ``|dy| < ny``."""
    nx, ny = shape
    dx, dy = xp.abs(dx), xp.abs(dy)
    dx, dy = xp.minimum(dx, nx - dx), xp.minimum(dy, ny - dy)
    hx, hy = quarter.shape[0] - 1, quarter.shape[1] - 1
    i, j = xp.minimum(dx.astype(np.int64), hx), xp.minimum(dy.astype(np.int64), hy)
    i1, j1 = xp.minimum(i + 1, hx), xp.minimum(j + 1, hy)
    fx, fy = dx - i, dy - j
    return (1.0 - fx) * ((1.0 - fy) * quarter[i, j] + fy * quarter[i, j1]) + fx * (
        (1.0 - fy) * quarter[i1, j] + fy * quarter[i1, j1]
    )


def near_pairs_array(xp: ModuleType, block_rc: Any, lookup: Any, reach: int) -> Any:
    """:func:`near_pairs` on arrays of ``xp`` (each pair once, ``I <= J``, in the order of
    ``I k + J``)."""
    k = block_rc.shape[0]
    bx, by = lookup.shape
    steps = xp.arange(-reach, reach + 1)
    di, dj = (s.reshape(-1) for s in xp.meshgrid(steps, steps, indexing="ij"))
    partner = lookup[(block_rc[:, :1] + di) % bx, (block_rc[:, 1:] + dj) % by]
    first = xp.broadcast_to(xp.arange(k)[:, None], partner.shape)
    keep = partner >= first
    keys = xp.unique(first[keep] * k + partner[keep])
    return xp.stack([keys // k, keys % k], axis=1)


def offset_kernels(
    xp: ModuleType, rfft2: Any, offsets: Any, quarter: Any, shape: tuple[int, int], block: int
) -> Any:
    """The half spectra ``T^`` on ``2b x 2b`` cells of ``T(w) = G(d + w)``, ``|w| < b``, for
    each block offset ``d`` (rows of ``offsets``, each in ``0 .. n - 1``): the kernels of the
    FFT pair sums (:func:`pair_sums_cells`; ``rfft2`` transforms the last two axes)."""
    nx, ny = shape
    m = 2 * block
    w = xp.arange(-block + 1, block)
    fx = (offsets[:, :1] + w) % nx
    fy = (offsets[:, 1:] + w) % ny
    fx, fy = xp.minimum(fx, nx - fx), xp.minimum(fy, ny - fy)
    cells = xp.zeros((offsets.shape[0], m, m))
    which = xp.arange(offsets.shape[0])[:, None, None]
    cells[which, (w % m)[:, None], (w % m)[None, :]] = quarter[fx[:, :, None], fy[:, None, :]]
    return rfft2(cells)


def half_spectrum_weights(xp: ModuleType, m: int) -> Any:
    """Parseval's weights of an ``m x m`` cell's half spectrum over ``m^2`` (each column but
    the first and the Nyquist one counted twice)."""
    weight = xp.full(m // 2 + 1, 2.0 / (m * m))
    weight[0] = weight[-1] = 1.0 / (m * m)
    return weight


def pair_sums_cells(
    xp: ModuleType,
    rows: Any,
    cols: Any,
    labels: Any,
    origin: Any,
    pairs: Any,
    quarter: Any,
    shape: tuple[int, int],
    block: int,
) -> Any:
    """:func:`pair_sums_direct`'s sums by FFTs on ``2b x 2b`` cells, on arrays of ``xp``
    (``origin``: each aggregate's block corner): ``sum_k w Re(conj(A^) T^ B^)`` per pair
    (the method of :func:`petsc_contact.backend.coarse._pair_sums_fft`), the pairs taken in
    batches whose spectra hold at most :data:`CHUNK_ENTRIES` entries."""
    nx, ny = shape
    m = 2 * block
    offsets = origin[pairs[:, 0]] - origin[pairs[:, 1]]
    keys, kind = xp.unique((offsets[:, 0] % nx) * ny + offsets[:, 1] % ny, return_inverse=True)
    kernels = offset_kernels(
        xp, xp.fft.rfft2, xp.stack([keys // ny, keys % ny], axis=1), quarter, shape, block
    )
    weight = half_spectrum_weights(xp, m)
    where = xp.full(origin.shape[0], -1, dtype=np.int64)
    out = xp.empty(pairs.shape[0])
    batch = max(1, CHUNK_ENTRIES // (m * m))
    for lo in range(0, pairs.shape[0], batch):
        chosen = slice(lo, lo + batch)
        members, index = xp.unique(pairs[chosen].reshape(-1), return_inverse=True)
        where[members] = xp.arange(members.size)
        cell = where[labels]
        on = cell >= 0
        cells = xp.zeros((members.size, m, m))
        mine = labels[on]
        cells[cell[on], rows[on] - origin[mine, 0], cols[on] - origin[mine, 1]] = 1.0
        where[members] = -1
        spectra = xp.fft.rfft2(cells)
        index = index.reshape(-1, 2)
        z = xp.conj(spectra[index[:, 0]]) * kernels[kind.reshape(-1)[chosen]]
        z *= spectra[index[:, 1]]
        out[chosen] = (z.real @ weight).sum(axis=1)
    return out


def specimen_calls() -> list[tuple[Callable[..., object], tuple[object, ...]]]:
    """Each kernel with tiny arguments of the types :mod:`petsc_contact.backend.coarse` passes
    it (int64 pixel indices, float64 compliances, complex128 spectra, Python ints), for
    :func:`~petsc_contact.numerics.kernels.compile_kernels`: one aggregate of two pixels."""
    rows, cols, starts = np.array([0, 1]), np.array([0, 0]), np.array([0, 2])
    pair, quarter = np.zeros((1, 2), dtype=np.int64), np.ones((2, 2))
    spectra = np.zeros((1, 2, 2), dtype=complex)
    index, weight = np.zeros(1, dtype=np.int64), np.ones(2)
    return [
        (grouped, (np.zeros(2, dtype=np.int64), starts)),
        (centroids, (rows, cols, starts)),
        (monopoles, (np.ones(1), np.zeros((1, 2)), quarter, 2, 2, 0, 2)),
        (near_pairs, (pair, np.zeros((1, 1), dtype=np.int64), 1)),
        (pair_sums_direct, (rows, cols, starts, pair, quarter, 2, 2)),
        (spectral_dots, (spectra, spectra, pair, index, weight, np.zeros(1), index)),
    ]
