"""The periodic grid (square or rectangular) and its distribution over MPI ranks in row slabs.

Every field lives on an ``nx x ny`` grid of sides ``Lx x Ly``.  Under MPI each rank owns the
contiguous rows ``grid.rows`` (the first ``n % size`` ranks one row more), which is the
layout of both PETSc's default ownership (with local sizes set per row) and mpi4py-fft's
slab decomposition.  Reductions go through :meth:`Grid.sum` so that every observable is
the same on every rank.

mpi4py is the ``mpi`` extra: the communicators come from :func:`world` and
:func:`self_comm`, which give the stand-in :class:`OneRank` where it is not installed and the
run has one rank, and raise :class:`MPIUnavailable` (saying how to install it) on several.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol, SupportsFloat, TypeVar

import numpy as np

if TYPE_CHECKING:  # mpi4py (the mpi extra) is loaded when a grid is made, if at all
    from mpi4py import MPI

from .validation import per_axis, positive

MPI_INSTALL_HINT = (
    "pip install 'petsc-contact[mpi]' (in the set-up's venv: .venv/bin/pip install mpi4py)"
)
LAUNCHER_VARIABLES = {
    "size": ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE"),  # Open MPI's mpiexec, MPICH's (Hydra)
    "rank": ("OMPI_COMM_WORLD_RANK", "PMI_RANK"),
}
T = TypeVar("T")


class RowSource(Protocol):
    """A global field that hands out its rows without being read whole (the rows of a resume
    state saved in slabs): ``source[a:b]`` reads rows ``a`` to ``b``."""

    @property
    def shape(self) -> tuple[int, ...]:
        """The global field's shape."""
        ...

    def __getitem__(self, rows: slice) -> np.ndarray: ...


class MPIUnavailable(ImportError):
    """A run on several ranks without mpi4py: the message says how to install it."""


class OneRank:
    """The communicator of a one-rank run without mpi4py: what the package calls of
    ``COMM_WORLD`` on one rank (petsc4py takes PETSc's ``COMM_SELF`` for it,
    :func:`~petsc_contact.backend._petsc.petsc_comm`)."""

    size = 1
    rank = 0

    def bcast(self, value: T, root: int = 0) -> T:
        """``value``: this rank is the root."""
        return value

    def gather(self, value: T, root: int = 0) -> list[T]:
        """``[value]``: every rank's value, this rank's."""
        return [value]

    def Barrier(self) -> None:
        """Nothing to wait for."""


def launched(what: str) -> int:
    """The ``"size"`` of the run or this process's ``"rank"`` without mpi4py: PETSc's
    ``COMM_WORLD`` where PETSc is loaded, else the launcher's environment (Open MPI, MPICH);
    1 and 0 outside a launcher."""
    petsc = sys.modules.get("petsc4py.PETSc")
    if petsc is not None:
        return int(getattr(petsc.COMM_WORLD, what))
    for name in LAUNCHER_VARIABLES[what]:
        if name in os.environ:
            return int(os.environ[name])
    return 1 if what == "size" else 0


def world() -> Any:
    """mpi4py's ``COMM_WORLD``; :class:`OneRank` where mpi4py is not installed and the run
    has one rank; :class:`MPIUnavailable` where it has several."""
    try:
        from mpi4py import MPI
    except ImportError:
        size = launched("size")
        if size > 1:
            raise MPIUnavailable(
                f"a run on {size} MPI ranks needs mpi4py, which is not installed: "
                + MPI_INSTALL_HINT
            ) from None
        return OneRank()
    return MPI.COMM_WORLD


def self_comm() -> Any:
    """mpi4py's ``COMM_SELF``, or :class:`OneRank` where mpi4py is not installed."""
    try:
        from mpi4py import MPI
    except ImportError:
        return OneRank()
    return MPI.COMM_SELF


def world_rank() -> int:
    """This process's rank in the run, whatever is installed (for messages: never raises)."""
    try:
        from mpi4py import MPI
    except ImportError:
        return launched("rank")
    return int(MPI.COMM_WORLD.rank)


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


@dataclass(frozen=True, init=False)
class Grid:
    """An ``nx x ny`` periodic grid of sides ``Lx x Ly`` split in row slabs over ``comm``.

    ``Grid(n, L)`` is the square grid; ``Grid((nx, ny), (Lx, Ly))`` a rectangle, whose pixels
    ``Lx/nx x Ly/ny`` need not be square.  Axis 0 (``x``, rows, ``nx`` points) is the one
    split over MPI ranks; axis 1 (``y``) holds the half spectrum.

    Attributes
    ----------
    shape
        Pixels ``(nx, ny)``, the shape of every field.
    lengths
        Sides ``(Lx, Ly)`` (any length unit; all outputs use the same unit).
    comm
        The MPI communicator of the run (:func:`world` by default; :class:`OneRank` without
        mpi4py).
    """

    shape: tuple[int, int]
    lengths: tuple[float, float]
    comm: MPI.Intracomm = field(compare=False)

    def __init__(
        self,
        n: int | tuple[int, int],
        length: float | tuple[float, float],
        comm: MPI.Intracomm | None = None,
    ) -> None:
        nx, ny = (int(v) for v in per_axis(n, "grid"))
        lx, ly = (float(v) for v in per_axis(length, "length"))
        if min(nx, ny) < 2:
            raise ValueError(f"grid needs at least 2 pixels per side, got {nx} x {ny}")
        positive("length", lx)
        positive("length", ly)
        object.__setattr__(self, "shape", (nx, ny))
        object.__setattr__(self, "lengths", (lx, ly))
        object.__setattr__(self, "comm", world() if comm is None else comm)

    @property
    def square(self) -> bool:
        """Whether the cell is square with as many pixels on both sides."""
        return self.shape[0] == self.shape[1] and self.lengths[0] == self.lengths[1]

    @property
    def n(self) -> int:
        """Pixels per side of a square grid (:attr:`shape` for any grid)."""
        if not self.square:
            raise ValueError(f"grid.n is for square grids; this one is {self.describe()}")
        return self.shape[0]

    @property
    def length(self) -> float:
        """Side of a square cell (:attr:`lengths` for any grid)."""
        if not self.square:
            raise ValueError(f"grid.length is for square grids; this one is {self.describe()}")
        return self.lengths[0]

    @property
    def spacing(self) -> tuple[float, float]:
        """Pixel sides ``(Lx/nx, Ly/ny)``."""
        return self.lengths[0] / self.shape[0], self.lengths[1] / self.shape[1]

    @property
    def pixel(self) -> float:
        """Pixel size ``a`` of square pixels (:attr:`spacing` for any grid)."""
        ax, ay = self.spacing
        if not np.isclose(ax, ay, rtol=1e-12, atol=0.0):
            raise ValueError(f"pixels are {ax:g} x {ay:g}, not square: use grid.spacing")
        return ax

    @property
    def pixel_area(self) -> float:
        """``Lx Ly / (nx ny)``, the area one pixel stands for."""
        return self.area / self.size

    @property
    def area(self) -> float:
        """The nominal area ``Lx Ly``."""
        return self.lengths[0] * self.lengths[1]

    @property
    def q0(self) -> float:
        """The smallest non-zero wavevector ``2 pi / max(Lx, Ly)`` of the periodic spectrum."""
        return fundamental_wavevector(max(self.lengths))

    @property
    def dq(self) -> tuple[float, float]:
        """The spacings ``(2 pi/Lx, 2 pi/Ly)`` of the spectrum along each axis."""
        return fundamental_wavevector(self.lengths[0]), fundamental_wavevector(self.lengths[1])

    @property
    def size(self) -> int:
        """Number of grid points ``nx ny``."""
        return self.shape[0] * self.shape[1]

    @property
    def half(self) -> int:
        """Columns of the half spectrum, ``ny//2 + 1``."""
        return self.shape[1] // 2 + 1

    @property
    def rows(self) -> slice:
        """The global rows this rank owns."""
        return block_rows(self.shape[0], self.comm.size, self.comm.rank)

    @property
    def local_shape(self) -> tuple[int, int]:
        r = self.rows
        return (r.stop - r.start, self.shape[1])

    def positions(self) -> tuple[np.ndarray, np.ndarray]:
        """The pixel centres along ``x`` (rows) and ``y`` (columns): ``(i + 1/2) a``."""
        (nx, ny), (ax, ay) = self.shape, self.spacing
        return (np.arange(nx) + 0.5) * ax, (np.arange(ny) + 0.5) * ay

    def describe(self) -> str:
        """``nx x ny`` points on ``Lx x Ly``, for messages and headers."""
        (nx, ny), (lx, ly) = self.shape, self.lengths
        return f"{nx}x{ny} on {lx:g} x {ly:g}"

    def padded(self) -> Grid:
        """The ``2nx x 2ny`` grid of sides ``2Lx x 2Ly`` of zero padding (same comm)."""
        (nx, ny), (lx, ly) = self.shape, self.lengths
        return Grid((2 * nx, 2 * ny), (2 * lx, 2 * ly), self.comm)

    def sum(self, *values: SupportsFloat) -> np.ndarray:
        """Sum scalars over all ranks (one reduction for all of them)."""
        local = np.array([float(v) for v in values])  # a device's scalars come to the host
        if self.comm.size == 1:
            return local
        total = np.empty_like(local)
        from mpi4py import MPI

        self.comm.Allreduce(local, total, op=MPI.SUM)
        return total

    def min(self, value: float) -> float:
        if self.comm.size == 1:
            return value
        from mpi4py import MPI

        return self.comm.allreduce(value, op=MPI.MIN)

    def max(self, value: float) -> float:
        if self.comm.size == 1:
            return value
        from mpi4py import MPI

        return self.comm.allreduce(value, op=MPI.MAX)

    def mean(self, local: np.ndarray) -> float:
        """Mean of a distributed field."""
        return float(self.sum(local.sum())[0]) / self.size

    def rms(self, local: np.ndarray) -> float:
        """Root mean square of a distributed field."""
        return float(np.sqrt(self.sum(np.vdot(local, local).real)[0] / self.size))

    def scatter(self, full: np.ndarray | RowSource) -> np.ndarray:
        """This rank's slab of a global array that every rank can read (memory-mapped, or a
        :class:`RowSource`): only its rows are read."""
        return np.ascontiguousarray(full[self.rows], dtype=float)

    def slab_from(self, local: np.ndarray, held: list[slice]) -> np.ndarray:
        """This rank's slab (:attr:`rows`) of a global array held in row blocks by the ranks:
        rank ``q`` holds its rows ``held[q]`` (``local``: this rank's, ``ny`` values a row; the
        blocks disjoint, together every row; one rank may hold them all and the others none).
        One ``Alltoallv``: every rank sends each other the rows of its block in that rank's
        slab, so that no rank holds more than its block and its slab."""
        mine = held[self.comm.rank]
        if self.comm.size == 1:
            return np.ascontiguousarray(
                local[self.rows.start - mine.start : self.rows.stop - mine.start]
            )
        moved = np.uint8 if local.dtype == bool else local.dtype  # MPI moves bytes, not bools
        slabs = [block_rows(self.shape[0], self.comm.size, q) for q in range(self.comm.size)]
        out = np.empty(self.local_shape, dtype=moved)
        self.comm.Alltoallv(
            _row_parts(np.ascontiguousarray(local, dtype=moved), mine, slabs),
            _row_parts(out, self.rows, held),
        )
        return out.view(bool) if local.dtype == bool else out

    def gather(self, local: np.ndarray) -> np.ndarray | None:
        """The global array on rank 0 (``None`` elsewhere), of the local slabs' dtype: for
        small maps only (a run's output never gathers a field: each rank writes its rows)."""
        if self.comm.size == 1:
            return np.array(local, copy=True)
        counts = self.comm.gather(local.size, root=0)
        dtype = np.uint8 if local.dtype == bool else local.dtype  # MPI moves bytes, not bools
        full = np.empty(self.shape, dtype=dtype) if self.comm.rank == 0 else None
        self.comm.Gatherv(
            np.ascontiguousarray(local, dtype=dtype),
            [full, counts] if self.comm.rank == 0 else None,
            root=0,
        )
        return full.view(bool) if full is not None and local.dtype == bool else full


def _row_parts(rows: np.ndarray, held: slice, parts: list[slice]) -> list[Any]:
    """The ``Alltoallv`` message of ``rows`` (global rows ``held``) in the parts they share
    with each rank's ``parts[q]``: the array, counts and displacements."""
    width = rows.shape[1]
    starts = [max(held.start, p.start) for p in parts]
    counts = [
        max(0, min(held.stop, p.stop) - a) * width for a, p in zip(starts, parts, strict=True)
    ]
    displacements = [
        (a - held.start) * width if c else 0 for a, c in zip(starts, counts, strict=True)
    ]
    return [rows, (counts, displacements)]


def sides(shape: tuple[int, ...], length: Any) -> tuple[float, float]:
    """``(Lx, Ly)`` of a map of ``shape``: ``length`` given per axis, or one length ``Lx``
    with square pixels (``Ly = Lx ny/nx``).  The package's one rule for a single length."""
    if isinstance(length, (tuple, list, np.ndarray)) and len(length) != 1:
        lx, ly = per_axis(length, "length")
        return float(lx), float(ly)
    lx = float(np.ravel(length)[0])
    return lx, lx * shape[1] / shape[0]


def grid_for(
    shape: tuple[int, ...], length: float | tuple[float, float], comm: MPI.Intracomm | None = None
) -> Grid:
    """The grid of a height map of ``shape`` with sides :func:`sides`."""
    if len(shape) != 2:
        raise ValueError(f"heights must be a 2-D array, got shape {tuple(shape)}")
    return Grid((int(shape[0]), int(shape[1])), sides(shape, length), comm)
