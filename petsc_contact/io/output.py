"""HDF5 results: written step by step, renamed into place only when the run ends.

A run writes ``OUT.h5.partial`` and renames it to ``OUT.h5`` when it ends (atomic on POSIX),
so a killed run never damages an earlier ``OUT.h5``, and every finished load step is already
on disk, flushed, in the ``.partial`` file.  Only rank 0 touches the file; distributed fields
are gathered to it (see :meth:`petsc_contact.conventions.grid.Grid.gather`).  This module owns the
schema: every dataset any command writes, with its units and description (the tables below,
rendered as ``docs/output-schema.md``).
"""

from __future__ import annotations

import hashlib
import json
import os
import platform
import re
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from importlib import metadata
from typing import Any

import numpy as np

from ..conventions.grid import Grid

PARTIAL = ".partial"  # a run's file until it ends: OUT.h5.partial, renamed OUT.h5 at the end


def partial_path(path: str) -> str:
    """The file a run with output ``path`` writes until it ends (``path + '.partial'``)."""
    return path + PARTIAL


def is_partial(path: str) -> bool:
    """Whether ``path`` names an unfinished run's file (see :func:`partial_path`)."""
    return path.endswith(PARTIAL)


def load_table(path: str, columns: int) -> np.ndarray:
    """A small numeric table: comma- or whitespace-separated, ``#`` comments, and at most one
    header line (a first row that is not numbers).  Raises ``ValueError`` with the line."""
    rows: list[list[float]] = []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            text = line.split("#", 1)[0].strip()
            if not text:
                continue
            fields = [v for v in re.split(r"[,\s]+", text) if v]
            try:
                rows.append([float(v) for v in fields])
            except ValueError:
                if rows:  # only the first row may be a header
                    raise ValueError(f"'{path}' line {number} is not {columns} numbers") from None
                rows.append([])  # the header
                continue
            if len(fields) != columns:
                raise ValueError(f"'{path}' line {number} has {len(fields)} columns, not {columns}")
    table = np.array([r for r in rows if r], dtype=float).reshape(-1, columns)
    if not table.size or not np.all(np.isfinite(table)):
        raise ValueError(f"'{path}' must hold rows of {columns} finite numbers")
    return table


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
    try:  # the instrument reader, when installed (its own __version__ is not its release)
        out["SurfaceTopography"] = metadata.version("SurfaceTopography")
    except metadata.PackageNotFoundError:
        out["SurfaceTopography"] = "not available"
    try:
        out["petsc_contact"] = metadata.version("petsc-contact")
    except metadata.PackageNotFoundError:
        from .. import __version__

        out["petsc_contact"] = __version__
    out["petsc_contact_commit"] = source_commit()
    if petsc is not None:
        out["petsc"] = ".".join(map(str, petsc.Sys.getVersion()))
    return out


def source_commit() -> str:
    """The git commit of the package's source (``+dirty`` with local changes), or
    ``unknown`` outside a git checkout."""
    import subprocess

    folder = os.path.dirname(os.path.abspath(__file__))
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


def write_attributes(obj: Any, attributes: dict[str, Any]) -> None:
    """HDF5 attributes of a file or group: dicts and lists as JSON, ``None`` as ``''``."""
    for key, value in attributes.items():
        obj.attrs[key] = (
            json.dumps(value)
            if isinstance(value, (dict, list, tuple))
            else ("" if value is None else value)
        )


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
        from_saved_state: bool = True,
    ) -> None:
        self.path = path
        self.partial = partial_path(path)
        self.grid = grid
        self.fields = fields
        self.root = grid.comm.rank == 0
        self.file: Any = None
        self.schema: dict[str, Entry] = GEOMETRIES.get(attributes.get("geometry", ""), {})
        if resume:
            opened = self._open_partial(from_saved_state) if self.root else 0
            self.steps = grid.comm.bcast(opened, root=0)
        else:
            self.steps = 0
            full = grid.gather(heights) if heights is not None else None
            if self.root:
                self._create(attributes, full)

    @classmethod
    def reopen(
        cls, path: str, grid: Grid, fields: tuple[str, ...] = (), from_saved_state: bool = True
    ) -> StepWriter:
        """Continue writing an interrupted run's ``path + '.partial'`` (see :func:`read_resume`);
        ``from_saved_state`` is false when :func:`read_resume` found no state to go on from."""
        return cls(path, grid, {}, None, fields, resume=True, from_saved_state=from_saved_state)

    def _create(self, attributes: dict[str, Any], heights: np.ndarray | None) -> None:
        import h5py

        nx, ny = self.grid.shape
        if os.path.exists(state_path(self.path)):  # a fresh run: an old state is not ours
            os.remove(state_path(self.path))
        f = self.file = h5py.File(self.partial, "w")
        write_attributes(f, attributes)
        f.attrs["created"] = time.strftime("%Y-%m-%dT%H:%M:%S%z")
        f.attrs["complete"] = False
        if heights is not None:
            describe(f.create_dataset("heights", data=heights), self._entry("heights"))
        for name in self.fields:
            d = f.create_dataset(
                name,
                shape=(0, nx, ny),
                maxshape=(None, nx, ny),
                dtype=bool if name == "contact" else np.float64,
                chunks=(1, min(nx, 256), min(ny, 256)),
                compression="gzip",
                compression_opts=4,
                shuffle=True,
            )
            describe(d, self._entry(name))
        f.flush()

    def _entry(self, name: str) -> Entry:
        """The schema entry of ``name``, its ``length`` in the run's unit when it has one."""
        try:
            entry = self.schema[name]
        except KeyError:
            raise KeyError(
                f"no schema entry for dataset '{name}' (petsc_contact.io.output)"
            ) from None
        return in_unit(entry, str(self.file.attrs.get("length_unit", "")))

    def _open_partial(self, from_saved_state: bool) -> int:
        """Open the ``.partial`` file for appending; the number of steps it holds."""
        import h5py

        self.file = h5py.File(self.partial, "a")
        self.schema = GEOMETRIES.get(str(self.file.attrs.get("geometry", "")), {})
        steps = int(self.file["converged"].shape[0]) if "converged" in self.file else 0
        # the steps from here on may be computed by another version than the file's record
        earlier = json.loads(str(self.file.attrs.get("resumed", "[]")) or "[]")
        when = time.strftime("%Y-%m-%dT%H:%M:%S%z")
        resumed = {
            "after_step": steps,
            "time": when,
            "petsc_contact_commit": source_commit(),
            "from_saved_state": from_saved_state,  # False: the next step began at first touch
        }
        self.file.attrs["resumed"] = json.dumps([*earlier, resumed])
        return steps

    def append(
        self,
        scalars: dict[str, Any],
        fields: dict[str, np.ndarray] | None = None,
        state: np.ndarray | None = None,
    ) -> None:
        """Add one load step: scalars (numbers, bools or strings) and the requested fields.

        ``state`` (local slab) is the solution a resumed run restarts from; it is kept
        beside the file, in ``path + '.state.npz'`` (:func:`state_path`), until :meth:`finish`
        removes it, so that the results file never holds (or keeps the space of) a field.
        """
        gathered = {k: self.grid.gather(fields[k]) for k in self.fields} if fields else {}
        full_state = self.grid.gather(state) if state is not None else None
        if self.root:
            f = self.file
            for key, value in scalars.items():
                if key not in f:  # new, or new since the version a resumed run began with
                    dtype = h5_dtype(value)
                    d = f.create_dataset(
                        key, (0,), dtype, maxshape=(None,), fillvalue=MISSING.get(dtype)
                    )
                    describe(d, self._entry(key))
                d = f[key]
                d.resize((self.steps + 1,))
                d[self.steps] = value
            for key, value in gathered.items():
                d = f[key]
                d.resize((self.steps + 1, *self.grid.shape))
                d[self.steps] = value
            f.flush()
            if full_state is not None:
                temporary = state_path(self.path) + ".tmp.npz"
                np.savez(temporary, state=full_state, after_step=self.steps)
                os.replace(temporary, state_path(self.path))
        self.steps += 1

    def finish(self) -> None:
        """Mark complete and rename into place (the earlier ``path``, if any, is replaced)."""
        if self.root and self.file is not None:
            self.file.attrs["complete"] = True
            if "resume_state" in self.file:  # written there by earlier versions
                del self.file["resume_state"]
            self.file.close()
            self.file = None
            os.replace(self.partial, self.path)
            if os.path.exists(state_path(self.path)):
                os.remove(state_path(self.path))
        self.grid.comm.Barrier()

    def abandon(self, why: str = "interrupted") -> None:
        """Close after an interruption, keeping the finished steps in the ``.partial`` file."""
        if self.root and self.file is not None:
            self.file.close()
            self.file = None
            print(
                f"petsc-contact: {why}; {self.steps} finished step(s) kept in {self.partial} "
                "(--resume continues)",
                file=sys.stderr,
            )


def read_resume(path: str, parameters: dict[str, Any]) -> tuple[int, np.ndarray | None]:
    """Finished steps and last state of an interrupted run ``path + '.partial'``.

    Returns ``(0, None)`` when there is nothing to resume.  Raises ``ValueError`` when the
    partial file belongs to a different run (its ``parameters`` differ, apart from
    ``resume`` and ``quiet``), so a resume never mixes two runs.
    """
    import h5py

    partial = partial_path(path)
    if not os.path.exists(partial):
        return 0, None
    ignore = ("resume", "quiet", "stop_after")
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
        state = f["resume_state"][...] if "resume_state" in f else None  # earlier versions
    if os.path.exists(state_path(path)):
        with np.load(state_path(path)) as saved:
            state = saved["state"]
    return steps, state


def state_path(path: str) -> str:
    """Where an unfinished run keeps the state it resumes from: beside ``path``."""
    return path + ".state.npz"


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


MISSING = {np.float64: np.nan, np.int64: -1}  # the earlier steps' value of a new column


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


# -- the schema: every dataset any command writes, its units and its meaning ------------------
#
# Units are symbolic: ``length`` is the unit of ``--length`` and of the heights (written as
# that unit, ``um``, in a file whose run has one: :func:`in_unit`), ``pressure`` the unit of
# ``--modulus``; ``1`` is
# dimensionless, ``s`` seconds of wall time, ``count`` a number of things, ``text`` a string
# and ``bool`` a flag.


@dataclass(frozen=True)
class Entry:
    """One dataset of the schema: its units and what it holds."""

    units: str
    description: str


def _entries(**entries: tuple[str, str]) -> dict[str, Entry]:
    return {name: Entry(*value) for name, value in entries.items()}


SOLVE_COLUMNS = _entries(
    iterations=("count", "TAO iterations of the step (punch with forces: summed over Newton)"),
    solve_time=("s", "wall time of the solve, the slowest rank's"),
    converged=("bool", "TAO converged and the package's own verification passed"),
    verification=("text", "'ok', or why the step's answer cannot be used"),
    tao_type=("text", "TAO type; python:PreconditionedCG for the default"),
    tao_reason=("text", "TAO's converged reason"),
    tao_reason_code=("count", "TAO's converged reason as a number (positive: converged)"),
    objective_gradient_evaluations=("count", "objective and gradient evaluations"),
    hessian_applications=(
        "count",
        "Hessian applications (the default CG: forward transforms of a direction)",
    ),
    preconditioner_applications=("count", "preconditioner applications"),
    gradient_norm=("1", "TAO's final gradient norm (its own definition, per type)"),
    tolerance=("1", "the absolute gradient tolerance used (raised to the rounding floor)"),
    stiffness_iterations=("count", "CG iterations of the exact stiffness solve"),
    stiffness_time=(
        "s",
        "wall time of the exact stiffness solve with its preconditioner's set-up, the slowest "
        "rank's",
    ),
    complementarity=("1", "sum(p+ g) / (sum(p+) h_rms), as Tamaas reports it"),
    max_pressure=("pressure", "largest contact pressure"),
    min_gap=("length", "smallest gap (negative: the bound is violated)"),
    area_fraction=("1", "fraction of the pixels in contact (punch: of the footprint)"),
    contact_patches=(
        "count",
        "contact patches: clusters of contact pixels joined through their edges "
        "(periodic: across the cell's edges)",
    ),
    nominal_pressure=("pressure", "nominal pressure p0 (punch: F / Lp^2)"),
)
PERIODIC_COLUMNS = _entries(
    mean_gap=("length", "mean gap u_bar"),
    contact_pressure_mean=("pressure", "mean over all pixels of the contact pressure (= p0)"),
    elastic_energy=("pressure*length", "elastic energy per apparent area, 1/2 <(g+h)(p-p0)>"),
    min_pressure=("pressure", "smallest pressure over all pixels (negative: tension)"),
    kkt_residual=("1", "natural residual rms(min(k g, p)) / p0"),
    preconditioner_stiffness=(
        "pressure/length",
        "interfacial stiffness estimate the preconditioner was held by (path, not answer)",
    ),
    stiffness=("pressure/length", "exact -dp0/du_bar with the contact set held fixed"),
)
PUNCH_COLUMNS = _entries(
    approach=("length", "rigid approach beyond first touch"),
    force=("pressure*length^2", "total force F"),
    total_stiffness=("pressure*length", "dF/d delta with the contact set held fixed"),
    interfacial_stiffness=("pressure/length", "interfacial stiffness per area (paper Eq. 2)"),
    flat_punch_stiffness=("pressure*length", "the flat punch's stiffness used in paper Eq. 2"),
    kkt_residual=("1", "natural residual rms(min(g, p/k)) / l, l the rms recess"),
    target_force=("pressure*length^2", "the prescribed force (load control)"),
    newton_iterations=("count", "Newton steps on the approach (load control)"),
    stiffness=("pressure/length", "the interfacial stiffness per area (--stiffness)"),
)
FIELDS = _entries(
    heights=("length", "the height map as given or generated (n x n)"),
    gap=("length", "gap of every step, exactly zero in contact (steps x n x n)"),
    pressure=("pressure", "pressure of every step, exactly zero out of contact (steps x n x n)"),
    contact=("bool", "contact mask of every step, p > k g (steps x n x n)"),
)
ENSEMBLE = _entries(
    seeds=("count", "the seeds, one row of every table each"),
    nominal_pressure=("pressure", "nominal pressures, one column of every table each"),
    **{
        q: (units, f"{q} of every seed and step (seeds x steps; NaN: not converged)")
        for q, units in (
            ("mean_gap", "length"),
            ("area_fraction", "1"),
            ("stiffness", "pressure/length"),
            ("elastic_energy", "pressure*length"),
            ("max_pressure", "pressure"),
            ("iterations", "count"),
            ("solve_time", "s"),
        )
    },
)
ENSEMBLE_STATISTICS = {
    "mean": "mean over the converged seeds",
    "std": "standard deviation over the converged seeds",
    "sem": "standard error of the mean",
    "count": "number of converged seeds",
}
COMPARE = _entries(
    time=("s", "the solver's own wall time at each iteration (measurement excluded)"),
    iteration=("count", "TAO iteration"),
    mean_gap_error=("1", "|u_bar - u_bar_ref| / u_bar_ref"),
    pressure_error=("1", "||p - p_ref|| / ||p_ref||"),
    natural_residual=("1", "rms(min(k g, p)) / p0"),
    complementarity=("1", "sum(p+ g) / (sum(p+) h_rms)"),
)
EXPERIMENT = _entries(
    pressure=("pressure", "measured pressure p"),
    displacement=("length", "measured displacement s"),
    measured_stiffness=("pressure/length", "K* = dp/ds (second-order differences)"),
    stiffness=("pressure/length", "K = K*/(1 - K* d/E') (paper Eq. C3; NaN where K* d/E' >= 1)"),
)
THEORY = _entries(
    wavevector=("1/length", "mean |q| of each radial bin of the map's spectrum"),
    psd=("length^4", "radially averaged PSD C(q) of the map (h_rms^2 = 2 pi int q C dq)"),
    nominal_pressure=("pressure", "nominal pressures of the predictions"),
    mean_gap=("length", "Persson's mean separation u_bar(p) from the map's spectrum"),
    stiffness=("pressure/length", "Persson's interfacial stiffness K(p) = -dp/du_bar"),
)
ENTRIES = {**SOLVE_COLUMNS, **PERIODIC_COLUMNS, **PUNCH_COLUMNS, **FIELDS}  # by name
GEOMETRIES = {
    "periodic": {**SOLVE_COLUMNS, **PERIODIC_COLUMNS, **FIELDS},
    "punch": {**SOLVE_COLUMNS, **PUNCH_COLUMNS, **FIELDS},
}


def ensemble_entry(name: str) -> Entry:
    """The entry of an ensemble summary dataset, statistics (``mean_gap_sem``) included."""
    if name in ENSEMBLE:
        return ENSEMBLE[name]
    quantity, _, statistic = name.rpartition("_")
    if quantity in ENSEMBLE and statistic in ENSEMBLE_STATISTICS:
        units = "count" if statistic == "count" else ENSEMBLE[quantity].units
        return Entry(units, f"{quantity}: {ENSEMBLE_STATISTICS[statistic]}, per step")
    raise KeyError(f"no schema entry for ensemble dataset '{name}'")


def in_unit(entry: Entry, length_unit: str) -> Entry:
    """``entry`` with the symbolic ``length`` of its units replaced by ``length_unit`` (``um``,
    so ``pressure/length`` becomes ``pressure/um``); unchanged when the run has no unit."""
    if not length_unit:
        return entry
    return Entry(re.sub(r"\blength\b", length_unit, entry.units), entry.description)


def describe(dataset: Any, entry: Entry) -> None:
    """Attach ``units`` and ``description`` to an h5py dataset."""
    dataset.attrs["units"] = entry.units
    dataset.attrs["description"] = entry.description


def annotate(group: Any, lookup: Callable[[str], Entry], length_unit: str = "") -> None:
    """Describe every dataset directly in ``group`` (lengths in ``length_unit`` when given);
    ``KeyError`` for one the schema lacks."""
    for name, item in group.items():
        if hasattr(item, "shape"):
            describe(item, in_unit(lookup(name), length_unit))


def schema_markdown() -> str:
    """``docs/output-schema.md``, generated from the tables above (a test keeps it current)."""
    lines = [
        "# Output schema",
        "",
        "Generated from `petsc_contact/io/output.py` by",
        "`petsc-contact schema > docs/output-schema.md`; a test fails when this page and the",
        "code disagree. Every dataset carries the `units` and `description` attributes listed",
        "here. Units are symbolic: `length` is the unit of `--length` and of the heights (a",
        "file whose run has a length unit writes that unit instead: `pressure/um`), `pressure`",
        "the unit of `--modulus`; `1` is dimensionless, `s` seconds of wall time.",
        "",
        "Every file of `periodic`, `demo`, `punch` and `compare` also records, as root",
        "attributes, what reproduces it: " + ", ".join(f"`{a}`" for a in RUN_ATTRIBUTES) + ".",
        "A run writes `OUT.h5.partial` and renames it to `OUT.h5` when it ends; until then the",
        "state a `--resume` starts from is kept beside it in `OUT.h5.state.npz` (array `state`,",
        "the gap or pressure field, and `after_step`), never in the results file. A resumed",
        "file adds `resumed`: a JSON list with, for each resume, `after_step`, `time`, the",
        "`petsc_contact_commit` that computed the steps from there on and `from_saved_state`",
        "(false when the state file was lost and the next step started from first touch: the",
        "same result to the solver's tolerance, at a different cost).",
        "",
    ]

    def table(title: str, intro: str, entries: dict[str, Entry]) -> None:
        lines.extend([f"## {title}", "", intro, "", "| dataset | units | description |"])
        lines.append("| --- | --- | --- |")
        lines.extend(f"| `{k}` | {e.units} | {e.description} |" for k, e in entries.items())
        lines.append("")

    table(
        "periodic and demo",
        "One entry per load step; fields with `--fields`; `stiffness` with `--stiffness`.",
        GEOMETRIES["periodic"],
    )
    table("punch", "One entry per approach or force.", GEOMETRIES["punch"])
    table(
        "ensemble summary",
        "Each quantity also has `_mean`, `_std`, `_sem` and `_count` over seeds. Attributes: "
        "`geometry`, `command_line`, `parameters` (the pressures resolved), `petsc_options`, "
        "`versions`, `mpi_size`, `seed_files`, `complete`.",
        ENSEMBLE,
    )
    table(
        "compare",
        "One group per solver, one entry per TAO iteration. Group attributes: `reason`, "
        "`converged`, `iterations`, `solve_time`, `verification`, `petsc_options` and, for an "
        "options file, `options_file_text`. Root attributes add `reference_mean_gap`, "
        "`reference_natural_residual`, `reference_tolerance`, `reference_iterations`.",
        COMPARE,
    )
    table("experiment", "Attributes: `block_modulus`, `thickness`, `table`, `formula`.", EXPERIMENT)
    table(
        "theory",
        "Persson's theory from a map's spectrum. Attributes: the run record (as above) and "
        "`u0`, `beta` (p = beta E* exp(-u_bar/u0)), `hurst_fit`, `fit_range`, "
        "`crossover_pressure`, `crossover_pressure_appendix`.",
        THEORY,
    )
    return "\n".join(lines).rstrip() + "\n"


RUN_ATTRIBUTES = (
    "geometry",
    "command_line",
    "parameters",
    "petsc_options",
    "versions",
    "mpi_size",
    "length",
    "lengths",
    "length_unit",
    "modulus",
    "units",
    "rms_height",
    "rms_slope",
    "fft_backend",
    "seed",
    "hurst",
    "rolloff_ratio",
    "cutoff_ratio",
    "grid",
    "heights_file",
    "heights_sha256",
    "heights_reader",
    "heights_channel",
    "heights_channel_index",
    "file_lengths",
    "file_unit",
    "metadata_overridden",
    "created",
    "complete",
)


@contextmanager
def atomic_h5(path: str) -> Iterator[Any]:
    """An HDF5 file written as ``path.partial`` and renamed to ``path`` only when complete."""
    import h5py

    partial = partial_path(path)
    with h5py.File(partial, "w") as f:
        yield f
    os.replace(partial, path)
