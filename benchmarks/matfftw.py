"""FFT round trip through PETSc's own FFTW-MPI matrix (MATFFTW) against the package's backend.

usage: [mpiexec -n P] .venv/bin/python benchmarks/matfftw.py [--grid 2048]
petsc4py 3.18 does not wrap MatCreateFFT, so it is reached through ctypes on the libpetsc
that petsc4py uses.  A round trip is what one operator application needs: scatter from the
PETSc (row-slab) Vec into FFTW's padded layout, forward, backward, scatter back.  The same
round trip with the package's backend (pyfftw on one rank, mpi4py-fft on several) is printed
beside it.  Best of 5 batches.
"""

from __future__ import annotations

import argparse
import ctypes
import time

import numpy as np

from petsc_contact.backend import _petsc
from petsc_contact.conventions.fft import make_fft
from petsc_contact.conventions.grid import Grid


def best_of(fn, repeats: int = 5, inner: int = 10) -> float:
    fn()
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(inner):
            fn()
        best = min(best, (time.perf_counter() - start) / inner)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=2048)
    args = ap.parse_args()
    petsc = _petsc.init([])
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    n = args.grid
    lib = ctypes.CDLL("libpetsc_real.so.3.18")
    int_t = ctypes.c_int64 if np.dtype(petsc.IntType).itemsize == 8 else ctypes.c_int32
    vp = ctypes.c_void_p
    lib.MatCreateFFT.argtypes = [
        vp,
        int_t,
        ctypes.POINTER(int_t),
        ctypes.c_char_p,
        ctypes.POINTER(vp),
    ]
    for name in ("VecScatterPetscToFFTW", "VecScatterFFTWToPetsc", "MatMult", "MatMultTranspose"):
        getattr(lib, name).argtypes = [vp, vp, vp]
    lib.MatCreateVecsFFTW.argtypes = [
        vp,
        ctypes.POINTER(vp),
        ctypes.POINTER(vp),
        ctypes.POINTER(vp),
    ]
    mat = vp()
    dims = (int_t * 2)(n, n)
    handle = MPI._handleof(comm)
    rc = lib.MatCreateFFT(vp(handle), 2, dims, b"fftw", ctypes.byref(mat))
    if rc:
        raise RuntimeError(f"MatCreateFFT failed ({rc})")
    x, y, z = vp(), vp(), vp()
    if lib.MatCreateVecsFFTW(mat, ctypes.byref(x), ctypes.byref(y), ctypes.byref(z)):
        raise RuntimeError("MatCreateVecsFFTW failed")
    grid = Grid(n, 1.0, comm)
    rows = grid.local_shape[0] * n
    vin = petsc.Vec().createMPI((rows, n * n), comm=comm)
    vout = vin.duplicate()
    vin.setRandom()

    def petsc_round_trip() -> None:
        lib.VecScatterPetscToFFTW(mat, vp(vin.handle), x)
        lib.MatMult(mat, x, y)
        lib.MatMultTranspose(mat, y, z)
        lib.VecScatterFFTWToPetsc(mat, z, vp(vout.handle))

    def scatter_only() -> None:
        lib.VecScatterPetscToFFTW(mat, vp(vin.handle), x)
        lib.VecScatterFFTWToPetsc(mat, z, vp(vout.handle))

    fft = make_fft(grid)
    fft.real[...] = vin.array_r.reshape(grid.local_shape)

    def package_round_trip() -> None:
        fft.real[...] = vin.array_r.reshape(grid.local_shape)
        fft.forward()
        fft.backward()
        vout.array[...] = fft.result.reshape(-1)

    t_petsc = comm.allreduce(best_of(petsc_round_trip), op=MPI.MAX)
    t_scatter = comm.allreduce(best_of(scatter_only), op=MPI.MAX)
    t_pkg = comm.allreduce(best_of(package_round_trip), op=MPI.MAX)
    lib.MatDestroy.argtypes = lib.VecDestroy.argtypes = [ctypes.POINTER(vp)]
    for v in (x, y, z):
        lib.VecDestroy(ctypes.byref(v))
    lib.MatDestroy(ctypes.byref(mat))
    vin.destroy()
    vout.destroy()
    if comm.rank == 0:
        print(
            f"n = {n}, ranks = {comm.size}: MATFFTW round trip {t_petsc * 1e3:.1f} ms "
            f"(of which the two scatters {t_scatter * 1e3:.1f} ms); package backend "
            f"({type(fft).__name__}) {t_pkg * 1e3:.1f} ms"
        )


if __name__ == "__main__":
    main()
