"""The parallel FFT backends against numpy's serial transform, under mpiexec: one launch per
rank count checks every grid of that count in turn (:data:`CASES`), each grid's checks
:data:`SCRIPT`."""

import subprocess

import pytest
from conftest import python

SCRIPT = r"""
nx, ny = (int(v) for v in shape.split(","))
grid = Grid((nx, ny), (2.0, 2.0 * ny / nx), MPI.COMM_WORLD)
fft = make_fft(grid)
assert type(fft).__name__ == expected, type(fft).__name__
full = np.random.default_rng(3).standard_normal((nx, ny))
fft.real[...] = full[grid.rows]
fft.forward()
rows, cols = fft.spectral_index
ref = np.fft.rfft2(full)[rows, cols]
got = fft.spectrum.T if fft.transposed else fft.spectrum
assert np.abs(got - ref).max() <= 1e-12 * np.abs(ref).max()
q = wavevector_magnitude(grid, fft)  # the layout the multipliers follow
q = q.T if fft.transposed else q
i, j = np.meshgrid(np.fft.fftfreq(nx, 1 / nx)[rows], np.arange(ny // 2 + 1)[cols], indexing="ij")
assert np.allclose(q, np.hypot(np.pi * i, 2 * np.pi / grid.lengths[1] * j))  # 2 pi/L per index
fft.backward()
assert np.abs(fft.result / grid.size - full[grid.rows]).max() <= 1e-13
out = np.empty(grid.local_shape)
fft.forward_from(full[grid.rows])
fft.backward_into(out)
assert np.abs(out / grid.size - full[grid.rows]).max() <= 1e-13
# an operator's quadratic form from its spectrum (Parseval with the half-spectrum
# multiplicities of this layout) equals x.Kx in real space
op = FourierOperator(grid, fft, wavevector_magnitude(grid, fft))
x = full[grid.rows]
quadratic = grid.sum(op.begin_mult(x))[0]
op.end_mult(out)
assert abs(quadratic / grid.sum(np.vdot(x, out))[0] - 1) <= 1e-13
"""
LAUNCH = r"""
import sys
import numpy as np
from mpi4py import MPI
from petsc_contact.devices.fft import make_fft, wavevector_magnitude
from petsc_contact.conventions.grid import Grid
from petsc_contact.backend.operator import FourierOperator

for case in sys.argv[1:]:
    shape, expected = case.split(":")
    exec(SCRIPT)
    MPI.COMM_WORLD.Barrier()
    if MPI.COMM_WORLD.rank == 0:
        print("passed", case, flush=True)
""".replace("SCRIPT", repr(SCRIPT))  # a failed check ends the launch: the later grids fail too
CASES = [
    (2, "64,64", "FFTWMPI"),
    (3, "96,96", "FFTWMPI"),
    (3, "30,30", "FFTWMPI"),
    (3, "64,64", "SlabFFT"),
    (2, "64,18", "FFTWMPI"),
    (3, "30,47", "FFTWMPI"),
    (3, "64,20", "SlabFFT"),
]


@pytest.fixture(scope="module")
def launched() -> dict[int, subprocess.CompletedProcess]:
    """Each rank count's launch over its grids of :data:`CASES`, FFTW-MPI's first: once
    mpi4py-fft has planned in a process, FFTW-MPI's planner returns no plan there, and
    ``make_fft`` falls back to mpi4py-fft for every later grid (30,47 on 3 ranks after 64,64)."""
    launches = {}
    for ranks in sorted({ranks for ranks, _, _ in CASES}):
        mine = sorted((b != "FFTWMPI", f"{n}:{b}") for k, n, b in CASES if k == ranks)
        launches[ranks] = python("-c", LAUNCH, *(c for _, c in mine), mpi=ranks, timeout=240)
    return launches


@pytest.mark.parametrize("ranks, n, backend", CASES)
def test_parallel_fft_matches_numpy(launched, ranks, n, backend):
    """FFTW-MPI (spectrum transposed) where FFTW's row split is the grid's; mpi4py-fft when
    it is not (n = 64 on 3 ranks: FFTW splits 22/22/20, the grid 22/21/21).  Rounding of a
    2-D FFT is ~eps log n relative to the largest coefficient.  Rectangles too, odd ``ny``
    included.  One launch per rank count (:func:`launched`), the grids in turn: a rank
    starts (imports, PETSc) once for all its grids."""
    r = launched[ranks]
    assert f"passed {n}:{backend}\n" in r.stdout, r.stdout + r.stderr
