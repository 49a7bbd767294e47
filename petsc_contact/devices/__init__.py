"""Devices: where a solve's arrays live (NumPy or CuPy), their FFTs and whole-field passes,
and nothing else.

:mod:`~petsc_contact.devices.device` is the :class:`~petsc_contact.devices.device.Device`
chosen once per run (``cpu``, ``gpu``, ``cpu-array``); :mod:`~petsc_contact.devices.fft` its
FFT engines (pyfftw, FFTW-MPI, mpi4py-fft, the array module's); its element-wise passes are
:mod:`~petsc_contact.devices.passes` (NumPy or CuPy, written once),
:mod:`~petsc_contact.devices.fused` (CuPy's fused kernels) and
:mod:`~petsc_contact.devices.compiled` (numba's, on the ``cpu`` device).
"""
