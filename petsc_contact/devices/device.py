"""Where a solve's arrays live: one small :class:`Device` value chosen once per run.

A device is an array module (NumPy or CuPy), the element-wise passes of the solvers written
for it (:class:`~petsc_contact.devices.passes.ArrayPasses`, CuPy's fused kernels, or the
numba passes of :mod:`~petsc_contact.devices.compiled` on the PETSc path) and the transfers to
and from the host; its FFT engine is :func:`~petsc_contact.devices.fft.make_fft`'s.  The
algorithms of :mod:`petsc_contact.solver` and the operators of the geometries take their
arrays, passes and transforms from it and never import CuPy themselves.

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

from .fused import FusedPasses
from .passes import ArrayPasses

DEVICES = ("cpu", "gpu", "cpu-array")
ARRAY_DEVICES = ("gpu", "cpu-array")  # the devices of the array path (no PETSc)


class DeviceUnavailable(RuntimeError):
    """The device asked for cannot be used here (no CuPy, no GPU): one line says why."""


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
        (:mod:`~petsc_contact.devices.compiled`), CuPy's fused kernels on the ``gpu``
        (:class:`~petsc_contact.devices.fused.FusedPasses`), :class:`ArrayPasses` on the
        stand-in (numba is loaded when a ``cpu`` run first asks, not when a command is
        parsed)."""
        if self.compiled:
            from . import compiled

            return compiled
        if not self.on_host:
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

    def describe(self) -> dict[str, str | int]:
        """What the output records of the device: its name, and the GPU's model and memory."""
        out: dict[str, str | int] = {"device": self.name}
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
