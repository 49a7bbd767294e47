"""Real-to-complex 2-D FFTs on the row-slab layout, planned once and reused.

One interface, four backends chosen by the device and the communicator size
(:func:`make_fft`):

- one rank: FFTW through Debian's ``pyfftw``, measured plan, one thread per core (faster
  than scipy's and numpy's FFTs; docs/performance.md);
- several ranks: FFTW's own MPI transforms (``libfftw3_mpi``, the library PETSc's MATFFTW
  uses, called through ctypes) with the spectrum in transposed order, which skips one global
  transpose per direction and keeps every local transform contiguous (faster than
  mpi4py-fft; docs/parallel.md);
- several ranks whose row slabs are not FFTW's (FFTW gives every rank ``ceil(nx/P)`` rows but
  the last; :func:`~petsc_contact.conventions.grid.block_rows` spreads the remainder, e.g.
  22/21/21 rows
  for n = 64 on 3 ranks), or without ``libfftw3_mpi``: the slab-decomposed parallel FFT of
  Debian's ``mpi4py-fft`` (FFTW underneath);
- a device of the array path (``gpu``, ``cpu-array``) on one rank: the array module's own
  transforms (:class:`ArrayFFT`: ``numpy.fft``, or cuFFT through ``cupy.fft``).

A backend's ``transposed`` attribute says how its spectrum block is stored: ``False`` for
(rows ``qx``, columns ``qy``), ``True`` for (``qy``, ``qx``).  Spectral multipliers built
with :func:`wavevectors` follow it; ``spectral_index`` is always (``qx`` range, ``qy`` range).

Each backend owns three buffers: ``real`` (input of :meth:`forward`, never modified by
either transform), ``spectrum`` (its output, the local block of the ``nx x (ny//2+1)`` half
spectrum) and ``result`` (output of :meth:`backward`; the serial backend makes it when first
asked for: the operators transform back into their callers' arrays, so a periodic run never
does).  Both transforms are unnormalised: ``backward(forward(x)) = nx ny x``.

:meth:`forward_from` and :meth:`backward_into` are the hot path of every operator (one round
trip with a spectral multiplier between them, :mod:`petsc_contact.backend.operator`).  The serial
backend runs FFTW directly on the caller's arrays when they are as aligned as its plans
(PETSc's Vec arrays are: 16 bytes), which saves two copies of the field per application;
otherwise it copies.
"""

from __future__ import annotations

import ctypes
import os
import platform
from types import ModuleType
from typing import Any

import numpy as np

from ..conventions.grid import Grid, fft_order
from .device import CPU, Device

PLANNER_EFFORT = "FFTW_MEASURE"
WISDOM_VARIABLE = "PETSC_CONTACT_FFTW_WISDOM"  # a file for FFTW's wisdom, or "off"
THREADS_VARIABLE = "PETSC_CONTACT_FFT_THREADS"  # the serial FFT's threads (default: the cores)


def default_threads() -> int:
    """FFT threads for a one-rank run: ``PETSC_CONTACT_FFT_THREADS`` where it is set (say 1
    for several runs side by side on one machine's cores, each then a core's), else the
    cores this process may use.  ``ValueError`` for a value that is not a positive whole
    number."""
    given = os.environ.get(THREADS_VARIABLE, "").strip()
    if not given:
        return max(1, len(os.sched_getaffinity(0)))
    if not given.isdigit() or int(given) < 1:
        raise ValueError(f"{THREADS_VARIABLE}={given!r}: the FFT's threads, a whole number >= 1")
    return int(given)


class _Wisdom:
    """FFTW's measured plans kept on disk between runs (the serial backend's).

    Measuring plans for a large grid takes seconds; with the wisdom of an earlier run
    FFTW plans at once, and every run of a machine uses the same plans (so the same
    rounding, and the same iteration counts).  The file is
    ``$XDG_CACHE_HOME/petsc-contact/fftw-wisdom-HOST`` (``~/.cache`` by default), or the path
    in ``PETSC_CONTACT_FFTW_WISDOM``; ``PETSC_CONTACT_FFTW_WISDOM=off`` measures afresh in
    every run.  A file FFTW cannot read is ignored and replaced.
    """

    loaded = False

    @staticmethod
    def path() -> str | None:
        value = os.environ.get(WISDOM_VARIABLE, "")
        if value == "off":
            return None
        if value:
            return value
        cache = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        return os.path.join(cache, "petsc-contact", f"fftw-wisdom-{platform.node()}")

    @classmethod
    def load(cls, pyfftw: Any) -> None:
        """Import the file's wisdom, once per process."""
        path = cls.path()
        if cls.loaded or path is None:
            return
        cls.loaded = True
        try:
            with open(path, "rb") as f:
                parts = tuple(f.read().split(b"\0"))
        except OSError:
            return  # no file yet: plans are measured
        if len(parts) == 3:  # double, single, long double; FFTW rejects what it cannot read
            pyfftw.import_wisdom(parts)

    @classmethod
    def save(cls, pyfftw: Any) -> None:
        """Write the process's wisdom back (atomically; a failure only costs planning time)."""
        path = cls.path()
        if path is None:
            return
        try:
            os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
            temporary = f"{path}.{os.getpid()}"
            with open(temporary, "wb") as f:
                f.write(b"\0".join(pyfftw.export_wisdom()))  # FFTW's wisdom is text
            os.replace(temporary, path)
        except OSError:
            pass


class SerialFFT:
    """FFTW (pyfftw) on the whole grid, for one MPI rank (plans kept by :class:`_Wisdom`)."""

    def __init__(self, grid: Grid, threads: int | None = None) -> None:
        import pyfftw

        _Wisdom.load(pyfftw)
        known = pyfftw.export_wisdom()
        nx, m = grid.shape[0], grid.half
        threads = threads or default_threads()
        self.threads = threads
        self.real = pyfftw.empty_aligned(grid.shape, dtype="float64")
        self.spectrum = pyfftw.empty_aligned((nx, m), dtype="complex128")
        self._result: np.ndarray | None = None  # made when first asked for (:attr:`result`)
        self._forward = pyfftw.FFTW(
            self.real, self.spectrum, axes=(0, 1), flags=(PLANNER_EFFORT,), threads=threads
        )
        self._backward = pyfftw.FFTW(  # planned on ``real`` (as aligned as ``result``)
            self.spectrum,
            self.real,
            axes=(0, 1),
            direction="FFTW_BACKWARD",
            flags=(PLANNER_EFFORT, "FFTW_DESTROY_INPUT"),
            threads=threads,
        )
        if pyfftw.export_wisdom() != known:  # new plans were measured
            _Wisdom.save(pyfftw)
        self.spectral_index = (slice(0, nx), slice(0, m))

    transposed = False
    device = CPU

    @property
    def result(self) -> np.ndarray:
        """The output of :meth:`backward`, made at its first use: the operators transform
        back into their callers' arrays, so a periodic run never makes it (a field less)."""
        if self._result is None:
            import pyfftw

            self._result = pyfftw.empty_aligned(self.real.shape, dtype="float64")
        return self._result

    def forward(self) -> None:
        """``spectrum <- FFT(real)``."""
        self._forward.execute()

    def backward(self) -> None:
        """``result <- IFFT(spectrum)`` without the ``1/(nx ny)``; destroys ``spectrum``."""
        self._backward.update_arrays(self.spectrum, self.result)
        self._backward.execute()

    def forward_from(self, x: np.ndarray) -> None:
        """``spectrum <- FFT(x)`` for a local array of the grid's size.

        ``x`` is read in place when it is contiguous and as aligned as the plan (PETSc's Vec
        arrays are); ``real`` is then left untouched.
        """
        src = x.reshape(self.real.shape)
        if self._direct(src, self._forward.input_alignment):
            self._forward.update_arrays(src, self.spectrum)
            self._forward.execute()
            self._forward.update_arrays(self.real, self.spectrum)
        else:
            self.real[...] = src
            self._forward.execute()

    def backward_into(self, out: np.ndarray) -> None:
        """``out <- IFFT(spectrum)`` (unnormalised, destroys ``spectrum``), in place if aligned.

        The plan is pointed back at ``real`` after, as :meth:`forward_from` does: a plan holds
        its arrays, and ``out`` must not outlive its caller's use of it (the pressure of a
        step's observables had stayed alive through the stiffness solve, a field more)."""
        dst = out.reshape(self.real.shape)
        if self._direct(dst, self._backward.output_alignment):
            self._backward.update_arrays(self.spectrum, dst)
            self._backward.execute()
            self._backward.update_arrays(self.spectrum, self.real)
        else:
            self.backward()
            dst[...] = self.result

    @staticmethod
    def _direct(a: np.ndarray, alignment: int) -> bool:
        return a.flags.c_contiguous and a.ctypes.data % alignment == 0


class SlabFFT:
    """mpi4py-fft slab decomposition: rows in real space, half-spectrum columns in Fourier space."""

    def __init__(self, grid: Grid) -> None:
        from mpi4py_fft import PFFT

        self._pfft = PFFT(
            grid.comm,
            grid.shape,
            axes=(0, 1),
            dtype=np.float64,
            grid=(-1,),
            planner_effort=PLANNER_EFFORT,
        )
        if self._pfft.local_slice(False)[0] != grid.rows:
            raise RuntimeError("mpi4py-fft row distribution differs from the grid's")
        # mpi4py-fft's backward transform works in forward.input_array, so ``real`` is a
        # separate buffer that no transform touches (as with the serial backend).
        self.real = np.zeros_like(self._pfft.forward.input_array)
        self.spectrum = self._pfft.forward.output_array
        self.result = np.empty_like(self.real)
        self.spectral_index = tuple(self._pfft.local_slice(True))

    transposed = False
    device = CPU

    def forward(self) -> None:
        self._pfft.forward(self.real, self.spectrum, normalize=False)

    def backward(self) -> None:
        self._pfft.backward(self.spectrum, self.result, normalize=False)

    def forward_from(self, x: np.ndarray) -> None:
        """``spectrum <- FFT(x)`` for a local array of the slab's size (through ``real``)."""
        self.real[...] = x.reshape(self.real.shape)
        self.forward()

    def backward_into(self, out: np.ndarray) -> None:
        """``out <- IFFT(spectrum)`` (unnormalised, through ``result``)."""
        self.backward()
        out.reshape(self.result.shape)[...] = self.result


_FFTW_MPI_TRANSPOSED_IN = 1 << 29  # fftw3-mpi.h
_FFTW_MPI_TRANSPOSED_OUT = 1 << 30
_FFTW_MEASURE = 0


class _FFTWMPILibrary:
    """``libfftw3_mpi`` through ctypes, initialised once per process (``None`` if absent)."""

    _lib: Any = None

    @classmethod
    def get(cls) -> Any:
        if cls._lib is None:
            try:
                lib = ctypes.CDLL("libfftw3_mpi.so.3")
            except OSError:
                cls._lib = False
                return None
            size_t = ctypes.c_ssize_t
            lib.fftw_mpi_local_size_many_transposed.restype = size_t
            # rank, n[], howmany, two block sizes and a pointer open both signatures
            head: list[Any] = [
                ctypes.c_int,
                ctypes.POINTER(size_t),
                size_t,
                size_t,
                size_t,
                ctypes.c_void_p,
            ]
            local_size = lib.fftw_mpi_local_size_many_transposed
            local_size.argtypes = [*head, *[ctypes.POINTER(size_t)] * 4]
            for name in ("fftw_mpi_plan_many_dft_r2c", "fftw_mpi_plan_many_dft_c2r"):
                fn = getattr(lib, name)
                fn.restype = ctypes.c_void_p
                fn.argtypes = [*head, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_uint]
            lib.fftw_execute.argtypes = [ctypes.c_void_p]
            lib.fftw_mpi_init()
            cls._lib = lib
        return cls._lib or None


class _FFTWMPIPlans:
    """FFTW-MPI's in-place buffer and its two transposed-order plans for one grid and comm.

    Made once per communicator and grid size and kept for the life of the process:
    destroying an FFTW-MPI plan after mpi4py-fft had planned in the same process crashed
    in ``fftw_destroy_plan`` in 8 of 16 runs here.  Every user runs forward, multiply and
    backward with no other transform in between (the CG's split Hessian application drops
    the backward instead), so the buffer can be shared.
    """

    _made: dict[tuple[int, tuple[int, int]], _FFTWMPIPlans | None] = {}

    def __init__(
        self, grid: Grid, lib: Any, block0: int, block1: int, local: list[int], alloc: int
    ) -> None:
        from mpi4py import MPI

        (nx, ny), m = grid.shape, grid.half
        rows, _, n_cols, col_start = local
        self.lib = lib
        self._buffer = _aligned(2 * alloc, np.float64)
        self.padded = self._buffer[: rows * 2 * m].reshape(rows, 2 * m)[:, :ny]
        self.spectrum = self._buffer.view(np.complex128)[: n_cols * nx].reshape(n_cols, nx)
        self.spectral_index = (slice(0, nx), slice(col_start, col_start + n_cols))
        dims = (ctypes.c_ssize_t * 2)(nx, ny)
        comm = ctypes.c_void_p(MPI._handleof(grid.comm))
        data = self._buffer.ctypes.data
        self.forward = lib.fftw_mpi_plan_many_dft_r2c(
            2, dims, 1, block0, block1, data, data, comm, _FFTW_MEASURE | _FFTW_MPI_TRANSPOSED_OUT
        )
        self.backward = lib.fftw_mpi_plan_many_dft_c2r(
            2, dims, 1, block1, block0, data, data, comm, _FFTW_MEASURE | _FFTW_MPI_TRANSPOSED_IN
        )
        self.ok = bool(self.forward and self.backward)

    @classmethod
    def get(cls, grid: Grid) -> _FFTWMPIPlans | None:
        """The plans for ``grid``; ``None`` without FFTW-MPI or if its rows are not the grid's."""
        from mpi4py import MPI

        key = (MPI._handleof(grid.comm), grid.shape)
        if key not in cls._made:
            cls._made[key] = cls._make(grid)
        return cls._made[key]

    @classmethod
    def _make(cls, grid: Grid) -> _FFTWMPIPlans | None:
        from mpi4py import MPI

        lib = _FFTWMPILibrary.get()
        if lib is None:
            return None
        nx, m = grid.shape[0], grid.half
        block0 = block1 = 0  # FFTW_MPI_DEFAULT_BLOCK: ceil(nx/P) rows, ceil(m/P) columns
        local = [ctypes.c_ssize_t() for _ in range(4)]
        alloc = lib.fftw_mpi_local_size_many_transposed(
            2,
            (ctypes.c_ssize_t * 2)(nx, m),
            1,
            block0,
            block1,
            MPI._handleof(grid.comm),
            *map(ctypes.byref, local),
        )
        rows, row_start = local[0].value, local[1].value
        if not grid.comm.allreduce(grid.rows == slice(row_start, row_start + rows), op=MPI.LAND):
            return None
        plans = cls(grid, lib, block0, block1, [v.value for v in local], max(alloc, 1))
        return plans if grid.comm.allreduce(plans.ok, op=MPI.LAND) else None


class FFTWMPI:
    """FFTW-MPI slab transforms with the spectrum in transposed order (``transposed = True``).

    Real space: this rank's rows of the grid, ``ceil(nx/P)`` per rank (FFTW's distribution).
    Fourier space: this rank's ``qy`` columns of the half spectrum, each holding all ``nx``
    values of ``qx`` contiguously.  FFTW's real arrays are padded to ``2 (ny//2 + 1)`` per
    row, so ``real`` and ``result`` are this object's own dense arrays, copied in and out;
    the plans and ``spectrum`` are shared by all objects of the same grid
    (:class:`_FFTWMPIPlans`).  Use :meth:`create`, which returns ``None`` when FFTW-MPI
    cannot serve the grid.
    """

    transposed = True
    device = CPU

    def __init__(self, plans: _FFTWMPIPlans) -> None:
        self._plans = plans
        self._execute = plans.lib.fftw_execute
        self.spectrum = plans.spectrum
        self.spectral_index = plans.spectral_index
        self.real = np.zeros(plans.padded.shape)
        self.result = np.zeros(plans.padded.shape)

    @classmethod
    def create(cls, grid: Grid) -> FFTWMPI | None:
        """The backend for ``grid``, or ``None`` without FFTW-MPI or if its rows differ."""
        plans = _FFTWMPIPlans.get(grid)
        return cls(plans) if plans is not None else None

    def forward(self) -> None:
        """``spectrum <- FFT(real)`` (``real`` is kept)."""
        self.forward_from(self.real)

    def backward(self) -> None:
        """``result <- IFFT(spectrum)`` without the ``1/(nx ny)``; destroys ``spectrum``."""
        self.backward_into(self.result)

    def forward_from(self, x: np.ndarray) -> None:
        """``spectrum <- FFT(x)`` for a local array of the slab's size (through FFTW's rows)."""
        self._plans.padded[...] = x.reshape(self.real.shape)
        self._execute(self._plans.forward)

    def backward_into(self, out: np.ndarray) -> None:
        """``out <- IFFT(spectrum)`` (unnormalised, destroys ``spectrum``)."""
        self._execute(self._plans.backward)
        out.reshape(self.result.shape)[...] = self._plans.padded


CUFFT_PLANS_VARIABLE = "PETSC_CONTACT_CUFFT_PLANS"  # "on": the GPU's own cuFFT plans


class ArrayModuleTransforms:
    """The array module's ``rfft2`` and ``irfft2`` written into given buffers: the stand-in's
    transforms (NumPy), and the GPU's unless :class:`CuFFTPlans` are asked for (CuPy, whose
    plan cache keeps a plan per shape; each call allocates its output, which is then copied,
    and copies the spectrum before the inverse, cuFFT's C2R overwriting its input)."""

    def __init__(self, xp: ModuleType, shape: tuple[int, int]) -> None:
        self.fft, self.shape = xp.fft, shape

    def forward(self, real: Any, spectrum: Any) -> None:
        """``spectrum <- FFT(real)``."""
        spectrum[...] = self.fft.rfft2(real)

    def backward(self, spectrum: Any, real: Any) -> None:
        """``real <- IFFT(spectrum)`` without the ``1/(nx ny)`` (``norm="forward"``)."""
        real[...] = self.fft.irfft2(spectrum, s=self.shape, norm="forward")


class CuFFTPlans:
    """cuFFT's plans of one grid, made once by CuPy (``cupyx.scipy.fft.get_fft_plan``, each
    with its work area) and run on the caller's buffers (``PlanNd.fft``): no output is
    allocated, nothing copied, and no ``1/N`` pass (the operators' multipliers hold it).  The
    inverse (C2R) overwrites the spectrum, as FFTW's does on the ``cpu`` device.  Used on a
    GPU when ``PETSC_CONTACT_CUFFT_PLANS=on`` (prepared, not yet measured: docs/gpu.md)."""

    def __init__(self, real: Any, spectrum: Any) -> None:
        from cupy.cuda import cufft
        from cupyx.scipy.fft import get_fft_plan

        shape, axes = real.shape, (0, 1)
        self._forward = get_fft_plan(real, shape=shape, axes=axes, value_type="R2C")
        self._backward = get_fft_plan(spectrum, shape=shape, axes=axes, value_type="C2R")
        self._directions = (cufft.CUFFT_FORWARD, cufft.CUFFT_INVERSE)

    def forward(self, real: Any, spectrum: Any) -> None:
        """``spectrum <- FFT(real)`` (C-contiguous, the plan's dtypes)."""
        self._forward.fft(real, spectrum, self._directions[0])

    def backward(self, spectrum: Any, real: Any) -> None:
        """``real <- IFFT(spectrum)``, unnormalised; ``spectrum`` is overwritten."""
        self._backward.fft(spectrum, real, self._directions[1])


class ArrayFFT:
    """Real-to-complex 2-D FFTs of one grid with the array module's ``fft`` (one rank: a
    GPU's arrays on several are not supported yet).

    The interface of :mod:`~petsc_contact.devices.fft`'s engines: buffers ``real`` (kept by
    :meth:`forward`), ``spectrum`` and ``result``; both transforms unnormalised, so
    ``backward(forward(x)) = nx ny x`` (the ``1/N`` is folded into the operators'
    multipliers: :meth:`~petsc_contact.backend.operator.SpectralOperator.normalised`), and
    :meth:`backward` may overwrite ``spectrum``.  ``real`` and ``result`` are made when first
    asked for (zero): the preconditioner's float32 transforms, run on the CG's fields, never
    make them.  The transforms are
    :class:`ArrayModuleTransforms` (NumPy's, or CuPy's with its plan cache), or on a GPU with
    ``PETSC_CONTACT_CUFFT_PLANS=on`` :class:`CuFFTPlans`; either way a field of the
    transforms' dtype that is C-contiguous is read, and written, in place, any other through
    a staging buffer (made when first needed).

    ``dtype`` is the transforms' precision, ``float64`` or ``float32`` (``spectrum`` then
    ``complex64``; NumPy 2 and cuFFT compute in it): :meth:`forward_from` takes a field of
    any real dtype, :meth:`backward_into` writes into one (cast there).
    """

    transposed = False

    def __init__(self, grid: Grid, device: Device, dtype: Any = np.float64) -> None:
        if grid.comm.size != 1:
            raise ValueError(f"the {device.name} device runs on one MPI rank, not {grid.comm.size}")
        xp = device.xp
        self.device = device
        self.shape = grid.shape
        self.dtype = np.dtype(dtype)
        nx, m = grid.shape[0], grid.half
        self.spectrum = xp.zeros((nx, m), dtype=np.result_type(self.dtype, np.complex64))
        self.spectral_index = (slice(0, nx), slice(0, m))
        self._fields: dict[str, Any] = {}  # real, result and the staging field, when made
        planned = not device.on_host and os.environ.get(CUFFT_PLANS_VARIABLE, "off") == "on"
        self.transforms = (
            CuFFTPlans(xp.empty(grid.shape, dtype=self.dtype), self.spectrum)
            if planned
            else ArrayModuleTransforms(xp, grid.shape)
        )

    @property
    def real(self) -> Any:
        """The field :meth:`forward` transforms (kept by it)."""
        return self._field("real")

    @property
    def result(self) -> Any:
        """The field :meth:`backward` writes."""
        return self._field("result")

    def _field(self, name: str) -> Any:
        """A field of the grid in the transforms' dtype, made (zero) when first asked for:
        ``real``, ``result``, or ``staging`` (for a field of another dtype or layout)."""
        if name not in self._fields:
            self._fields[name] = self.device.xp.zeros(self.shape, dtype=self.dtype)
        return self._fields[name]

    def forward(self) -> None:
        """``spectrum <- FFT(real)``."""
        self.forward_from(self.real)

    def backward(self) -> None:
        """``result <- IFFT(spectrum)`` without the ``1/(nx ny)``."""
        self.backward_into(self.result)

    def forward_from(self, x: Any) -> None:
        """``spectrum <- FFT(x)`` for an array of the grid's size (``real`` untouched)."""
        field = x.reshape(self.shape)
        if not self._direct(field):
            staging = self._field("staging")
            staging[...] = field
            field = staging
        self.transforms.forward(field, self.spectrum)

    def backward_into(self, out: Any) -> None:
        """``out <- IFFT(spectrum)`` (unnormalised; ``spectrum`` may be overwritten)."""
        if self._direct(out):  # a C-contiguous array's reshape is a view of it
            self.transforms.backward(self.spectrum, out.reshape(self.shape))
            return
        staging = self._field("staging")
        self.transforms.backward(self.spectrum, staging)
        out[...] = staging.reshape(out.shape)

    def _direct(self, field: Any) -> bool:
        """Whether ``field`` can be a transform's own buffer (its dtype, C-contiguous)."""
        return bool(field.dtype == self.dtype and field.flags.c_contiguous)


def _aligned(size: int, dtype: Any) -> np.ndarray:
    """A zeroed 1-D array of ``size`` items whose data is 64-byte aligned (SIMD-friendly)."""
    raw = np.zeros(size * np.dtype(dtype).itemsize + 64, dtype=np.uint8)
    offset = -raw.ctypes.data % 64
    return raw[offset : offset + size * np.dtype(dtype).itemsize].view(dtype)


FFT = SerialFFT | SlabFFT | FFTWMPI | ArrayFFT


def make_fft(grid: Grid, device: Device = CPU) -> FFT:
    """The FFT engine of ``grid`` on ``device``: FFTW's for this grid's communicator (the
    module docstring) on the ``cpu`` device, and for host arrays on several ranks (its MPI
    transforms, the device's passes on them); the array module's (:class:`ArrayFFT`, one
    rank) otherwise."""
    if not (device.compiled or (device.on_host and grid.comm.size > 1)):
        return ArrayFFT(grid, device)
    fft = SerialFFT(grid) if grid.comm.size == 1 else FFTWMPI.create(grid) or SlabFFT(grid)
    fft.device = device
    return fft


def wavevectors(grid: Grid, fft: FFT) -> tuple[np.ndarray, np.ndarray]:
    """Local components ``(qx, qy)`` of the half-spectrum block, broadcastable to its shape.

    ``q = 2 pi (i/Lx, j/Ly)`` with ``i`` in numpy's FFT order
    (:func:`~petsc_contact.conventions.grid.fft_order`) and ``j = 0 .. ny//2``.
    """
    rows, cols = fft.spectral_index
    dqx, dqy = grid.dq
    qx = dqx * fft_order(grid.shape[0])[rows]
    qy = dqy * np.arange(grid.half)[cols]
    return (qx[None, :], qy[:, None]) if fft.transposed else (qx[:, None], qy[None, :])


def wavevector_magnitude(grid: Grid, fft: FFT, xp: ModuleType = np) -> Any:
    """``|q|`` on the local half-spectrum block, an array of ``xp`` (made there: only the
    axes' wavevectors cross)."""
    qx, qy = (xp.asarray(q) for q in wavevectors(grid, fft))
    return xp.sqrt(qx**2 + qy**2)


def half_spectrum_weights(grid: Grid, fft: FFT) -> np.ndarray:
    """Multiplicity of each half-spectrum column in the full spectrum (1 or 2).

    ``sum(w * |F|^2)`` over all ranks equals the full-spectrum sum (Parseval).
    """
    ny = grid.shape[1]
    cols = np.arange(grid.half)[fft.spectral_index[1]]
    w = np.where((cols == 0) | ((ny % 2 == 0) & (cols == ny // 2)), 1.0, 2.0)
    return w[:, None] if fft.transposed else w[None, :]


def single_entries(grid: Grid, fft: FFT) -> np.ndarray:
    """Flat indices, in the local spectrum block, of the entries of multiplicity 1.

    They are the columns ``qy = 0`` and ``qy = ny/2`` (even ``ny``) of the half spectrum; every
    other entry stands for itself and its complex conjugate (:func:`half_spectrum_weights`).
    """
    weights = np.broadcast_to(half_spectrum_weights(grid, fft), fft.spectrum.shape)
    return np.flatnonzero(weights == 1.0)
