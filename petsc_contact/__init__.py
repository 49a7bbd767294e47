"""petsc-contact: non-adhesive contact of rough elastic solids with PETSc/TAO.

Modules: :mod:`surface` (self-affine surfaces, paper Eq. 5), :mod:`greens` (elastic
kernels), :mod:`operator` (FFT shell Mats), :mod:`problem` (the periodic QP), :mod:`punch`
(the punch), :mod:`solve` (the TAO driver), :mod:`cg` (the constrained CG TAO types),
:mod:`periodic` (load sweeps), :mod:`stiffness`, :mod:`theory`, :mod:`observables`,
:mod:`output` (HDF5), :mod:`cli`.
PETSc is found and initialised lazily (:func:`petsc_contact._petsc.init`).
"""

import os

# FFTW runs one thread per core; a threaded BLAS spinning beside it (np.dot, PETSc's VecDot)
# slows every FFT down many times.  Effective when numpy is not imported yet (the CLI).
# Not OMP_NUM_THREADS: Debian's FFTW threads through OpenMP, and OMP_NUM_THREADS=1 halves it.
# Passive OpenMP waiting keeps FFTW's idle threads off the core numpy works on (~5-10%).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

__version__ = "0.1.0"

from .grid import Grid
from .periodic import periodic_contact
from .punch import punch_contact

__all__ = ["Grid", "periodic_contact", "punch_contact", "__version__"]
