"""Fourier-diagonal operators as PETSc shell matrices and preconditioners.

:class:`FourierOperator` applies ``y = IFFT(kernel * FFT(x))`` to the row-slab PETSc Vecs of
a :class:`~petsc_contact.conventions.grid.Grid` (the periodic geometry).
:class:`PaddedOperator` does the same on a ``2nx x 2ny`` zero-padded copy of an ``nx x ny``
field and reads back the first block: the free-boundary convolution of the punch (Hockney
1970).  Either object serves as the context of a Python ``Mat`` (``mult``) and of a Python
``PC`` (``apply``), so one class gives TAO both the exact Hessian and the Fourier preconditioner.

The operators hold their multipliers and apply themselves on the arrays of their FFT's
:class:`~petsc_contact.devices.device.Device`: FFTW and NumPy on the ``cpu`` device, the
array module's FFT on ``gpu`` (CuPy) and ``cpu-array``, where no PETSc object is ever made
of them (the package's own solver calls ``apply_array`` and the two halves directly).
"""

from __future__ import annotations

import copy
import warnings
from types import ModuleType
from typing import Any

import numpy as np

from ..conventions.grid import Grid, block_rows
from ..conventions.warnings import user_level
from ..devices.device import CPU, Device
from ..devices.fft import FFT, half_spectrum_weights, make_fft, single_entries
from . import _petsc


def real_multiplier(values: Any, xp: ModuleType = np) -> Any:
    """A real spectral multiplier of its own (C-contiguous float64, one float per complex
    entry of the spectrum block: an array of ``xp``, the array module ``values`` belong to)."""
    return xp.array(xp.real(values), dtype=float, order="C")


class ShellInterface:
    """The petsc4py Python ``Mat`` and ``PC`` methods of an operator with ``apply_array``.

    Subclasses define ``apply_array(x, out)`` on local arrays and ``diagonal()``.
    """

    applications: int
    grid: Grid

    def apply_array(self, x: np.ndarray, out: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def diagonal(self) -> float:
        raise NotImplementedError

    def mult(self, mat: Any, x: Any, y: Any) -> None:
        with y as out:
            self.apply_array(x.array_r, out)

    multTranspose = mult

    def getDiagonal(self, mat: Any, d: Any) -> None:
        d.set(self.diagonal())

    def apply(self, pc: Any, x: Any, y: Any) -> None:
        self.mult(None, x, y)

    applyTranspose = apply


class DiagonalShift(ShellInterface):
    """An operator plus a diagonal that PETSc sets on its shell ``Mat`` (``MatDiagonalSet``).

    TAO's interior-point type ``bqpip`` adds its barrier's diagonal to the Hessian before each
    of its Newton solves and restores the Hessian's own diagonal after it; a shell of
    :class:`SpectralOperator` alone cannot take that.  ``op`` is left unchanged: only the
    ``Mat`` made of this wrapper (:func:`shell_matrix`) applies the shift.
    """

    def __init__(self, op: ShellInterface) -> None:
        self.op, self.grid = op, op.grid
        self.shift: np.ndarray | None = None  # this rank's entries added to the diagonal

    @property
    def applications(self) -> int:  # type: ignore[override]
        return self.op.applications

    def apply_array(self, x: np.ndarray, out: np.ndarray) -> np.ndarray:
        self.op.apply_array(x, out)
        if self.shift is not None:
            out += self.shift * x
        return out

    def diagonal(self) -> float:
        return self.op.diagonal()

    def getDiagonal(self, mat: Any, d: Any) -> None:
        with d as out:
            out[...] = self.op.diagonal() if self.shift is None else self.op.diagonal() + self.shift

    def setDiagonal(self, mat: Any, d: Any, addv: Any) -> None:
        """PETSc's ``MatDiagonalSet``: add ``d`` (``ADD_VALUES``), or make ``d`` the diagonal."""
        values = np.array(d.array_r)
        # petsc4py 3.18 passes whether the mode is ADD_VALUES; older ones the InsertMode
        add = addv if isinstance(addv, bool) else addv == _petsc.petsc().InsertMode.ADD_VALUES
        if add:
            self.shift = values if self.shift is None else self.shift + values
        else:
            self.shift = values - self.op.diagonal()
        if not self.grid.sum(float(np.abs(self.shift).max(initial=0.0)))[0]:
            self.shift = None  # the operator's own diagonal again: no pass


class SpectralOperator(ShellInterface):
    """An FFT round trip with a real multiplier, in two halves.

    :meth:`begin_mult` transforms ``x``, multiplies its spectrum and returns this rank's
    part of ``x.Ax`` (Parseval, in the same pass); :meth:`end_mult` transforms back.  The
    constrained CG uses the halves to learn ``d.Hd`` for its step before deciding whether
    it needs ``Hd`` at all (after a projection it evaluates the gradient afresh instead).
    No other transform on the same FFT may run between the two.  Subclasses define
    :meth:`_forward` and :meth:`_backward`, and hold :attr:`multiplier` (the normalised
    spectrum block, one float per complex entry: :func:`real_multiplier`) and :attr:`fft`.
    """

    fft: FFT
    multiplier: np.ndarray
    factor = 1.0  # the operator is ``factor`` times :attr:`multiplier`'s (see ``times``)
    transform_size: int  # N, the points of the transform: a round trip multiplies by N
    _single: np.ndarray

    def normalised(self, value: Any) -> Any:
        """A physical multiplier (scalar or array) in the units this operator stores: over
        :attr:`transform_size`.  The package's one FFT normalisation convention."""
        return value / self.transform_size

    def inverse_spectrum(self) -> np.ndarray:
        """The normalised spectrum of the inverse operator: ``1/(N a)`` over ``N``."""
        return self.normalised(self.normalised(1.0)) / self.spectrum

    def begin_mult(self, x: np.ndarray) -> float:
        """Transform and multiply ``x`` (local array); return this rank's part of ``x.Ax``."""
        self.applications += 1
        return self.transform(x)

    def transform(self, x: np.ndarray) -> float:
        """:meth:`begin_mult` without counting an application (for objective evaluations)."""
        self._forward(x)
        values = self.fft.spectrum.view(np.float64).reshape(-1)  # a view: spectra are dense
        passes = self.fft.device.passes
        multiplier, factor = self.multiplier.reshape(-1), self.factor
        return float(passes.scale_entries(values, multiplier, self._single, factor))

    def end_mult(self, out: np.ndarray) -> np.ndarray:
        """``out <- A x`` for the ``x`` of the last :meth:`begin_mult`."""
        self._backward(out)
        return out

    def apply_array(self, x: np.ndarray, out: np.ndarray) -> np.ndarray:
        """``out <- A x`` for local arrays."""
        self.begin_mult(x)
        return self.end_mult(out)

    @property
    def spectrum(self) -> np.ndarray:
        """The normalised real multiplier on the local spectrum block (a view: read only; a
        new array where :attr:`factor` is not 1)."""
        values = self.multiplier
        return values if self.factor == 1.0 else values * self.factor

    def _with(self, multiplier: np.ndarray) -> Any:
        """Another operator of this kind on the same FFT, with ``multiplier``."""
        other = copy.copy(self)
        other.multiplier, other.factor = multiplier, 1.0
        other.applications = 0
        return other

    def _weighted_sum(self, grid: Grid) -> float:
        """The multiplier summed over the full spectrum of ``grid`` (the FFT's grid), all ranks:
        the operator's diagonal entry (summed on the device: one scalar comes back)."""
        w = self.fft.device.asarray(half_spectrum_weights(grid, self.fft))
        return float(grid.sum((w * self.spectrum).sum())[0])

    def _forward(self, x: np.ndarray) -> None:
        raise NotImplementedError

    def _backward(self, out: np.ndarray) -> None:
        raise NotImplementedError


class FourierOperator(SpectralOperator):
    """Convolution with a real, even kernel given on the local half-spectrum block.

    Parameters
    ----------
    grid, fft
        Layout and FFT backend.
    kernel
        The multiplier on ``fft.spectrum``'s block (without FFT normalisation), on the host
        or on ``fft``'s device.
    once
        Deprecated and ignored (every multiplier is kept once per entry); until 0.3.0.
    """

    def __init__(self, grid: Grid, fft: FFT, kernel: np.ndarray, once: bool | None = None) -> None:
        if once is not None:
            warnings.warn(
                "FourierOperator's once= is deprecated and ignored: every multiplier is kept "
                "once per entry; it will be removed in 0.3.0",
                DeprecationWarning,
                stacklevel=user_level(),
            )
        self.grid = grid
        self.fft = fft
        self.transform_size = grid.size
        device = fft.device  # the multiplier made where the kernel is moved to, once
        values = self.normalised(device.asarray(kernel, dtype=float))
        self.multiplier = real_multiplier(values, device.xp)
        self._single = fft.device.asarray(single_entries(grid, fft))
        self.applications = 0

    def scaled(self, factor: float) -> FourierOperator:
        """Another operator on the same FFT with the multiplier times ``factor``."""
        return self._with(self.multiplier * (self.factor * factor))

    def times(self, factor: float) -> FourierOperator:
        """Another operator on the same FFT, ``factor`` times this one, that shares its
        multiplier (no field): its :attr:`factor` may be set again in place; the products
        are formed where the spectrum is scaled, the same numbers as a multiplier stored
        scaled."""
        other = self._with(self.multiplier)
        other.factor = self.factor * factor
        return other

    def sharing(self, multiplier: np.ndarray) -> FourierOperator:
        """Another operator on the same FFT whose multiplier is ``multiplier``, an array of
        this one's layout shared (not copied): what it is given it holds."""
        return self._with(multiplier)

    @property
    def input_field(self) -> np.ndarray:
        """Its FFT's input buffer, flat: an application reads it as its input and never
        writes it (:class:`~petsc_contact.solver.linear.ReadsInputFirst`)."""
        return self.fft.real.reshape(-1)

    def set_inverse(self, op: FourierOperator, support: float) -> None:
        """Become the inverse of ``op + support I`` on the same grid, in place.

        ``support`` is in ``op``'s normalised units (kernel over ``N = nx ny``); with it
        the normalised multiplier is ``N^-2/(op.multiplier + support)``, so a zero entry
        of ``op`` gives ``inf`` when ``support`` is 0 (the caller sets that entry).
        """
        np.multiply(op.multiplier, op.factor, out=self.multiplier)  # op's spectrum
        np.add(self.multiplier, support, out=self.multiplier)
        with np.errstate(divide="ignore"):  # 1/(N a) normalised: N^-2 / a
            np.divide(self.normalised(self.normalised(1.0)), self.multiplier, out=self.multiplier)

    def set_entry(self, row: int, column: int, value: float) -> None:
        """Set one entry of the normalised multiplier (local spectrum indices)."""
        self.multiplier[row, column] = value

    def _forward(self, x: np.ndarray) -> None:
        self.fft.forward_from(x)

    def _backward(self, out: np.ndarray) -> None:
        self.fft.backward_into(out)

    def diagonal(self) -> float:
        """The (constant) diagonal entry of the circulant operator."""
        return self._weighted_sum(self.grid)


class PaddedOperator(SpectralOperator):
    """Free-boundary convolution of an ``nx x ny`` field by zero padding to ``2nx x 2ny``.

    Parameters
    ----------
    grid
        The ``nx x ny`` footprint grid (its row slabs are the Vec layout).
    kernel_rows
        ``f(rows) -> array`` giving rows ``rows`` of the real ``2nx x 2ny`` kernel in numpy's
        ``fftfreq`` offset order (e.g. :func:`~petsc_contact.physics.greens.hockney_kernel`).
        It must be even in both offsets, so that its spectrum is real.
    fft
        FFT backend of the padded ``2nx x 2ny`` grid; pass one to share it between operators.
    device
        Where the fields live when no ``fft`` is given: the padded grid's FFT is
        ``device.fft`` (FFTW on the ``cpu`` device, the array module's on the others).  The
        operator's fields, multiplier included, are arrays of the FFT's ``device``; the
        kernel is evaluated on the host and transformed there.

    Notes
    -----
    Under MPI the footprint rows a rank owns and the padded rows it transforms differ;
    rows move with one ``Alltoallv`` each way (:class:`RowExchange`).
    """

    def __init__(
        self, grid: Grid, kernel_rows: Any, fft: FFT | None = None, device: Device = CPU
    ) -> None:
        self.grid = grid
        self.padded = grid.padded()
        self.fft = fft if fft is not None else make_fft(self.padded, device)
        where = self.fft.device
        self.fft.real[...] = where.asarray(kernel_rows(self.padded.rows))
        self.fft.forward()
        self.transform_size = self.padded.size
        self.multiplier = real_multiplier(self.normalised(self.fft.spectrum.real), where.xp)
        self._single = where.asarray(single_entries(self.padded, self.fft))
        self._centre = float(kernel_rows(slice(0, 1))[0, 0])
        self.exchange = RowExchange(grid.comm, grid.shape, self.padded.shape[0])
        self.applications = 0
        self.fft.real[...] = 0.0  # the padding stays zero: applications write only the block

    @property
    def device(self) -> Device:
        """Where the operator's fields live (its FFT's device)."""
        return self.fft.device

    def with_spectrum(self, spectrum: Any) -> PaddedOperator:
        """Another operator on the same padded FFT with the given (normalised) spectrum."""
        other = self._with(real_multiplier(spectrum, self.fft.device.xp))
        other._centre = other._weighted_sum(self.padded)
        return other

    def _forward(self, x: np.ndarray) -> None:
        """Pad ``x`` (``P x``) and transform it."""
        ny = self.grid.shape[1]
        self.exchange.to_padded(x.reshape(self.grid.local_shape), self.fft.real[:, :ny])
        self.fft.forward()

    def _backward(self, out: np.ndarray) -> None:
        """Transform back and keep the footprint block (``P^T``)."""
        self.fft.backward()
        ny = self.grid.shape[1]
        self.exchange.to_footprint(self.fft.result[:, :ny], out.reshape(self.grid.local_shape))

    def diagonal(self) -> float:
        """The constant diagonal entry (the kernel at zero offset)."""
        return self._centre


class RowExchange:
    """Move the footprint's ``nx`` rows (``ny`` values each) between the ``nx``-row and
    ``m``-row slab layouts of a comm.

    Row ``i`` of the footprint is row ``i`` of the padded grid; each rank owns
    :func:`~petsc_contact.conventions.grid.block_rows` of both.  With one rank this is a copy.
    """

    def __init__(self, comm: Any, shape: tuple[int, int], m: int) -> None:
        self.comm = comm
        size = comm.size
        n, width = shape
        mine_f = block_rows(n, size, comm.rank)
        mine_p = block_rows(m, size, comm.rank)

        def overlap(a: slice, b: slice) -> int:
            return max(0, min(a.stop, b.stop, n) - max(a.start, b.start))

        self.send = [overlap(mine_f, block_rows(m, size, q)) * width for q in range(size)]
        self.recv = [overlap(block_rows(n, size, q), mine_p) * width for q in range(size)]
        self.rows_in = sum(self.recv) // width  # footprint rows present in my padded slab
        self._padded_rows = np.empty((self.rows_in, width))  # reused by every exchange
        self._footprint_rows = np.empty((mine_f.stop - mine_f.start, width))

    def to_padded(self, footprint: np.ndarray, padded: np.ndarray) -> None:
        """Write my footprint rows into the padded slabs (``padded`` is my ``[:, :ny]`` view)."""
        if self.comm.size == 1:
            padded[: footprint.shape[0]] = footprint
            return
        buf = self._padded_rows
        self.comm.Alltoallv([np.ascontiguousarray(footprint), self.send], [buf, self.recv])
        padded[: self.rows_in] = buf

    def to_footprint(self, padded: np.ndarray, footprint: np.ndarray) -> None:
        """Read my footprint rows back from the padded slabs."""
        if self.comm.size == 1:
            footprint[...] = padded[: footprint.shape[0]]
            return
        buf = self._padded_rows
        buf[...] = padded[: self.rows_in]
        self.comm.Alltoallv([buf, self.recv], [self._footprint_rows, self.send])
        footprint[...] = self._footprint_rows


def shell_matrix(petsc: Any, op: ShellInterface) -> Any:
    """A PETSc Python ``Mat`` of the grid's row-slab layout whose ``mult`` is ``op``."""
    n_local = op.grid.local_shape[0] * op.grid.shape[1]
    mat = petsc.Mat().createPython(
        ((n_local, op.grid.size), (n_local, op.grid.size)),
        context=op,
        comm=_petsc.petsc_comm(op.grid.comm),
    )
    mat.setOption(petsc.Mat.Option.SYMMETRIC, True)
    mat.setUp()
    return mat
