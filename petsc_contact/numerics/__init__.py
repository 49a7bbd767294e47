"""The numerical engine under the physics and the PETSc edge, without PETSc: the FFT backends
(pyfftw, FFTW-MPI through ctypes, mpi4py-fft) and their normalisation, the fused numba passes
of the solvers and operators, and the dense Schur algebra on small contact sets."""
