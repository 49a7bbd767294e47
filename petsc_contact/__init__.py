"""petsc-contact: non-adhesive contact of rough elastic solids with PETSc/TAO.

Modules: :mod:`surface` (self-affine surfaces, paper Eq. 5), :mod:`greens` (elastic
kernels), :mod:`problem` (the bound-constrained QP), :mod:`solve` (the TAO driver),
:mod:`periodic` (load sweeps), :mod:`observables`, :mod:`output` (HDF5), :mod:`cli`.
PETSc is found and initialised lazily (:func:`petsc_contact._petsc.init`).
"""

import os

# FFTW runs one thread per core; a threaded BLAS spinning beside it (np.dot, PETSc's VecDot)
# made every FFT 10x slower here.  Effective when numpy is not imported yet (the CLI).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

__version__ = "0.1.0"

from .grid import Grid  # noqa: E402
from .periodic import periodic_contact  # noqa: E402

__all__ = ["Grid", "periodic_contact", "__version__"]
