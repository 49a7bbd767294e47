"""A run, described: the scene, its loads, the solver's options and what to keep.

:class:`Run` is what ``petsc-contact periodic`` and ``punch`` take on the command line, as one
typed value; :func:`~petsc_contact.workflows.runner.run_contact` runs it, resume and pause
included, and the ensemble and the paper's study are lists of runs.  Its field names are the
command line's options (``rms_slope`` is ``--rms-slope``), so a file's ``parameters`` record
is the description, and :meth:`Run.arguments` gives the command line back.  Each field is
described once as an option, with its help, unit and default, in
:data:`~petsc_contact.workflows.options.OPTIONS`, from which the command line, docs/cli.md
and the fields' defaults are made.  A run is a description: it reads no file and loads no
PETSc (:func:`~petsc_contact.workflows.runner.prepare` checks its files).

A surface is generated (``grid``, ``hurst`` and ``rms_slope`` or ``rms_height``: paper Eq. 5)
or given as ``heights``: a file of any supported format, a 2-D array, or a SurfaceTopography
``Topography``.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np

from ..conventions.units import METRES, NEWTONS, PASCALS, parse_quantity, pressure_value
from ..conventions.validation import log_range, non_negative, positive
from ..conventions.warnings import ConvertedLoads, user_level
from ..interactions.hard_wall import HARD_WALL
from ..interactions.hardness import HardnessCap
from ..interactions.interaction import Interaction
from ..substrates.layer import check_layer
from .options import check_choices, check_rules, grid_size, run_default

GEOMETRIES = ("periodic", "punch")
LOADS = ("pressures", "sweep", "approaches", "forces", "mean_gaps")


def _listed(value: Any) -> Any:
    """Loads (or a sweep) as a sequence: a number is one item, text with commas its items
    (``"1e-3,2MPa"``, as the command line reads it), an array its values; a sequence as
    it is."""
    if isinstance(value, str):
        return tuple(item.strip() for item in value.split(","))
    if isinstance(value, (int, float, np.number)):
        return (value,)
    if isinstance(value, np.ndarray):
        return tuple(value.ravel().tolist())
    return value


def swept(
    spec: Sequence[float | str],
    low: float,
    high: float,
    value: Callable[[float | str], float] = float,
) -> list[float]:
    """The loads of a sweep ``(N,)`` or ``(N, MIN, MAX)``, read by its rule
    (:func:`~petsc_contact.workflows.options.sweep_spec`: the command line's and ``Run``'s):
    ``N`` log-spaced, by default from ``low`` to ``high``; ``value`` turns a bound given with
    a unit (``"1kPa"``) into the run's units, where the rule's ``0 < MIN < MAX`` is checked."""
    if len(spec) == 3:
        n, lo, hi = float(spec[0]), value(spec[1]), value(spec[2])
        if any(isinstance(v, str) for v in spec[1:]):  # a bound with a unit, now in the run's
            log_range("the sweep", n, (lo, hi))
    else:
        n, lo, hi = float(spec[0]), low, high
    return [float(v) for v in np.geomspace(lo, hi, int(n))]


def cycled(
    spec: Sequence[float | str], value: Callable[[float | str], float] = float
) -> list[float]:
    """The nominal pressures of an adhesive load cycle ``(N, PMIN, PMAX)`` (the periodic
    ``--sweep`` with ``--adhesion``; ``value`` turns a bound given with a unit into the run's
    units): ``N`` equally spaced up to ``PMAX`` (``PMAX/N, ..., PMAX``: loading), then ``N``
    equally spaced down to ``PMIN`` (unloading, into tension where ``PMIN < 0``);
    ``ValueError`` in one line unless ``PMIN < PMAX`` and ``PMAX > 0`` (bounds with units are
    compared here, numbers by the rule: :func:`~petsc_contact.workflows.options.cycle_spec`)."""
    n, low, high = int(float(spec[0])), value(spec[1]), value(spec[2])
    if not (low < high and high > 0):
        raise ValueError(
            f"--sweep: a load cycle needs PMIN < PMAX and PMAX > 0, got {low:g} and {high:g}"
        )
    loading = high * np.arange(1, n + 1) / n
    unloading = high - (high - low) * np.arange(1, n + 1) / n
    return [float(p) for p in (*loading, *unloading)]


@dataclass(frozen=True)
class Run:
    """One contact run (the options of ``petsc-contact periodic`` and ``punch``).

    Attributes
    ----------
    geometry
        ``periodic`` (a periodic cell, by nominal pressures or mean gaps) or ``punch`` (a
        rigid rough punch on a free half-space, by approaches or forces).
    heights, channel, height_unit, override_metadata, fill_undefined, detrend
        A measured surface in any form
        (:func:`~petsc_contact.io.topography.as_topography`): a file's path, a 2-D array,
        :func:`~petsc_contact.io.topography.read_topography`'s result (its sides and unit)
        or a SurfaceTopography ``Topography``; which channel (of a file); the heights' unit
        when the file has none; whether ``length`` and ``height_unit`` replace the file's own;
        how undefined points are filled (``error``, ``mean``, ``harmonic``); what is removed
        (``none``, ``height``, ``slope``, ``curvature``).
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
    pressures, sweep, approaches, forces, mean_gaps
        The loads, one kind per run: nominal pressures (periodic; the punch: over its face),
        approaches or forces (punch), mean gaps (periodic: displacement control, the nominal
        pressure each needs found by Newton's steps), or a sweep ``(N,)`` or
        ``(N, min, max)`` of log-spaced ones: nominal pressures on a periodic run, approaches
        on the punch (default range: see the CLI;
        :meth:`with_` keeps a sweep's meaning across geometries).  A value may carry its
        unit: ``"2MPa"``, ``"10nm"``, ``"1mN"``; one load (``pressures=1e-3``) or a sweep's
        count alone (``sweep=4``) needs no tuple, and text with commas is read as the
        command line reads it (``"1e-3,2MPa"``); a mean gap is in the unit of ``length``
        (``"10nm"`` where it has one).
    thickness, poisson, base
        The periodic geometry's elastic body: a layer of thickness ``thickness`` (a length,
        ``"10um"`` with a unit; ``None``, the default: the half-space), its Poisson ratio (0 to
        0.5; ``modulus`` stays its contact modulus ``E/(1 - nu^2)``) and how it rests on its
        rigid base (``bonded``, ``frictionless``;
        :class:`~petsc_contact.substrates.layer.PeriodicLayer`).
    footprint, flat_stiffness, hardness, stiffness
        The punch's outline (``square``, ``disk``) and its flat-punch reference (``grid``,
        ``analytic``: the exact continuum value, ``king``: King's estimate for a square); the
        hardness the pressure is capped at, on either geometry (``None``: the hard wall;
        :class:`~petsc_contact.interactions.hardness.HardnessCap`); whether every step adds
        the exact stiffness.
    adhesion, work_of_adhesion, interaction_range
        An adhesive law on the half-space, periodic or under the punch (``exponential``,
        ``maugis``; ``None``: the hard wall), its work of adhesion ``w`` (units of ``E*``
        times the length unit) and range ``rho`` (a length, ``"5nm"`` with a unit;
        :class:`~petsc_contact.interactions.adhesion.Adhesion`): the nominal pressures and
        the punch's forces and approaches may then be zero or negative, and a periodic sweep
        ``(N, PMIN, PMAX)`` is a load cycle (:func:`cycled`).
    output, fields, scalars_only, resume, overwrite, stop_after
        The HDF5 file (none: results only in memory), whether the fields of every step are
        stored, whether the height map is left out, whether an interrupted run is continued
        or (``overwrite``) its finished steps deleted to start afresh (neither: an output
        with finished steps is refused), and after how many minutes the run pauses (between
        steps).
    options
        PETSc options for this run (``("-tao_type", "bncg")``, the same as one string or a
        dict, as :func:`~petsc_contact.workflows.periodic_sweep.periodic_contact` takes them).
    options_prefix
        The prefix this run's solvers read their PETSc options with (``"a_"``: ``-a_tao_type``).
    skip_memory_check
        Run even when the estimated memory exceeds what the machine has available.
    device
        Where the solves run (:mod:`~petsc_contact.devices.device`): ``cpu`` (PETSc/TAO),
        ``gpu`` (the package's CG on CuPy) or ``cpu-array`` (the GPU's code on NumPy); the
        array devices read ``options`` as :class:`~petsc_contact.solver.driver.SolveSettings`
        does; ``cpu-array`` runs on any number of ranks, ``gpu`` on one.
    """

    geometry: str = "periodic"
    heights: Any = run_default("heights")
    channel: str | int | None = run_default("channel")
    height_unit: str | None = run_default("height_unit")
    override_metadata: bool = run_default("override_metadata")
    fill_undefined: str = run_default("fill_undefined")
    detrend: str = run_default("detrend")
    grid: int | tuple[int, int] | None = run_default("grid")
    hurst: float | None = run_default("hurst")
    rms_slope: float | None = run_default("rms_slope")
    rms_height: float | None = run_default("rms_height")
    rolloff_ratio: float = run_default("rolloff_ratio")
    cutoff_ratio: float | None = run_default("cutoff_ratio")
    seed: int = run_default("seed")
    exact_rms: bool = run_default("exact_rms")
    cut_from: int = run_default("cut_from")
    length: Any = run_default("length")
    modulus: float | str = run_default("modulus")
    pressures: Sequence[float | str] | None = run_default("pressures")
    sweep: Sequence[float | str] | None = run_default("sweep")
    approaches: Sequence[float | str] | None = run_default("approaches")
    forces: Sequence[float | str] | None = run_default("forces")
    mean_gaps: Sequence[float | str] | None = run_default("mean_gaps")
    thickness: float | str | None = run_default("thickness")
    poisson: float = run_default("poisson")
    base: str = run_default("base")
    footprint: str = run_default("footprint")
    flat_stiffness: str = run_default("flat_stiffness")
    hardness: float | str | None = run_default("hardness")
    adhesion: str | None = run_default("adhesion")
    work_of_adhesion: float | None = run_default("work_of_adhesion")
    interaction_range: float | str | None = run_default("interaction_range")
    stiffness: bool = run_default("stiffness")
    output: str | None = run_default("output")
    fields: bool = run_default("fields")
    scalars_only: bool = run_default("scalars_only")
    resume: bool = run_default("resume")
    overwrite: bool = run_default("overwrite")
    stop_after: float | None = run_default("stop_after")
    skip_memory_check: bool = run_default("skip_memory_check")
    device: str = run_default("device")
    options: tuple[str, ...] = field(default=(), compare=False)
    options_prefix: str = field(default=run_default("options_prefix"), compare=False)

    def __post_init__(self) -> None:
        """Put the fields in one form and check their values (``ValueError`` naming the
        option as the command line does); nothing is read (the files are checked when the
        run is prepared: :func:`~petsc_contact.workflows.runner.check_files`).

        A path given as ``heights`` becomes its text; a single load, sweep count or grid size
        (``pressures=1e-3``, ``sweep=4``, ``grid=64``) or text with commas (``"1e-3,2MPa"``,
        ``"128,64"``) is taken as the command line takes it, and PETSc options given as one
        string or a dict become a tuple."""
        from ..io.store import check_resume_or_overwrite

        self._normalise()
        if self.geometry not in GEOMETRIES:
            raise ValueError(f"geometry must be one of {', '.join(GEOMETRIES)}: {self.geometry}")
        positive("--modulus", self.modulus_value)
        _ = self.interaction  # --hardness checked
        check_choices(lambda name: getattr(self, name))  # --device, --footprint, ...
        check_rules(lambda name: getattr(self, name))  # --sweep, --cut-from, --stop-after
        self._check_layer()
        check_resume_or_overwrite(self.resume, self.overwrite)
        self._check_mean_gaps()
        self._check_adhesion()
        loads = (("pressures", PASCALS), ("approaches", METRES), ("forces", NEWTONS))
        for name, units in (*loads, ("mean_gaps", METRES)):
            values = getattr(self, name)
            if values is None or self.sweep is not None:
                continue
            flag = "--" + name.replace("_", "-")
            if len(values) == 0:
                raise ValueError(f"{flag} needs at least one value")
            check = non_negative if name == "approaches" else positive  # an approach may be 0
            if name != "mean_gaps" and self.adhesion is not None:
                continue  # tension is held by the attraction: any finite load
            for v in values:
                check(flag, parse_quantity(v, units, flag).value)

    def _check_mean_gaps(self) -> None:
        """``ValueError`` in one line for mean gaps on the punch, or beside another load."""
        if self.mean_gaps is None:
            return
        if self.geometry != "periodic":
            raise ValueError("--mean-gaps is a periodic run's load; the punch takes approaches")
        others = [f"--{n}" for n in ("pressures", "sweep") if getattr(self, n) is not None]
        if others:
            raise ValueError(f"give one kind of load: --mean-gaps or {' or '.join(others)}")
        if self.hardness is not None:
            raise ValueError("--mean-gaps with --hardness: a capped periodic run takes --pressures")

    def _check_adhesion(self) -> None:
        """``ValueError`` in one line for an adhesive law without its work and range (or
        those without it), or beside what it does not yet combine with."""
        work, reach = self.work_of_adhesion, self.interaction_range
        if self.adhesion is None:
            if work is not None or reach is not None:
                raise ValueError("--work-of-adhesion and --interaction-range need --adhesion")
            low = self.sweep[1] if self.sweep is not None and len(self.sweep) == 3 else 1.0
            if not isinstance(low, str) and low < 0:
                raise ValueError(
                    "--sweep: a tensile PMIN < 0 is an adhesive load cycle's (--adhesion)"
                )
            return
        if work is None or reach is None:
            raise ValueError("--adhesion needs --work-of-adhesion W and --interaction-range RHO")
        others = ("thickness", "hardness", "stiffness")
        given_others = [o for o in others if getattr(self, o) not in (None, False)]
        if given_others:
            flags = ", ".join("--" + o.replace("_", "-") for o in given_others)
            raise ValueError(
                f"--adhesion with {flags}: an adhesive run is on the half-space and takes "
                "--pressures, a --sweep (a load cycle) or --mean-gaps (periodic), --approaches, "
                "--forces or --pressures (punch)"
            )
        if self.sweep is not None and self.geometry != "periodic":
            raise ValueError(
                "--sweep with --adhesion is the periodic cell's load cycle: give the punch "
                "--approaches, --forces or --pressures"
            )
        if self.sweep is not None and len(self.sweep) != 3:
            raise ValueError("--sweep with --adhesion is a load cycle: give N,PMIN,PMAX")
        positive("--work-of-adhesion", work)
        positive("--interaction-range", parse_quantity(reach, METRES, "--interaction-range").value)

    def _check_layer(self) -> None:
        """``ValueError`` in one line for a layer's thickness (positive, on the periodic
        geometry), Poisson ratio or base that cannot be."""
        check_layer(self.poisson, self.base)
        if self.thickness is None:
            return
        if self.geometry != "periodic":
            raise ValueError(
                "--thickness is the periodic geometry's: the punch presses a half-space"
            )
        if self.hardness is not None:
            raise ValueError("--thickness with --hardness: the capped cell is a half-space's")
        positive("--thickness", parse_quantity(self.thickness, METRES, "--thickness").value)

    def _normalise(self) -> None:
        """Put the fields given in another natural form in the one the run uses (frozen:
        through ``object.__setattr__``); ``ValueError`` naming the option for a wrong count."""
        if isinstance(self.heights, os.PathLike):
            object.__setattr__(self, "heights", os.fspath(self.heights))
        for name in LOADS:
            object.__setattr__(self, name, _listed(getattr(self, name)))
        if self.grid is not None:
            object.__setattr__(self, "grid", grid_size(self.grid))
        if not isinstance(self.length, str | None) and np.size(self.length) not in (1, 2):
            raise ValueError(f"--length takes L or (LX, LY), got {self.length!r}")
        if not isinstance(self.options, tuple):
            from ..backend._petsc import option_list

            object.__setattr__(self, "options", tuple(option_list(self.options)))
        from ..solver.driver import check_option_values

        check_option_values(self.options)  # -tao_max_it abc: refused before anything runs

    @property
    def modulus_value(self) -> float:
        """The contact modulus ``E*`` in the run's pressure unit."""
        return parse_quantity(self.modulus, PASCALS, "--modulus").value

    @property
    def pressure_unit(self) -> str | None:
        """The run's pressure unit: the modulus's (``--modulus 1GPa``), or none."""
        return parse_quantity(self.modulus, PASCALS, "--modulus").unit

    @property
    def interaction(self) -> Interaction:
        """The law at the surface: the hard wall, or the cap of ``hardness`` (in the run's
        pressure unit); ``ValueError`` in one line for a hardness not positive."""
        if self.hardness is None:
            return HARD_WALL
        return HardnessCap(pressure_value(self.hardness, self.pressure_unit, "--hardness"))

    @property
    def measured(self) -> bool:
        """Whether the surface is given (a file, an array, a topography), not generated."""
        return self.heights is not None

    @property
    def heights_file(self) -> str | None:
        """The path of a surface given as a file."""
        return self.heights if isinstance(self.heights, str) else None

    def with_(self, **changes: Any) -> Run:
        """A copy with some fields changed (``run.with_(seed=3, output="s3.h5")``).

        A load keeps its meaning across a change of ``geometry`` that gives no load: a
        periodic run's ``sweep=(N, MIN, MAX)``, nominal pressures, becomes on the punch
        (which sweeps approaches) those ``pressures``, nominal pressures over its face, with
        a :class:`~petsc_contact.conventions.warnings.ConvertedLoads` note; a punch's,
        approaches, is refused on a periodic run (``ValueError`` naming what to give).  A
        sweep's count alone, ``sweep=N``, is the new geometry's default sweep."""
        new = replace(self, **changes)
        sweep = self.sweep
        kept = new.geometry == self.geometry or any(k in changes for k in LOADS)
        if sweep is None or len(sweep) != 3 or kept:
            return new
        if new.geometry == "periodic":
            raise ValueError(
                f"the punch's sweep={sweep!r} is of approaches, which a periodic run does "
                "not take: give its nominal pressures with the geometry, "
                "run.with_(geometry='periodic', sweep=...) or pressures=..."
            )
        unit = new.pressure_unit
        pressures = swept(sweep, 0.0, 0.0, lambda v: pressure_value(v, unit, "--sweep"))
        warnings.warn(
            f"the periodic run's sweep={sweep!r} is of nominal pressures, the punch's of "
            f"approaches: the punch takes its {len(pressures)} pressures ({pressures[0]:g} to "
            f"{pressures[-1]:g}) as pressures=, nominal pressures over its face (give a load "
            "with geometry= to choose another)",
            ConvertedLoads,
            stacklevel=user_level(),
        )
        return replace(new, sweep=None, pressures=tuple(pressures))

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

    def _repr_html_(self) -> str:
        """A notebook's display: the fields that differ from their defaults (as
        :meth:`parameters` records them) and the PETSc options."""
        from ..io.tables import html_table

        defaults = Run().parameters()
        given = {k: v for k, v in self.parameters().items() if k != "command" and v != defaults[k]}
        if self.options:
            given["options"] = " ".join(self.options)
        return html_table(f"Run ({self.geometry})", given)

    def arguments(self) -> list[str]:
        """The command line that describes this run (``periodic --grid 512 ...``): every
        field that differs from its default, as the CLI spells it (a map given as an array
        or a topography has no spelling there: it is left out)."""
        out = [self.geometry]
        defaults = Run()
        for f in fields(self):
            value = getattr(self, f.name)
            skipped = f.name in ("geometry", "options") or isinstance(value, np.ndarray)
            if skipped or value == getattr(defaults, f.name):
                continue
            flag = "--" + f.name.replace("_", "-")
            if isinstance(value, bool):
                out.append(flag)
            elif isinstance(value, (list, tuple)):
                out += [flag, ",".join(f"{v:g}" if isinstance(v, float) else str(v) for v in value)]
            elif isinstance(value, (str, int, float)):
                out += [flag, f"{value:g}" if isinstance(value, float) else str(value)]
        return [*out, *self.options]
