"""What reproduces a result: the versions of everything that shapes it, the source commit,
PETSc's options and the digest of an input map."""

from __future__ import annotations

import hashlib
import os
import platform
import sys
from importlib import metadata
from typing import Any

import numpy as np

from .._version import __version__


def file_digest(path: str) -> str:
    """SHA-256 of a file, to tie a result to its input."""
    sha = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            sha.update(block)
    return sha.hexdigest()


def input_digest(heights: Any) -> str:
    """SHA-256 of a height map as a run is given it: its file's bytes for a path, else its
    array's type, shape and values (a ``Topography``'s heights, a masked array's masked points
    NaN), so that a changed map, in a file or in memory, is told from the one a result holds."""
    if isinstance(heights, (str, os.PathLike)):
        return file_digest(os.fspath(heights))
    from .topography import as_topography

    values = np.ascontiguousarray(as_topography(heights).heights)
    sha = hashlib.sha256(f"{values.dtype.str} {values.shape} ".encode())
    sha.update(values.data)
    return sha.hexdigest()


MODULES = ("numpy", "scipy", "h5py", "mpi4py", "pyfftw", "mpi4py_fft", "numba", "petsc4py")
"""The modules whose versions every record gives (``cupy`` too, when a run loaded it)."""


def module_version(name: str) -> str:
    """The version of the module ``name``: its own where it is loaded, else its installed
    distribution's (nothing is imported: an array device's run loads no petsc4py), else
    ``not available`` (not installed, or known not to import: ``None`` in ``sys.modules``)."""
    if name in sys.modules:
        loaded = sys.modules[name]
        return "not available" if loaded is None else str(getattr(loaded, "__version__", "?"))
    try:
        return metadata.version(name)
    except (metadata.PackageNotFoundError, ValueError):
        return "not available"


def versions(petsc: Any | None = None) -> dict[str, str]:
    """Versions of everything that shapes a result."""
    out = {"python": platform.python_version(), "platform": platform.platform()}
    for mod in MODULES:
        out[mod] = module_version(mod)
    if sys.modules.get("cupy") is not None:  # a GPU run's (its distribution's name varies)
        out["cupy"] = module_version("cupy")
    try:  # the instrument reader, when installed (its own __version__ is not its release)
        out["SurfaceTopography"] = metadata.version("SurfaceTopography")
    except metadata.PackageNotFoundError:
        out["SurfaceTopography"] = "not available"
    try:
        out["petsc_contact"] = metadata.version("petsc-contact")
    except metadata.PackageNotFoundError:
        out["petsc_contact"] = __version__
    out["petsc_contact_commit"] = source_commit()
    if petsc is not None:
        out["petsc"] = ".".join(map(str, petsc.Sys.getVersion()))
    return out


def source_commit() -> str:
    """The git commit of the package's source (``+dirty`` with local changes anywhere in
    the package, not only in this module's folder), or ``unknown`` outside a git checkout."""
    import subprocess

    folder = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # the package
    try:
        run = [
            subprocess.run(["git", "-C", folder, *args], capture_output=True, text=True, timeout=10)
            for args in (["rev-parse", "HEAD"], ["status", "--porcelain", "--", "."])
        ]
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    if run[0].returncode != 0:
        return "unknown"
    return run[0].stdout.strip() + ("+dirty" if run[1].stdout.strip() else "")


def petsc_options(petsc: Any) -> str:
    """All options in PETSc's database as one command-line string."""
    opts = petsc.Options().getAll()
    return " ".join(f"-{k} {v}".rstrip() for k, v in sorted(opts.items()))
