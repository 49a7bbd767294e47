"""HDF5 results: written step by step, renamed into place only when the run ends.

A run writes ``OUT.h5.partial`` and renames it to ``OUT.h5`` when it ends (atomic on POSIX),
so a killed run never damages an earlier ``OUT.h5``, and every finished load step is already
on disk, flushed, in the ``.partial`` file.  Only rank 0 touches the file; distributed fields
are gathered to it (see :meth:`petsc_contact.grid.Grid.gather`).  The schema is in README.md.
"""

from __future__ import annotations

import hashlib
import json
import os
import platform
import sys
import time
from importlib import metadata
from typing import Any

import numpy as np

from .grid import Grid


def load_heights(path: str) -> np.ndarray:
    """Read a measured or saved height map (``.npy``, or a whitespace/comma text matrix).

    ``.npy`` files are memory-mapped, so under MPI each rank reads only its rows.
    Raises ``ValueError``/``OSError`` with a one-line reason for anything unusable.
    """
    if not os.path.isfile(path):
        raise OSError(f"heights file '{path}' does not exist")
    if not os.access(path, os.R_OK):
        raise OSError(f"heights file '{path}' is not readable")
    try:
        if path.endswith(".npy"):
            h = np.load(path, mmap_mode="r", allow_pickle=False)
        else:
            h = np.loadtxt(path, delimiter="," if path.endswith(".csv") else None, ndmin=2)
    except Exception as exc:
        raise OSError(f"cannot read heights from '{path}': {exc}") from None
    if h.ndim != 2:
        raise ValueError(f"heights must be a 2-D array, '{path}' has shape {h.shape}")
    if h.shape[0] != h.shape[1]:
        raise ValueError(f"heights must be square (n x n), '{path}' has shape {h.shape}")
    if h.shape[0] < 2:
        raise ValueError(f"heights need at least 2 x 2 points, '{path}' has shape {h.shape}")
    if not np.issubdtype(h.dtype, np.number) or np.iscomplexobj(h):
        raise ValueError(f"heights must be real numbers, '{path}' holds {h.dtype}")
    return h


def check_finite(grid: Grid, h: np.ndarray, what: str = "heights") -> None:
    """Raise ``ValueError`` if any rank's slab has NaN or inf."""
    bad = grid.sum(np.count_nonzero(~np.isfinite(h)))[0]
    if bad:
        raise ValueError(f"{what} contain {int(bad)} NaN or infinite values")


def file_digest(path: str) -> str:
    """SHA-256 of a file, to tie a result to its input."""
    sha = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            sha.update(block)
    return sha.hexdigest()


def versions(petsc: Any | None = None) -> dict[str, str]:
    """Versions of everything that shapes a result."""
    out = {"python": platform.python_version(), "platform": platform.platform()}
    for mod in ("numpy", "scipy", "h5py", "mpi4py", "pyfftw", "mpi4py_fft", "numba", "petsc4py"):
        try:
            out[mod] = str(__import__(mod).__version__)
        except Exception:
            out[mod] = "not available"
    try:
        out["petsc_contact"] = metadata.version("petsc-contact")
    except metadata.PackageNotFoundError:
        from . import __version__

        out["petsc_contact"] = __version__
    if petsc is not None:
        out["petsc"] = ".".join(map(str, petsc.Sys.getVersion()))
    return out


def petsc_options(petsc: Any) -> str:
    """All options in PETSc's database as one command-line string."""
    opts = petsc.Options().getAll()
    return " ".join(f"-{k} {v}".rstrip() for k, v in sorted(opts.items()))


def check_writable(path: str) -> None:
    """Raise ``OSError`` with a one-line reason unless ``path`` can be created."""
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise OSError(f"output folder '{folder}' does not exist")
    if not os.access(folder, os.W_OK):
        raise OSError(f"output folder '{folder}' is not writable")
    if os.path.isdir(path):
        raise OSError(f"output path '{path}' is a folder")


class StepWriter:
    """Per-step HDF5 writer (rank 0 writes; other ranks only join collective gathers).

    Parameters
    ----------
    path
        Final file name; the run writes ``path + '.partial'`` until :meth:`finish`.
    grid
        Layout of fields.
    attributes
        Run metadata stored as root attributes (dicts and lists stored as JSON).
    heights
        This rank's slab of the input heights, stored as the dataset ``heights``.
    fields
        Names of per-step 2-D fields to store (e.g. ``("gap", "pressure")``), or empty.
    """

    def __init__(
        self,
        path: str,
        grid: Grid,
        attributes: dict[str, Any],
        heights: np.ndarray | None,
        fields: tuple[str, ...] = (),
        *,
        resume: bool = False,
    ) -> None:
        self.path = path
        self.partial = path + ".partial"
        self.grid = grid
        self.fields = fields
        self.root = grid.comm.rank == 0
        self.file: Any = None
        if resume:
            self.steps = grid.comm.bcast(self._open_partial() if self.root else 0, root=0)
        else:
            self.steps = 0
            full = grid.gather(heights) if heights is not None else None
            if self.root:
                self._create(attributes, full)

    @classmethod
    def reopen(cls, path: str, grid: Grid, fields: tuple[str, ...] = ()) -> StepWriter:
        """Continue writing an interrupted run's ``path + '.partial'`` (see :func:`read_resume`)."""
        return cls(path, grid, {}, None, fields, resume=True)

    def _create(self, attributes: dict[str, Any], heights: np.ndarray | None) -> None:
        import h5py

        n = self.grid.n
        f = self.file = h5py.File(self.partial, "w")
        for key, value in attributes.items():
            f.attrs[key] = (
                json.dumps(value)
                if isinstance(value, (dict, list, tuple))
                else ("" if value is None else value)
            )
        f.attrs["created"] = time.strftime("%Y-%m-%dT%H:%M:%S%z")
        f.attrs["complete"] = False
        if heights is not None:
            f.create_dataset("heights", data=heights)
        for name in self.fields:
            f.create_dataset(
                name,
                shape=(0, n, n),
                maxshape=(None, n, n),
                chunks=(1, min(n, 256), min(n, 256)),
            )
        f.flush()

    def _open_partial(self) -> int:
        """Open the ``.partial`` file for appending; the number of steps it holds."""
        import h5py

        self.file = h5py.File(self.partial, "a")
        return int(self.file["converged"].shape[0]) if "converged" in self.file else 0

    def append(
        self,
        scalars: dict[str, Any],
        fields: dict[str, np.ndarray] | None = None,
        state: np.ndarray | None = None,
    ) -> None:
        """Add one load step: scalars (numbers, bools or strings) and the requested fields.

        ``state`` (local slab) is the solution a resumed run restarts from; it is kept in
        the dataset ``resume_state`` until :meth:`finish` removes it.
        """
        gathered = {k: self.grid.gather(fields[k]) for k in self.fields} if fields else {}
        full_state = self.grid.gather(state) if state is not None else None
        if self.root:
            f = self.file
            for key, value in scalars.items():
                if key not in f:
                    f.create_dataset(key, shape=(0,), maxshape=(None,), dtype=h5_dtype(value))
                d = f[key]
                d.resize((self.steps + 1,))
                d[self.steps] = value
            for key, value in gathered.items():
                d = f[key]
                d.resize((self.steps + 1, self.grid.n, self.grid.n))
                d[self.steps] = value
            if full_state is not None:
                if "resume_state" not in f:
                    f.create_dataset("resume_state", data=full_state)
                else:
                    f["resume_state"][...] = full_state
                f["resume_state"].attrs["after_step"] = self.steps
            f.flush()
        self.steps += 1

    def finish(self) -> None:
        """Mark complete and rename into place (the earlier ``path``, if any, is replaced)."""
        if self.root and self.file is not None:
            self.file.attrs["complete"] = True
            if "resume_state" in self.file:
                del self.file["resume_state"]
            self.file.close()
            self.file = None
            os.replace(self.partial, self.path)
        self.grid.comm.Barrier()

    def abandon(self) -> None:
        """Close after an interruption, keeping the finished steps in the ``.partial`` file."""
        if self.root and self.file is not None:
            self.file.close()
            self.file = None
            print(
                f"petsc-contact: interrupted; {self.steps} finished step(s) kept in {self.partial}",
                file=sys.stderr,
            )


def read_resume(path: str, parameters: dict[str, Any]) -> tuple[int, np.ndarray | None]:
    """Finished steps and last state of an interrupted run ``path + '.partial'``.

    Returns ``(0, None)`` when there is nothing to resume.  Raises ``ValueError`` when the
    partial file belongs to a different run (its ``parameters`` differ, apart from
    ``resume`` and ``quiet``), so a resume never mixes two runs.
    """
    import h5py

    partial = path + ".partial"
    if not os.path.exists(partial):
        return 0, None
    ignore = ("resume", "quiet")
    mine = {k: v for k, v in parameters.items() if k not in ignore}
    with h5py.File(partial, "r") as f:
        theirs = {k: v for k, v in json.loads(f.attrs["parameters"]).items() if k not in ignore}
        mine = json.loads(json.dumps(mine))
        changed = sorted(
            k for k in set(mine) | set(theirs) if not _same(mine.get(k), theirs.get(k))
        )
        if changed:
            raise ValueError(
                f"cannot resume '{partial}': it was run with different "
                f"parameters ({', '.join(changed)})"
            )
        steps = int(f["converged"].shape[0]) if "converged" in f else 0
        state = f["resume_state"][...] if "resume_state" in f else None
    return steps, state


def _same(a: Any, b: Any) -> bool:
    """Equal parameters; floats to 1e-9 relative (derived loads carry FFT rounding)."""
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) or isinstance(b, float):
        try:
            return bool(np.isclose(float(a), float(b), rtol=1e-9, atol=0.0))
        except (TypeError, ValueError):
            return False
    return a == b


def h5_dtype(value: Any) -> Any:
    """HDF5 dtype of one per-step scalar."""
    import h5py

    if isinstance(value, str):
        return h5py.string_dtype()
    if isinstance(value, (bool, np.bool_)):
        return bool
    if isinstance(value, (int, np.integer)):
        return np.int64
    return np.float64
