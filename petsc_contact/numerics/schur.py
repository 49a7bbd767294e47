"""Exact inverse of the periodic Hessian on a free set with few bound pixels (a Schur complement).

With ``G = H^+`` the Fourier compliance (``q = 0`` entry zero) and ``B`` the ``m`` variables
held at their bound, the solution of ``H_FF z_F = r_F``, ``z_B = 0`` is

    z = G (r + lambda_B) + c,      [ G_BB  1 ] [lambda]   [ -(G r)_B ]
                                   [ 1^T   0 ] [  c   ] = [ -sum(r)  ],

``lambda`` being the reactions on ``B`` and ``c`` the rigid shift (``H`` annihilates constants,
so ``r + lambda`` must have zero sum).  ``G_BB`` is a dense ``m x m`` block of the real-space
compliance ``G(i - i', j - j')``, read from one column of ``G``: the operator is periodic and
even in both offsets, so the quarter ``(nx/2 + 1) x (ny/2 + 1)`` of that column
(:func:`quarter`) holds every entry.  ``G`` is positive semi-definite with only the constants
in its null space, so ``G_BB`` is positive definite for any ``B`` short of the whole grid
(its smallest eigenvalue at least ``(1 - m/N)/k_max``, ``N`` pixels and ``k_max`` the
Hessian's largest eigenvalue) and
the bordered system is solved by ``G_BB``'s Cholesky factor (:class:`BorderedSystem`, which
the two-level form's coarse matrix shares), where the fields live: on a GPU, nothing but
scalars comes to the host.  On several ranks each rank holds only the quarter's rows in its
own slab (:func:`held_rows`), makes only the entries whose folded row offset it holds, and
the ranks' matrices are summed (:func:`sum_over_ranks`): each entry comes from one rank.
Applied as the conjugate-gradient preconditioner, it makes each step exact on the current
contact set; it costs two FFT round trips and an ``m x m`` Cholesky factorisation per set.
"""

from __future__ import annotations

from types import ModuleType
from typing import Any

import numpy as np

from ..conventions.grid import Grid
from ..devices.device import CPU, Device


class BorderedSystem:
    """The bordered system ``[[E, w], [w^T, 0]] [a, c] = [f, -r_sum]`` of a symmetric
    positive definite ``E``, solved by ``E``'s Cholesky factor on the device where ``E``
    lives (:meth:`~petsc_contact.devices.device.Device.cho_factor`):

        a = y - c E^-1 w,    c = (w.y + r_sum) / (w.E^-1 w),    y = E^-1 f,

    so that ``E a + c w = f`` and ``w.a = -r_sum``.  The exact Schur form (``E = G_BB``,
    ``w = 1``) and the two-level form (``E`` the coarse matrix, ``w`` the aggregates' sizes)
    both solve it once per application.

    Parameters
    ----------
    matrix
        ``E``, an array of ``device`` (on the host factorised in its own memory if it is in
        Fortran order; only one triangle is read).
    weights
        ``w``, an array of ``device``.
    device
        Where ``E`` is factorised and the system solved.

    Attributes
    ----------
    factorised
        Whether ``E`` was positive definite (otherwise :meth:`solve` must not be used).
    factor
        The ``cho_factor`` pair of ``E`` (:meth:`~petsc_contact.devices.device.Device.
        cho_factor`: SciPy's on the host, cuSOLVER's factor on a GPU), ``None`` when it
        failed.
    """

    def __init__(self, matrix: Any, weights: Any, device: Device = CPU) -> None:
        self.device = device
        self.factor = device.cho_factor(matrix)
        self.factorised = self.factor is not None
        if self.factor is None:
            return
        self._weights = weights
        self._e_w = device.cho_solve(self.factor, weights)  # E^-1 w
        self._w_e_w = float(weights @ self._e_w)

    def solve(self, f: Any, r_sum: float) -> tuple[Any, float]:
        """``(a, c)`` for the right-hand side ``f`` (an array of the device) and ``r_sum``."""
        assert self.factor is not None
        y = self.device.cho_solve(self.factor, f)
        c = (float(self._weights @ y) + r_sum) / self._w_e_w
        return y - c * self._e_w, c


class ContactSchur:
    """The bordered contact system of a bound set, for ``z = H_FF^-1 r`` (module docstring).

    Parameters
    ----------
    grid
        The row-slab layout.
    quarter
        ``G`` at offsets ``0 .. nx/2`` and ``0 .. ny/2``, this rank's rows of it
        (:func:`quarter`), an array of ``device``.
    bound
        This rank's slab of the bound-set mask (``True`` on ``B``), an array of ``device``.
    device
        Where the fields it corrects live, and where ``G_BB`` is made, factorised and solved
        (:attr:`local` is an index array of it); on several ranks (the ``cpu`` device) every
        rank factorises the whole ``G_BB``, summed over the ranks.

    Attributes
    ----------
    local
        This rank's bound pixels (flat local indices), the support of the reactions.
    size
        The number of bound pixels on all ranks, ``m``.
    factorised
        Whether ``G_BB`` was positive definite (it is, short of rounding, for ``m`` below the
        grid's size; otherwise :meth:`solve` must not be used).
    system
        The :class:`BorderedSystem` of ``G_BB``.
    """

    def __init__(self, grid: Grid, quarter: Any, bound: Any, device: Device = CPU) -> None:
        self.grid = grid
        self.device = device
        xp = device.xp
        self.local = xp.flatnonzero(device.asarray(bound).reshape(-1))
        rows, cols = self.local // grid.shape[1], self.local % grid.shape[1]
        rows = rows + grid.rows.start
        both = allgather(xp.stack([rows, cols], axis=1), grid.comm)
        self.offset = 0 if grid.comm.size == 1 else int(grid.comm.exscan(len(self.local)) or 0)
        block = compliance_block(xp, quarter, both, grid.shape, held_rows(grid))
        self.size = len(both)
        self.system = BorderedSystem(sum_over_ranks(block, grid.comm), xp.ones(self.size), device)
        self.factorised = bool(grid.min(float(self.system.factorised)))  # alike on every rank

    def solve(self, g_r: Any, r_sum: float) -> tuple[Any, float]:
        """``(lambda on this rank's bound pixels, c)`` for ``G r`` (local slab) and ``sum(r)``."""
        mine = -g_r.reshape(-1)[self.local]
        reactions, shift = self.system.solve(allgather(mine, self.grid.comm), r_sum)
        if self.grid.comm.size > 1:
            reactions = reactions[self.offset : self.offset + len(self.local)]
        return reactions, shift


SYSTEM_ROWS = 64  # rows of G_BB filled at a time (bounds the temporaries)


def compliance_block(
    xp: ModuleType, quarter: Any, both: Any, shape: tuple[int, int], held: range
) -> Any:
    """``G_BB`` for the bound pixels ``both`` (global ``(row, col)`` pairs, an array of
    ``xp``), this rank's part of it: the entries whose folded row offset is in ``held``
    (:func:`held_rows`, the rows of ``quarter`` from ``held.start``), zero elsewhere; on one
    rank the whole block.

    Filled :data:`SYSTEM_ROWS` rows at a time, so that the pixel offsets' temporaries stay
    ``SYSTEM_ROWS x m`` for ``m`` pixels; returned in Fortran order (the transpose of the
    rows filled: the block is symmetric), which LAPACK factorises in place on the host.
    """
    m = len(both)
    whole = held.start == 0 and held.stop == shape[0] // 2 + 1
    block = xp.zeros((m, m))
    for lo in range(0, m, SYSTEM_ROWS):
        part = both[lo : lo + SYSTEM_ROWS]
        di, dj = (
            _fold(part[:, k][:, None] - both[:, k][None, :], period)
            for k, period in enumerate(shape)
        )
        block[lo : lo + len(part)] = quarter[di, dj] if whole else _held(quarter, di, dj, held)
    return block.T


def _held(quarter: np.ndarray, di: np.ndarray, dj: np.ndarray, held: range) -> np.ndarray:
    """``G(di, dj)`` where the row ``di`` is in ``held`` (``quarter``'s rows from
    ``held.start``), zero elsewhere (several ranks: on the host)."""
    out = np.zeros(di.shape)
    mine = (di >= held.start) & (di < held.stop)
    out[mine] = quarter[di[mine] - held.start, dj[mine]]
    return out


SUM_CHUNK = 1 << 19
"""Entries summed over the ranks by one ``Allreduce`` of :func:`sum_over_ranks` (4 MiB): the
buffers MPI takes for a sum stay this small, not the matrix's size (up to 117 MiB)."""


def sum_over_ranks(matrix: np.ndarray, comm: Any) -> np.ndarray:
    """``matrix`` (contiguous, in C or Fortran order) summed over the ranks in place and
    returned, :data:`SUM_CHUNK` entries at a time (each entry made on one rank, zero on the
    others: the sum is exact); untouched on one rank."""
    if comm.size > 1:
        from mpi4py import MPI

        if not (matrix.flags.c_contiguous or matrix.flags.f_contiguous):
            raise ValueError("sum_over_ranks sums a contiguous matrix in place")
        flat = matrix.reshape(-1, order="A")  # a view of its memory, in order
        for start in range(0, flat.size, SUM_CHUNK):
            comm.Allreduce(MPI.IN_PLACE, flat[start : start + SUM_CHUNK], op=MPI.SUM)
    return matrix


def held_rows(grid: Grid) -> range:
    """The rows of ``G``'s quarter (``0 .. nx/2``) in this rank's slab: all of them on one
    rank, none on a rank whose slab lies beyond ``nx/2`` (or has no rows)."""
    half_x = grid.shape[0] // 2 + 1
    return range(min(grid.rows.start, half_x), min(grid.rows.stop, half_x))


def quarter(grid: Grid, column: Any, device: Device = CPU) -> Any:
    """``G`` at offsets ``0 .. nx/2`` and ``0 .. ny/2``, the rows this rank holds, an array of
    ``device`` (where the set-dependent forms are made from it).

    ``column`` is this rank's slab of ``G e_0``, the response to a unit value at pixel
    ``(0, 0)`` (an array of ``device``); by periodicity and evenness
    ``G(i, j) = G(min(i, nx - i), min(j, ny - j))``.  On one rank the whole quarter; on
    several the rows :func:`held_rows` (none gathered), followed by the next row of the
    quarter where there is one (received from the rank holding it), which the bilinear
    monopoles of :func:`~petsc_contact.numerics.aggregates.monopoles` read.
    """
    half_x, half_y = (m // 2 + 1 for m in grid.shape)
    held = held_rows(grid)
    mine = column[: len(held), :half_y]
    if grid.comm.size == 1:
        return device.xp.array(mine, order="C")  # a copy: column is a work field
    next_row = bool(held) and held.stop < half_x
    part = np.empty((len(held) + next_row, half_y))
    part[: len(held)] = device.to_host(mine)
    _next_row(grid.comm, held, part)
    return part


def _next_row(comm: Any, held: range, part: np.ndarray) -> None:
    """Send this rank's first row of the quarter to the rank holding the rows before it, and
    receive into ``part``'s last row the row after ``held`` where ``part`` has room for it
    (ranks holding no rows take no part)."""
    spans = comm.allgather((held.start, held.stop) if held else None)
    holders = [(rank, span) for rank, span in enumerate(spans) if span is not None]
    sends = [comm.Isend(part[0], dest=r) for r, (_, stop) in holders if held and stop == held.start]
    if len(part) > len(held):
        source = next(r for r, (start, _) in holders if start == held.stop)
        comm.Recv(part[len(held)], source=source)
    for request in sends:
        request.Wait()


def response_quarter(grid: Grid, apply: Any, work: Any, device: Device = CPU) -> Any:
    """:func:`quarter` of an operator's response to a unit value at pixel ``(0, 0)``;
    ``apply(x, out)`` applies it to this rank's slab, ``work`` is two flat field-sized
    arrays of ``device`` to compute in (overwritten)."""
    impulse, response = (w.reshape(grid.local_shape) for w in work)
    impulse.fill(0.0)
    if grid.rows.start == 0:
        impulse[0, 0] = 1.0
    apply(impulse, response)
    return quarter(grid, response, device)


def allgather(local: np.ndarray, comm: Any) -> np.ndarray:
    """Concatenate every rank's array along the first axis, in rank order."""
    return local if comm.size == 1 else np.concatenate(comm.allgather(local))


def _fold(offset: Any, n: int) -> Any:
    """Index of a periodic offset in the even kernel's quarter, ``min(d mod n, -d mod n)``
    (an integer array of any array module)."""
    up, down = offset % n, -offset % n
    return (up + down - abs(up - down)) // 2
