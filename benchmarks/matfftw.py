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
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft


def best_of(fn, repeats: int = 5, inner: int = 10) -> float:
    fn()
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(inner):
            fn()
        best = min(best, (time.perf_counter() - start) / inner)
    return best


class MatFFTW:
    """PETSc's ``MATFFTW`` of an ``n x n`` grid with its three FFTW-layout Vecs (ctypes)."""

    def __init__(self, petsc, n: int, comm) -> None:
        from mpi4py import MPI

        self.lib = lib = ctypes.CDLL(_petsc.library_path())
        int_t = ctypes.c_int64 if np.dtype(petsc.IntType).itemsize == 8 else ctypes.c_int32
        vp = ctypes.c_void_p
        lib.MatCreateFFT.argtypes = [vp, int_t, ctypes.POINTER(int_t), ctypes.c_char_p]
        lib.MatCreateFFT.argtypes += [ctypes.POINTER(vp)]
        for name in (
            "VecScatterPetscToFFTW",
            "VecScatterFFTWToPetsc",
            "MatMult",
            "MatMultTranspose",
        ):
            getattr(lib, name).argtypes = [vp, vp, vp]
        lib.MatCreateVecsFFTW.argtypes = [vp] + [ctypes.POINTER(vp)] * 3
        lib.MatDestroy.argtypes = lib.VecDestroy.argtypes = [ctypes.POINTER(vp)]
        self.mat = vp()
        dims = (int_t * 2)(n, n)
        if lib.MatCreateFFT(vp(MPI._handleof(comm)), 2, dims, b"fftw", ctypes.byref(self.mat)):
            raise RuntimeError("MatCreateFFT failed")
        self.x, self.y, self.z = vp(), vp(), vp()
        vecs = (ctypes.byref(self.x), ctypes.byref(self.y), ctypes.byref(self.z))
        if lib.MatCreateVecsFFTW(self.mat, *vecs):
            raise RuntimeError("MatCreateVecsFFTW failed")

    def round_trip(self, vin, vout) -> None:
        """Scatter in, forward, backward, scatter out: one operator application's FFTs."""
        lib, vp = self.lib, ctypes.c_void_p
        lib.VecScatterPetscToFFTW(self.mat, vp(vin.handle), self.x)
        lib.MatMult(self.mat, self.x, self.y)
        lib.MatMultTranspose(self.mat, self.y, self.z)
        lib.VecScatterFFTWToPetsc(self.mat, self.z, vp(vout.handle))

    def scatters(self, vin, vout) -> None:
        vp = ctypes.c_void_p
        self.lib.VecScatterPetscToFFTW(self.mat, vp(vin.handle), self.x)
        self.lib.VecScatterFFTWToPetsc(self.mat, self.z, vp(vout.handle))

    def destroy(self) -> None:
        for v in (self.x, self.y, self.z):
            self.lib.VecDestroy(ctypes.byref(v))
        self.lib.MatDestroy(ctypes.byref(self.mat))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=2048)
    args = ap.parse_args()
    petsc = _petsc.init([])
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    n = args.grid
    matfftw = MatFFTW(petsc, n, comm)
    grid = Grid(n, 1.0, comm)
    vin = petsc.Vec().createMPI((grid.local_shape[0] * n, n * n), comm=comm)
    vout = vin.duplicate()
    vin.setRandom()
    fft = make_fft(grid)

    def package_round_trip() -> None:
        fft.real[...] = vin.array_r.reshape(grid.local_shape)
        fft.forward()
        fft.backward()
        vout.array[...] = fft.result.reshape(-1)

    times = [
        comm.allreduce(best_of(fn), op=MPI.MAX)
        for fn in (
            lambda: matfftw.round_trip(vin, vout),
            lambda: matfftw.scatters(vin, vout),
            package_round_trip,
        )
    ]
    matfftw.destroy()
    vin.destroy()
    vout.destroy()
    if comm.rank == 0:
        t_petsc, t_scatter, t_pkg = (1e3 * t for t in times)
        print(
            f"n = {n}, ranks = {comm.size}: MATFFTW round trip {t_petsc:.1f} ms "
            f"(of which the two scatters {t_scatter:.1f} ms); package backend "
            f"({type(fft).__name__}) {t_pkg:.1f} ms"
        )


if __name__ == "__main__":
    main()
