"""Where a solve's arrays live: one small :class:`Device` value chosen once per run.

A device is an array module (NumPy or CuPy), the element-wise passes of the solvers written
for it (:class:`ArrayPasses`, or the numba passes of :mod:`~petsc_contact.numerics.kernels`
on the PETSc path), an FFT engine for its arrays (:class:`ArrayFFT`) and the transfers to and
from the host.  The algorithms of :mod:`petsc_contact.solver` and the operators of the
geometries take their arrays, passes and transforms from it and never import CuPy themselves.

Three devices (``--device``, ``Run(device=...)``):

- ``cpu``: NumPy arrays in PETSc Vecs, FFTW, the numba passes; every TAO type (the default);
- ``gpu``: CuPy arrays on the current CUDA device, ``cupy.fft`` with its plan cache;
- ``cpu-array``: the very code the GPU runs, on NumPy arrays (``numpy.fft`` on one rank,
  FFTW's MPI transforms on several): a stand-in that lets every machine test the GPU path's
  logic.

``gpu`` and ``cpu-array`` run the package's own solver without petsc4py; ``cpu-array`` on any
number of MPI ranks, ``gpu`` on one.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from types import ModuleType
from typing import Any

import numpy as np

from ..conventions.grid import Grid

DEVICES = ("cpu", "gpu", "cpu-array")
ARRAY_DEVICES = ("gpu", "cpu-array")  # the devices of the array path (no PETSc)


class DeviceUnavailable(RuntimeError):
    """The device asked for cannot be used here (no CuPy, no GPU): one line says why."""


class ArrayPasses:
    """The element-wise passes of the constrained CG and the spectral operators, written
    once for any array module ``xp`` with NumPy's interface (NumPy or CuPy).

    The same contracts as the numba passes of :mod:`~petsc_contact.numerics.kernels`
    (which the PETSc path uses): bounds are a float or an array of the vector's length;
    every reduction is returned as a Python number (one host synchronisation on a GPU).
    """

    def __init__(self, xp: ModuleType) -> None:
        self.xp = xp

    def free_set(
        self, x: Any, g: Any, lower: Any, upper: Any, free: Any, r: Any
    ) -> tuple[float, int, int, int]:
        """``free <- (x > lower | g < 0) & ~(x >= upper & g < 0)``, ``r <- g`` on it;
        returns ``(r.r, changed, joined, free count)``."""
        xp = self.xp
        pull = g < 0.0
        now = ((x > lower) | pull) & ~((x >= upper) & pull)
        changed = int(xp.count_nonzero(now != free))
        joined = int(xp.count_nonzero(now & ~free))
        free[...] = now
        xp.multiply(g, now, out=r)
        return float(xp.dot(r, r)), changed, joined, int(xp.count_nonzero(now))

    def restrict_dot(self, z: Any, free: Any, r: Any) -> float:
        """``z <- z`` on the free set, ``0`` elsewhere; returns ``r.z``."""
        self.xp.multiply(z, free, out=z)
        return float(self.xp.dot(r, z))

    def restrict(self, out: Any, x: Any, free: Any) -> None:
        """``out <- x`` on the free set, ``0`` elsewhere (``out`` may be ``x``)."""
        self.xp.multiply(x, free, out=out)

    def fill_outside(self, out: Any, x: Any, inside: Any) -> None:
        """``out <- x`` off ``inside`` (``out`` kept on it)."""
        self.xp.copyto(out, x, where=~inside)

    def extend_direction(self, z: Any, d: Any, free: Any, beta: float, r: Any) -> float:
        """``z <- z + beta d`` with ``d`` restricted to the free set; returns ``r.z``."""
        z += beta * (d * free)
        return float(self.xp.dot(r, z))

    def advance(self, x: Any, d: Any, alpha: float, lower: Any, upper: Any) -> tuple[int, int]:
        """``x <- x + alpha d``; how many entries fell below ``lower`` and rose above ``upper``."""
        xp = self.xp
        self.axpy(alpha, d, x)
        return int(xp.count_nonzero(x < lower)), int(xp.count_nonzero(x > upper))

    def clip(self, x: Any, lower: Any, upper: Any) -> None:
        """``x <- min(max(x, lower), upper)``."""
        xp = self.xp
        xp.maximum(x, lower, out=x)
        xp.minimum(x, upper, out=x)

    def axpy(self, a: float, x: Any, y: Any) -> None:
        """``y <- y + a x``."""
        y += a * x

    def scale_spectrum(self, values: Any, multiplier: Any, single: Any) -> float:
        """Multiply a spectrum's float view by a real multiplier (each entry twice); return
        ``sum(w k |s|^2)`` before it (``w = 1`` on ``single``, 2 elsewhere; Parseval)."""
        xp = self.xp
        re, im = values[2 * single], values[2 * single + 1]
        once = xp.dot(multiplier[2 * single], re * re + im * im)
        total = xp.dot(multiplier, values * values)
        values *= multiplier
        return float(2.0 * total - once)

    def add_dot(self, y: Any, base: Any, d: Any) -> float:
        """``y <- y + base``; returns ``d.base``."""
        y += base
        return float(self.xp.dot(d, base))

    def changed_count(self, before: Any, now: Any) -> int:
        """How many entries of two boolean masks differ."""
        return int(self.xp.count_nonzero(before != now))


class ArrayFFT:
    """Real-to-complex 2-D FFTs of one grid with the array module's ``fft`` (one rank: a
    GPU's arrays on several are not supported yet).

    The interface of :mod:`~petsc_contact.numerics.fft`'s engines: buffers ``real`` (kept by
    :meth:`forward`), ``spectrum`` and ``result``; both transforms unnormalised, so
    ``backward(forward(x)) = nx ny x``.  CuPy keeps the cuFFT plans of a shape in its plan
    cache, so every transform after the first reuses them.
    """

    transposed = False

    def __init__(self, grid: Grid, device: Device) -> None:
        if grid.comm.size != 1:
            raise ValueError(f"the {device.name} device runs on one MPI rank, not {grid.comm.size}")
        xp = device.xp
        self.device = device
        self.shape = grid.shape
        nx, m = grid.shape[0], grid.half
        self.real = xp.zeros(grid.shape)
        self.spectrum = xp.zeros((nx, m), dtype=complex)
        self.result = xp.zeros(grid.shape)
        self.spectral_index = (slice(0, nx), slice(0, m))

    def forward(self) -> None:
        """``spectrum <- FFT(real)``."""
        self.forward_from(self.real)

    def backward(self) -> None:
        """``result <- IFFT(spectrum)`` without the ``1/(nx ny)``."""
        self.backward_into(self.result)

    def forward_from(self, x: Any) -> None:
        """``spectrum <- FFT(x)`` for an array of the grid's size."""
        self.spectrum[...] = self.device.xp.fft.rfft2(x.reshape(self.shape))

    def backward_into(self, out: Any) -> None:
        """``out <- IFFT(spectrum)`` (unnormalised)."""
        fft = self.device.xp.fft
        out.reshape(self.shape)[...] = fft.irfft2(self.spectrum, s=self.shape, norm="forward")


@dataclass(frozen=True)
class Device:
    """An array module with its passes, its FFT engine and its host transfers.

    Attributes
    ----------
    name
        ``cpu``, ``gpu`` or ``cpu-array`` (module docstring).
    xp
        The array module: ``numpy`` or ``cupy``.
    compiled
        Whether its whole-field passes are numba's and its transforms FFTW's (NumPy
        arrays): the ``cpu`` device; the others run the array module's own.
    """

    name: str
    xp: ModuleType
    compiled: bool = False

    @cached_property
    def passes(self) -> Any:
        """The element-wise passes: numba's on the ``cpu`` device
        (:mod:`~petsc_contact.numerics.kernels`), CuPy's fused kernels on the ``gpu``
        (:class:`~petsc_contact.numerics.fused.FusedPasses`), :class:`ArrayPasses` on the
        stand-in."""
        if self.compiled:
            from . import kernels

            return kernels
        if not self.on_host:
            from .fused import FusedPasses

            return FusedPasses(self.xp)
        return ArrayPasses(self.xp)

    @property
    def on_host(self) -> bool:
        """Whether the arrays are NumPy's (no transfers)."""
        return self.xp is np

    def asarray(self, values: Any, dtype: Any = None) -> Any:
        """``values`` as an array of this device (no copy where it already is one)."""
        return self.xp.asarray(values, dtype=dtype)

    def to_host(self, values: Any) -> np.ndarray:
        """A NumPy array of ``values`` (a copy from the device; the array itself on the host)."""
        if self.on_host:
            return np.asarray(values)
        return self.xp.asnumpy(values)

    def synchronize(self) -> None:
        """Wait for the device's queued work (before a timer is read)."""
        if not self.on_host:
            self.xp.cuda.get_current_stream().synchronize()

    def cho_factor(self, matrix: Any) -> tuple[Any, bool] | None:
        """The Cholesky factor of a symmetric ``E`` (an array of this device) as SciPy's
        ``cho_factor`` pair ``(c, lower)``, on this device; ``None`` where ``E`` is not
        positive definite.  On the host SciPy's upper factor (only ``E``'s upper triangle is
        read), in ``E``'s memory if it is in Fortran order (else in a copy); on a GPU
        cuSOLVER's lower one (its lower triangle is read)."""
        if self.on_host:
            from scipy.linalg import LinAlgError, cho_factor

            try:
                return cho_factor(matrix, lower=False, overwrite_a=True, check_finite=False)
            except LinAlgError:
                return None
        import cupyx

        try:
            with cupyx.errstate(linalg="raise"):  # CuPy ignores a failed potrf by default
                lower = self.xp.linalg.cholesky(matrix)  # C order
        except np.linalg.LinAlgError:
            return None
        return lower.T, False  # the upper factor in Fortran order: solved without a copy

    def cho_solve(self, factor: tuple[Any, bool], b: Any) -> Any:
        """``E^-1 b`` from the ``cho_factor`` pair of ``E`` (its factor on this device,
        :meth:`cho_factor`)."""
        if self.on_host:
            from scipy.linalg import cho_solve

            return cho_solve(factor, b, check_finite=False)
        from cupyx.scipy.linalg import solve_triangular

        c, lower = factor  # c^T c = E (upper) or c c^T = E (lower); the other half is junk
        first, second = ("N", "T") if lower else ("T", "N")
        t = solve_triangular(c, b, trans=first, lower=lower)
        return solve_triangular(c, t, trans=second, lower=lower)

    def label(self, mask: Any) -> tuple[Any, int]:
        """The 4-connected clusters of a boolean mask of this device: its labels (0 off the
        mask, an array of this device) and their number (SciPy's or CuPy's ``ndimage.label``)."""
        if self.on_host:
            from scipy import ndimage
        else:
            from cupyx.scipy import ndimage
        labels, count = ndimage.label(mask)
        return labels, int(count)

    def fft(self, grid: Grid) -> Any:
        """The FFT engine of ``grid`` on this device: FFTW's (:func:`~petsc_contact.numerics.
        fft.make_fft`) on the ``cpu`` device, and for host arrays on several ranks (its MPI
        transforms, this device's passes on them); the array module's (:class:`ArrayFFT`,
        one rank) otherwise."""
        if self.compiled or (self.on_host and grid.comm.size > 1):
            from .fft import make_fft

            return make_fft(grid, self)
        return ArrayFFT(grid, self)

    def describe(self) -> dict[str, Any]:
        """What the output records of the device: its name, and the GPU's model and memory."""
        out: dict[str, Any] = {"device": self.name}
        if not self.on_host:
            cuda = self.xp.cuda
            props = cuda.runtime.getDeviceProperties(cuda.Device().id)
            name = props["name"]
            out["device_name"] = name.decode() if isinstance(name, bytes) else str(name)
            out["device_memory"] = int(props["totalGlobalMem"])
        return out


CPU = Device("cpu", np, compiled=True)  # NumPy with numba's passes and FFTW


def get_device(name: str = "cpu") -> Device:
    """The device called ``name`` (:data:`DEVICES`).

    Raises
    ------
    ValueError
        For a name that is none of them.
    DeviceUnavailable
        For ``gpu`` where CuPy cannot be imported or sees no CUDA device.
    """
    if name == "cpu":
        return CPU
    if name == "cpu-array":
        return Device("cpu-array", np)
    if name != "gpu":
        raise ValueError(f"unknown device '{name}': choose one of {', '.join(DEVICES)}")
    try:
        import cupy
    except ImportError as error:
        raise DeviceUnavailable(
            f"--device gpu needs CuPy ({error}): pip install 'petsc-contact[gpu]' (docs/gpu.md)"
        ) from None
    try:
        count = cupy.cuda.runtime.getDeviceCount()
    except Exception as error:  # CUDA's errors differ by driver and runtime
        raise DeviceUnavailable(f"--device gpu: CUDA reports no usable GPU ({error})") from None
    if count < 1:
        raise DeviceUnavailable("--device gpu: no CUDA GPU on this machine")
    return Device("gpu", cupy)
