"""petsc-contact: non-adhesive contact of rough elastic solids with PETSc/TAO.

The folders are the layers, and imports run from the later to the earlier ones
(docs/architecture.md): ``conventions`` (grid, units, input checks, memory estimates),
``devices`` (where the arrays live: NumPy or CuPy, their FFTs and whole-field passes),
``numerics`` (the numba kernels' compilation, the coarse sums, Schur algebra; no PETSc),
``reference``
(analytic solutions), ``physics`` (pure numpy), ``substrates`` (the elastic body by its
Green's function), ``interactions`` (the law at the surface, its bounds), ``solver`` (the
package's own solver on arrays of any device; the solver backend), ``io`` (HDF5, height maps,
plots),
``backend`` (PETSc: operators, TAO driver, the package's TAO types, preconditioners,
stiffness solves), ``geometries`` (the contact core: periodic and punch), ``workflows``
(runs, sweeps, compare, ensembles), ``paper`` (theory for a map, figures, the paper's study)
and ``cli``.  The names below
are loaded when first used, so that importing the package is quick; PETSc is initialised by
the backend (:func:`petsc_contact.backend._petsc.init`) when a run needs it.
"""

import os

# FFTW runs one thread per core; a threaded BLAS spinning beside it (np.dot, PETSc's VecDot)
# slows every FFT down many times.  Effective when numpy is not imported yet (the CLI).
# Not OMP_NUM_THREADS: Debian's FFTW threads through OpenMP, and OMP_NUM_THREADS=1 halves it.
# Passive OpenMP waiting keeps FFTW's idle threads off the core numpy works on (~5-10%).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

from typing import Any

from ._moved import install
from ._version import __version__

install()  # the old paths of moved modules (petsc_contact._moved)

PUBLIC = {  # loaded when first used: importing the package loads no numba, scipy or PETSc
    "Grid": "conventions.grid",
    "periodic_contact": "workflows.periodic_sweep",
    "punch_contact": "workflows.punch_sweep",
    "Run": "workflows.description",
    "run_contact": "workflows.runner",
    "run_ensemble": "workflows.seeds",
    "read_topography": "io.topography",
    "predict_map": "paper.predictions",
    "read_frame": "io.results",
}
__all__ = [*PUBLIC, "__version__"]


def __getattr__(name: str) -> Any:
    if name in PUBLIC:
        import importlib

        return getattr(importlib.import_module(f".{PUBLIC[name]}", __name__), name)
    raise AttributeError(f"module 'petsc_contact' has no attribute '{name}'")


def __dir__() -> list[str]:
    """The public API (``dir(petsc_contact)``), none of it loaded by being listed."""
    return sorted(__all__)
