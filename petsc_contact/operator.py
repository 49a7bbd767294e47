"""Fourier-diagonal operators as PETSc shell matrices and preconditioners.

:class:`FourierOperator` applies ``y = IFFT(kernel * FFT(x))`` to the row-slab PETSc Vecs of
a :class:`~petsc_contact.grid.Grid`.  The same object serves as the context of a Python
``Mat`` (``mult``) and of a Python ``PC`` (``apply``), so one class gives TAO both the exact
Hessian and the Fourier preconditioner.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .fft import SerialFFT, SlabFFT, half_spectrum_weights
from .grid import Grid


class FourierOperator:
    """Convolution with a real, even kernel given on the local half-spectrum block.

    Parameters
    ----------
    grid, fft
        Layout and FFT backend.
    kernel
        The multiplier on ``fft.spectrum``'s block (without FFT normalisation).
    """

    def __init__(self, grid: Grid, fft: SerialFFT | SlabFFT, kernel: np.ndarray) -> None:
        self.grid = grid
        self.fft = fft
        self.kernel = np.ascontiguousarray(kernel / grid.size)
        self.applications = 0

    def apply_array(self, x: np.ndarray, out: np.ndarray) -> np.ndarray:
        """``out <- K x`` for local arrays (any shape with the slab's size)."""
        self.applications += 1
        self.fft.real[...] = x.reshape(self.grid.local_shape)
        self.fft.forward()
        self.fft.spectrum *= self.kernel
        self.fft.backward()
        out.reshape(self.grid.local_shape)[...] = self.fft.result
        return out

    def diagonal(self) -> float:
        """The (constant) diagonal entry of the circulant operator."""
        w = half_spectrum_weights(self.grid, self.fft)
        return float(self.grid.sum((w * self.kernel).sum())[0])

    # petsc4py Python Mat interface
    def mult(self, mat: Any, x: Any, y: Any) -> None:
        with y as out:
            self.apply_array(x.array_r, out)

    multTranspose = mult

    def getDiagonal(self, mat: Any, d: Any) -> None:
        d.set(self.diagonal())

    # petsc4py Python PC interface
    def apply(self, pc: Any, x: Any, y: Any) -> None:
        self.mult(None, x, y)

    applyTranspose = apply


def shell_matrix(petsc: Any, op: FourierOperator) -> Any:
    """A PETSc Python ``Mat`` of the grid's row-slab layout whose ``mult`` is ``op``."""
    n_local = op.grid.local_shape[0] * op.grid.n
    mat = petsc.Mat().createPython(((n_local, op.grid.size), (n_local, op.grid.size)),
                                   context=op, comm=op.grid.comm)
    mat.setOption(petsc.Mat.Option.SYMMETRIC, True)
    mat.setUp()
    return mat
