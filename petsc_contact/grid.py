"""The square periodic grid and its distribution over MPI ranks in row slabs.

Every field lives on an ``n x n`` grid of side ``length``.  Under MPI each rank owns the
contiguous rows ``grid.rows`` (the first ``n % size`` ranks one row more), which is the
layout of both PETSc's default ownership (with local sizes set per row) and mpi4py-fft's
slab decomposition.  Reductions go through :meth:`Grid.sum` so that every observable is
the same on every rank.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from mpi4py import MPI

from .validation import positive


def block_rows(n: int, size: int, rank: int) -> slice:
    """Rows owned by ``rank`` when ``n`` rows are split over ``size`` ranks."""
    base, extra = divmod(n, size)
    start = rank * base + min(rank, extra)
    return slice(start, start + base + (rank < extra))


def fft_order(n: int) -> np.ndarray:
    """The integer wavenumbers (or offsets) ``0, 1, ..., -1`` in numpy's FFT order."""
    return np.fft.fftfreq(n, 1.0 / n)


def fundamental_wavevector(length: float) -> float:
    """``q0 = 2 pi / L``, the longest wavelength a periodic cell of side ``L`` holds."""
    return 2 * np.pi / length


@dataclass(frozen=True)
class Grid:
    """An ``n x n`` periodic grid of side ``length`` split in row slabs over ``comm``.

    Attributes
    ----------
    n
        Pixels per side.
    length
        Side of the square cell (any length unit; all outputs use the same unit).
    comm
        The MPI communicator of the run.
    """

    n: int
    length: float
    comm: MPI.Intracomm = field(default_factory=lambda: MPI.COMM_WORLD, compare=False)

    def __post_init__(self) -> None:
        if self.n < 2:
            raise ValueError(f"grid needs at least 2 pixels per side, got {self.n}")
        positive("length", self.length)

    @property
    def pixel(self) -> float:
        """Pixel size ``a = L/n``."""
        return self.length / self.n

    @property
    def q0(self) -> float:
        """The fundamental wavevector ``2 pi / L``: the spacing of the periodic spectrum."""
        return fundamental_wavevector(self.length)

    @property
    def size(self) -> int:
        """Number of grid points ``n^2``."""
        return self.n * self.n

    @property
    def rows(self) -> slice:
        """The global rows this rank owns."""
        return block_rows(self.n, self.comm.size, self.comm.rank)

    @property
    def local_shape(self) -> tuple[int, int]:
        r = self.rows
        return (r.stop - r.start, self.n)

    def sum(self, *values: float) -> np.ndarray:
        """Sum scalars over all ranks (one reduction for all of them)."""
        local = np.array(values, dtype=float)
        if self.comm.size == 1:
            return local
        total = np.empty_like(local)
        self.comm.Allreduce(local, total, op=MPI.SUM)
        return total

    def min(self, value: float) -> float:
        return value if self.comm.size == 1 else self.comm.allreduce(value, op=MPI.MIN)

    def max(self, value: float) -> float:
        return value if self.comm.size == 1 else self.comm.allreduce(value, op=MPI.MAX)

    def mean(self, local: np.ndarray) -> float:
        """Mean of a distributed field."""
        return float(self.sum(local.sum())[0]) / self.size

    def rms(self, local: np.ndarray) -> float:
        """Root mean square of a distributed field."""
        return float(np.sqrt(self.sum(np.vdot(local, local).real)[0] / self.size))

    def scatter(self, full: np.ndarray) -> np.ndarray:
        """This rank's slab of a global array that every rank can read (e.g. memory-mapped)."""
        return np.ascontiguousarray(full[self.rows], dtype=float)

    def gather(self, local: np.ndarray) -> np.ndarray | None:
        """The global array on rank 0 (``None`` elsewhere)."""
        if self.comm.size == 1:
            return np.array(local, copy=True)
        counts = self.comm.gather(local.size, root=0)
        full = np.empty((self.n, self.n)) if self.comm.rank == 0 else None
        self.comm.Gatherv(
            np.ascontiguousarray(local, dtype=float),
            [full, counts] if self.comm.rank == 0 else None,
            root=0,
        )
        return full
