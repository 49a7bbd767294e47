"""A run, described: the scene, its loads, the solver's options and what to keep.

:class:`Run` is what ``petsc-contact periodic`` and ``punch`` take on the command line, as one
typed value; :func:`~petsc_contact.workflows.runner.run_contact` runs it, resume and pause
included, and the ensemble and the paper's study are lists of runs.  Its field names are the
command line's options (``rms_slope`` is ``--rms-slope``), so a file's ``parameters`` record
is the description, and :meth:`Run.arguments` gives the command line back.

A surface is generated (``grid``, ``hurst`` and ``rms_slope`` or ``rms_height``: paper Eq. 5)
or given as ``heights``: a file of any supported format, a 2-D array, or a SurfaceTopography
``Topography``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np

from ..conventions.units import METRES, NEWTONS, PASCALS, parse_quantity

GEOMETRIES = ("periodic", "punch")


@dataclass(frozen=True)
class Run:
    """One contact run (the options of ``petsc-contact periodic`` and ``punch``).

    Attributes
    ----------
    geometry
        ``periodic`` (load controlled, a periodic cell) or ``punch`` (a rigid rough punch on
        a free half-space, by approaches or forces).
    heights, channel, height_unit, override_metadata, fill_undefined, detrend
        A measured surface: a file path, a 2-D array or a SurfaceTopography ``Topography``;
        which channel; the heights' unit when the file has none; whether ``length`` and
        ``height_unit`` replace the file's own; how undefined points are filled (``error``,
        ``mean``, ``harmonic``); what is removed (``none``, ``height``, ``slope``,
        ``curvature``).
    grid, hurst, rms_slope, rms_height, rolloff_ratio, cutoff_ratio, seed, exact_rms
        A generated surface (paper Eq. 5): ``N`` or ``(NX, NY)``, the Hurst exponent, one
        rms target, ``L/lambda_r``, ``L/lambda_1`` (default: the Nyquist limit), the seed,
        and whether the realisation is rescaled to the target exactly.
    cut_from
        A punch face cut from a larger surface: ``M`` (> 1) generates the periodic surface
        of ``M`` times the sides with the same pixel size and spectrum (its ``L/lambda_r``
        and ``L/lambda_1`` are ``M`` times the run's) and keeps its central footprint, with
        the tilt and edges of the longer wavelengths; 1 (default): the face is itself a
        periodic surface.
    length, modulus
        The sides (``"100um"``, ``"150um,100um"``, ``1.0`` or ``(Lx, Ly)``; default: the
        file's, else 1) and the contact modulus ``E*`` (``1e9``, or ``"1GPa"``: pressures
        are in its unit).
    pressures, sweep, approaches, forces
        The loads: nominal pressures (periodic; the punch: over its face), approaches or
        forces (punch), or a sweep ``(N,)`` or ``(N, min, max)`` of log-spaced ones (default
        range: see the CLI).  A value may carry its unit: ``"2MPa"``, ``"10nm"``, ``"1mN"``.
    footprint, flat_stiffness, stiffness
        The punch's outline (``square``, ``disk``) and its flat-punch reference (``grid``,
        ``analytic``); whether every step adds the exact stiffness.
    output, fields, scalars_only, resume, overwrite, stop_after
        The HDF5 file (none: results only in memory), whether the fields of every step are
        stored, whether the height map is left out, whether an interrupted run is continued
        or (``overwrite``) its finished steps deleted to start afresh (neither: an output
        with finished steps is refused), and after how many minutes the run pauses (between
        steps).
    options
        PETSc options for this run (``("-tao_type", "bncg")``).
    options_prefix
        The prefix this run's solvers read their PETSc options with (``"a_"``: ``-a_tao_type``).
    skip_memory_check
        Run even when the estimated memory exceeds what the machine has available.
    """

    geometry: str = "periodic"
    heights: Any = None
    channel: str | int | None = None
    height_unit: str | None = None
    override_metadata: bool = False
    fill_undefined: str = "error"
    detrend: str = "none"
    grid: int | tuple[int, int] | None = None
    hurst: float | None = None
    rms_slope: float | None = None
    rms_height: float | None = None
    rolloff_ratio: float = 1.0
    cutoff_ratio: float | None = None
    seed: int = 0
    exact_rms: bool = False
    cut_from: int = 1
    length: Any = None
    modulus: float | str = 1.0
    pressures: Sequence[float | str] | None = None
    sweep: Sequence[float | str] | None = None
    approaches: Sequence[float | str] | None = None
    forces: Sequence[float | str] | None = None
    footprint: str = "square"
    flat_stiffness: str = "grid"
    stiffness: bool = False
    output: str | None = None
    fields: bool = False
    scalars_only: bool = False
    resume: bool = False
    overwrite: bool = False
    stop_after: float | None = None
    skip_memory_check: bool = False
    options: tuple[str, ...] = field(default=(), compare=False)
    options_prefix: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        """Check the numbers and the files (``ValueError`` naming the option as the command
        line does): a heights file must be a regular, non-empty file, and the output (with
        its ``OUT.csv``) a regular file or a new name that is not the heights file."""
        from ..conventions.validation import non_negative, positive
        from ..io.paths import check_input, check_outputs
        from ..io.store import csv_path

        if self.heights_file is not None:
            check_input(self.heights_file, "--heights")
        if self.output is not None:
            outputs = [("--output", self.output), ("the table of --output", csv_path(self.output))]
            check_outputs(outputs, [("--heights", self.heights_file)])
        if self.geometry not in GEOMETRIES:
            raise ValueError(f"geometry must be one of {', '.join(GEOMETRIES)}: {self.geometry}")
        positive("--modulus", self.modulus_value)
        if self.cut_from < 1:
            raise ValueError(f"--cut-from must be a whole number >= 1, got {self.cut_from}")
        if self.stop_after is not None:
            non_negative("--stop-after", self.stop_after)
        for name, units in (("pressures", PASCALS), ("approaches", METRES), ("forces", NEWTONS)):
            values = getattr(self, name)
            if values is None or self.sweep is not None:
                continue
            if len(values) == 0:
                raise ValueError(f"--{name} needs at least one value")
            check = non_negative if name == "approaches" else positive  # an approach may be 0
            for v in values:
                check(f"--{name}", parse_quantity(v, units, f"--{name}").value)

    @property
    def modulus_value(self) -> float:
        """The contact modulus ``E*`` in the run's pressure unit."""
        return parse_quantity(self.modulus, PASCALS, "--modulus").value

    @property
    def pressure_unit(self) -> str | None:
        """The run's pressure unit: the modulus's (``--modulus 1GPa``), or none."""
        return parse_quantity(self.modulus, PASCALS, "--modulus").unit

    @property
    def measured(self) -> bool:
        """Whether the surface is given (a file, an array, a topography), not generated."""
        return self.heights is not None

    @property
    def heights_file(self) -> str | None:
        """The path of a surface given as a file."""
        return self.heights if isinstance(self.heights, str) else None

    def with_(self, **changes: Any) -> Run:
        """A copy with some fields changed (``run.with_(seed=3, output="s3.h5")``)."""
        return replace(self, **changes)

    def parameters(self) -> dict[str, Any]:
        """What a results file records as ``parameters`` (JSON values; an array or a
        topography given as ``heights`` is recorded by its kind, its file by its path)."""
        out: dict[str, Any] = {"command": self.geometry}
        for f in fields(self):
            if f.name in ("geometry", "options"):
                continue
            value = getattr(self, f.name)
            if f.name == "heights" and value is not None and not isinstance(value, str):
                value = "array" if isinstance(value, np.ndarray) else type(value).__name__
            out[f.name] = list(value) if isinstance(value, (tuple, np.ndarray)) else value
        return out

    def arguments(self) -> list[str]:
        """The command line that describes this run (``periodic --grid 512 ...``): every
        field that differs from its default, as the CLI spells it."""
        out = [self.geometry]
        defaults = Run()
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name in ("geometry", "options") or value == getattr(defaults, f.name):
                continue
            flag = "--" + f.name.replace("_", "-")
            if isinstance(value, bool):
                out.append(flag)
            elif isinstance(value, (list, tuple)):
                out += [flag, ",".join(f"{v:g}" if isinstance(v, float) else str(v) for v in value)]
            elif isinstance(value, (str, int, float)):
                out += [flag, f"{value:g}" if isinstance(value, float) else str(value)]
        return [*out, *self.options]
