"""The schema of the HDF5 results: every dataset any command writes, with its units and
description (the tables below, rendered as ``docs/output-schema.md``), how values are stored
(attributes, per-step scalars) and the helpers that attach descriptions.  How a run's files
are written durably is :mod:`petsc_contact.io.store`; what reproduces a result,
:mod:`petsc_contact.io.provenance`.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..physics.observables import MIN_CONTACT_PIXELS


def write_attributes(obj: Any, attributes: dict[str, Any]) -> None:
    """HDF5 attributes of a file or group: dicts and lists as JSON, ``None`` as ``''``."""
    attrs = obj.attrs
    for key, value in attributes.items():
        attrs[key] = (
            json.dumps(value)
            if isinstance(value, (dict, list, tuple))
            else ("" if value is None else value)
        )


MISSING = {np.float64: np.nan, np.int64: -1}  # the earlier steps' value of a new column


def h5_dtype(value: Any) -> Any:
    """HDF5 dtype of one per-step value (a scalar, or an array: its elements')."""
    import h5py

    if isinstance(value, np.ndarray):
        return np.int64 if value.dtype.kind in "iu" else np.float64
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
# ``--modulus`` (written as it, ``GPa``, when it has one); ``1`` is
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
    iterations=(
        "count",
        "TAO iterations of the step (punch with forces, periodic with mean gaps: summed over "
        "Newton; periodic with --hardness where cap_reached: the hard wall's solve and the "
        "capped Newton's together)",
    ),
    solve_time=("s", "wall time of the solve, the slowest rank's"),
    converged=(
        "bool",
        "TAO converged and the package's own verification passed (the natural residual within "
        "10 x effective_tolerance, no negative gap)",
    ),
    accurate=(
        "bool",
        "every measured accuracy figure (kkt_residual, force_balance, complementarity, "
        "stiffness_residual) within the package's accuracy, whatever the options asked "
        "(docs/solvers.md); the exit status is 1 unless every step converged and is accurate",
    ),
    verification=(
        "text",
        "'ok'; or why the step's answer cannot be used (converged false); or which measured "
        "figures are beyond the package's accuracy (accurate false)",
    ),
    tao_type=(
        "text",
        "TAO type (bncg); cg and pk for the package's solvers (compare's names), python:CLASS "
        "for another Python type",
    ),
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
    effective_tolerance=(
        "1",
        "the gradient tolerance the solve stopped against, as TAO's default test reads them: "
        "the largest of tolerance, -tao_grtol x |f| and -tao_gttol x the first gradient norm",
    ),
    accuracy_limit=(
        "1",
        "the package's accuracy at this step: the largest kkt_residual and complementarity "
        "(periodic: and force_balance) of an accurate step, 100 x the default tolerance 1e-8 "
        "(or x the rounding floor); punch force_balance and stiffness_residual: 1e-4",
    ),
    stiffness_iterations=("count", "CG iterations of the exact stiffness solve"),
    stiffness_residual=(
        "1",
        "residual of the exact stiffness solve A_MM y = 1_M recomputed from y, in its "
        "preconditioner's norm, relative (punch: the larger of the step's and the flat "
        "punch's); NaN where not solved",
    ),
    stiffness_tolerance=(
        "1",
        "the relative tolerance the stiffness solve was asked for (-stiffness_ksp_rtol, on "
        "its preconditioned residual)",
    ),
    stiffness_time=(
        "s",
        "wall time of the exact stiffness solve with its preconditioner's set-up, the slowest "
        "rank's",
    ),
    complementarity=(
        "1",
        "sum(p+ g) / (sum(p+) l): the force-weighted mean gap in units of l = h_rms (punch: "
        "the rms recess), as Tamaas reports it",
    ),
    max_pressure=("pressure", "largest contact pressure"),
    min_gap=("length", "smallest gap (negative: the bound is violated)"),
    area_fraction=("1", "fraction of the pixels in contact (punch: of the footprint)"),
    contact_resolved=(
        "bool",
        f"at least {MIN_CONTACT_PIXELS} pixels in contact (the package's resolution rule): "
        "false marks a contact of a few pixels, whose area and stiffness the grid does not "
        "resolve (the printed table marks it UNRESOLVED)",
    ),
    full_contact=(
        "bool",
        "every pixel (punch: of the footprint) in contact: the load is at or beyond full "
        "contact, the run warns, and the interfacial stiffness there is NaN (docs/formulation.md)",
    ),
    contact_patches=(
        "count",
        "contact patches: clusters of contact pixels joined through their edges "
        "(periodic: across the cell's edges)",
    ),
    nominal_pressure=("pressure", "nominal pressure p0 (punch: F / Lp^2)"),
)
DISTRIBUTIONS = _entries(
    pressure_histogram=("count", "contact pixels per pressure bin (steps x bins)"),
    pressure_bins=("pressure", "pressure bin edges, 0 to the largest contact pressure"),
    gap_histogram=("count", "open pixels per gap bin (steps x bins)"),
    gap_bins=("length", "gap bin edges, 0 to the largest gap"),
    patch_size_histogram=(
        "count",
        "contact patches per size bin: 1, 2-3, 4-7, ... pixels (steps x bins)",
    ),
    largest_patch=("count", "pixels of the largest contact patch"),
    largest_patch_fraction=("1", "the largest patch's share of the pixels"),
    filled_contact_fraction=(
        "1",
        "share of the contact pixels whose heights were filled (--fill-undefined)",
    ),
    filled_load_fraction=("1", "share of the force carried by filled pixels"),
)
SECOND_DIMENSION = {  # the dimension of the per-step arrays' second axis
    "pressure_histogram": "bin",
    "gap_histogram": "bin",
    "pressure_bins": "edge",
    "gap_bins": "edge",
    "patch_size_histogram": "patch_bin",
}
PERIODIC_COLUMNS = _entries(
    mean_gap=("length", "mean gap u_bar"),
    contact_pressure_mean=("pressure", "mean over all pixels of the contact pressure (= p0)"),
    elastic_energy=("pressure*length", "elastic energy per apparent area, 1/2 <(g+h)(p-p0)>"),
    min_pressure=("pressure", "smallest pressure over all pixels (negative: tension)"),
    kkt_residual=(
        "1",
        "natural residual rms(min(k g, p)) / p0 (--hardness: the gap's, as the punch's, over "
        "h_rms)",
    ),
    force_balance=(
        "1",
        "abs(contact_pressure_mean - p0) / p0: the force the contact pressure misses (at most "
        "kkt_residual)",
    ),
    preconditioner_stiffness=(
        "pressure/length",
        "interfacial stiffness estimate the preconditioner was held by (path, not answer)",
    ),
    stiffness=(
        "pressure/length",
        "exact -dp0/du_bar with the contact set held fixed (NaN at full contact: unbounded)",
    ),
    target_mean_gap=("length", "the prescribed mean gap (displacement control, --mean-gaps)"),
    mean_gap_mismatch=(
        "1",
        "abs(mean_gap - target_mean_gap) / s (displacement control): s is the smaller of "
        "target_mean_gap and its approach from first touch, beyond 1e-4 not converged; with "
        "--adhesion s = target_mean_gap, beyond 1e-6 not converged (the loading machine)",
    ),
    mean_gap_tolerance=(
        "1",
        "the relative tolerance Newton's steps on ln p0 aimed at (displacement control)",
    ),
    newton_iterations=(
        "count",
        "Newton steps on the nominal pressure (displacement control) or, with --hardness, on "
        "the approach (punch: on the approach, load control)",
    ),
)
PUNCH_COLUMNS = _entries(
    approach=("length", "rigid approach beyond first touch"),
    force=("pressure*length^2", "total force F"),
    mean_gap=("length", "mean gap u_bar over the footprint (-dp/du_bar: K without paper Eq. 2)"),
    total_stiffness=("pressure*length", "dF/d delta with the contact set held fixed"),
    interfacial_stiffness=(
        "pressure/length",
        "interfacial stiffness per area (paper Eq. 2; NaN at full contact, unbounded, and "
        "where the step did not converge)",
    ),
    flat_punch_stiffness=(
        "pressure*length",
        "K_flat, the flat punch's stiffness used in paper Eq. 2: the same grid's flat punch "
        "(--flat-stiffness grid) or beta 2 E* sqrt(A/pi) (analytic, king; beta: "
        "flat_punch_beta)",
    ),
    flat_punch_beta=(
        "1",
        "the shape factor beta = K_flat / (2 E* sqrt(A/pi)) of paper Eq. 2's flat punch: "
        "analytic, the square's exact 1.0212 (Read's capacitance) or the disk's 1; king, "
        "King's estimate 1.012; grid, the same grid's flat punch's (a file without it is "
        "older: there analytic meant 1.012)",
    ),
    kkt_residual=("1", "natural residual rms(min(g, p/k)) / l, l the rms recess"),
    target_force=("pressure*length^2", "the prescribed force (load control)"),
    force_balance=(
        "1",
        "abs(force - target_force) / target_force (load control; NaN under approach control; "
        "beyond 1e-4 not converged)",
    ),
    newton_iterations=(
        "count",
        "Newton steps on the approach (load control; periodic: on the nominal pressure under "
        "displacement control, on the approach with --hardness)",
    ),
    stiffness=(
        "pressure/length",
        "the interfacial stiffness per area (--stiffness; NaN as interfacial_stiffness)",
    ),
)
PLASTIC = _entries(
    plastic_area_fraction=(
        "1",
        "fraction of the pixels (punch: of the footprint) at the hardness cap, p - k g > H "
        "(--hardness; in area_fraction too)",
    )
)
CAPPED_CELL = _entries(
    cap_reached=(
        "bool",
        "--hardness: false where the hard wall's answer stays at or below the cap (that is "
        "the capped answer: kkt_residual the hard wall's, over p0), true where the cell was "
        "then solved posed in the pressure (kkt_residual over h_rms)",
    ),
    approach=(
        "length",
        "--hardness: the rigid approach at which mean(p) = p0 (the cell posed in the "
        "pressure; it includes c p0, c the mean mode's compliance 2/(E* q0))",
    ),
    force=("pressure*length^2", "--hardness: the force p0 A the approach's Newton reached"),
    target_force=("pressure*length^2", "--hardness: the force p0 A it aimed at"),
    total_stiffness=(
        "pressure*length",
        "--hardness: dF/d delta with the elastic contact held and the plastic pixels at the "
        "cap; stiffness = 1/(A/total_stiffness - c)",
    ),
)
ADHESIVE = _entries(
    adhesive_pressure=(
        "pressure",
        "--adhesion: the mean attraction mean(phi'(g)); the mean wall reaction less it is the "
        "nominal pressure",
    ),
    pressure_scale=(
        "pressure",
        "--adhesion: the pressure scale P = max(|p0|, w/rho) that kkt_residual, force_balance "
        "and the tolerance are in units of (punch: p0 the force over the padded cell, 4 Lx Ly, "
        "or c0 |approach| under approaches, c0 = 1/G(q = 0))",
    ),
    interaction_energy=(
        "pressure*length",
        "--adhesion: the interaction energy per apparent area, mean(phi(g)) (-w in full contact)",
    ),
    pull_off_pressure=(
        "pressure",
        "--adhesion: the most tensile converged nominal pressure with contact on the unloading "
        "branch so far (the steps from the largest pressure on; NaN before any)",
    ),
    hysteresis_energy=(
        "pressure*length",
        "--adhesion --mean-gaps: the energy per apparent area the cycle lost, the work the "
        "loading machine did, -integral of nominal_pressure d mean_gap over the steps so far "
        "(trapezoids: a jump closed by the chord between its steps); NaN until a step is "
        "back at the first step's target_mean_gap, and after a step that did not converge",
    ),
    branch_jump=(
        "bool",
        "--adhesion: the contact area changed by more than half of the larger of this and the "
        "last converged step's (a jump into or out of contact; warned)",
    ),
)
COORDINATES = _entries(
    step=("count", "load step, counted from 1 as the printed table counts"),
    bin=("count", "a histogram's bin, counted from 0"),
    edge=("count", "a histogram's bin edge, counted from 0"),
    patch_bin=("count", "the smallest patch size of a patch size bin: 1, 2, 4, ... pixels"),
    seed=("count", "the seed of each member of an ensemble: the rows of its seeds x steps tables"),
    x=("length", "position of each row of the maps: the pixel centres, (i + 1/2) Lx/nx"),
    y=("length", "position of each column of the maps: the pixel centres, (j + 1/2) Ly/ny"),
)
FIELDS = _entries(
    heights=("length", "the height map as given or generated (n x n)"),
    gap=("length", "gap of every step, exactly zero in contact (steps x n x n)"),
    pressure=("pressure", "pressure of every step, exactly zero out of contact (steps x n x n)"),
    contact=("bool", "contact mask of every step, p > k g (steps x n x n)"),
    filled=("bool", "the pixels whose heights were undefined and filled (n x n)"),
    plastic_displacement=(
        "length",
        "depth the punch sinks into the pixels at the hardness cap (--hardness), 0 elsewhere "
        "(steps x n x n)",
    ),
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
    row=("count", "row of the measured table, counted from 1"),
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
    area_fraction=(
        "1",
        "Persson's relative contact area A/A0 = erf(sqrt(2) p / (E* h'_rms)), h'_rms^2 = "
        "2 pi int q^3 C dq over the spectrum (docs/formulation.md)",
    ),
)
ENTRIES = {
    **COORDINATES,
    **SOLVE_COLUMNS,
    **DISTRIBUTIONS,
    **PERIODIC_COLUMNS,
    **PUNCH_COLUMNS,
    **PLASTIC,
    **ADHESIVE,
    **FIELDS,
}
GEOMETRIES = {
    "periodic": {
        **COORDINATES,
        **SOLVE_COLUMNS,
        **DISTRIBUTIONS,
        **PERIODIC_COLUMNS,
        **PLASTIC,
        **CAPPED_CELL,
        **ADHESIVE,
        **FIELDS,
    },
    "punch": {
        **COORDINATES,
        **SOLVE_COLUMNS,
        **DISTRIBUTIONS,
        **PUNCH_COLUMNS,
        **PLASTIC,
        **ADHESIVE,
        "min_pressure": PERIODIC_COLUMNS["min_pressure"],
        **FIELDS,
    },
}


@dataclass(frozen=True)
class Frame:
    """What :func:`~petsc_contact.io.results.read_frame` gives of one kind of file: its rows
    in words, the names of its index and its columns, in order (those the file holds)."""

    rows: str
    index: tuple[str, ...]
    columns: tuple[str, ...]


def _run_frame(geometry: str) -> Frame:
    """A run's step table: its per-step scalars, in the schema's order."""
    beside = {*COORDINATES, *SECOND_DIMENSION, *FIELDS}  # per-step arrays and maps
    columns = tuple(k for k in GEOMETRIES[geometry] if k not in beside)
    return Frame("one per load step", ("step",), columns)


FRAMES = {  # by the file's kind: its geometry, or compare (a file with solver groups)
    "periodic": _run_frame("periodic"),
    "punch": _run_frame("punch"),
    "periodic ensemble": Frame(
        "one per load step",
        ("step",),
        (
            "nominal_pressure",
            *(
                f"{quantity}_{statistic}"
                for quantity in ENSEMBLE
                if quantity not in ("seeds", "nominal_pressure")
                for statistic in ENSEMBLE_STATISTICS
            ),
        ),
    ),
    "theory": Frame(
        "one per nominal pressure",
        ("step",),
        tuple(k for k in THEORY if k not in ("wavevector", "psd")),
    ),
    "experiment": Frame("one per row of the measured table", ("row",), tuple(EXPERIMENT)[1:]),
    "compare": Frame(
        "one per solver and TAO iteration, the solvers in the order of the root attribute "
        "`solvers`",
        ("solver", "iteration"),
        tuple(k for k in COMPARE if k != "iteration"),
    ),
}


def ensemble_entry(name: str) -> Entry:
    """The entry of an ensemble summary dataset, statistics (``mean_gap_sem``) and dimension
    scales (``seed``, ``step``) included."""
    if name in ENSEMBLE:
        return ENSEMBLE[name]
    if name in COORDINATES:
        return COORDINATES[name]
    quantity, _, statistic = name.rpartition("_")
    if quantity in ENSEMBLE and statistic in ENSEMBLE_STATISTICS:
        units = "count" if statistic == "count" else ENSEMBLE[quantity].units
        return Entry(units, f"{quantity}: {ENSEMBLE_STATISTICS[statistic]}, per step")
    raise KeyError(f"no schema entry for ensemble dataset '{name}'")


def in_unit(entry: Entry, length_unit: str = "", pressure_unit: str = "") -> Entry:
    """``entry`` with its symbolic ``length`` and ``pressure`` replaced by the run's units
    (``um`` and ``GPa``: ``pressure/length`` becomes ``GPa/um``); each left symbolic when the
    run has no such unit."""
    units = entry.units
    if length_unit:
        units = re.sub(r"\blength\b", length_unit, units)
    if pressure_unit:
        units = re.sub(r"\bpressure\b", pressure_unit, units)
    return Entry(units, entry.description)


def describe(dataset: Any, entry: Entry) -> None:
    """Attach ``units`` and ``description`` to an h5py dataset."""
    dataset.attrs["units"] = entry.units
    dataset.attrs["description"] = entry.description


def annotate(
    group: Any, lookup: Callable[[str], Entry], length_unit: str = "", pressure_unit: str = ""
) -> None:
    """Describe every dataset directly in ``group`` (in the run's units when given);
    ``KeyError`` for one the schema lacks."""
    for name, item in group.items():
        if hasattr(item, "shape"):
            describe(item, in_unit(lookup(name), length_unit, pressure_unit))


def schema_markdown() -> str:
    """``docs/output-schema.md``, generated from the tables above (a test keeps it current)."""
    lines = _introduction()
    _frames(lines)
    _dataset_tables(lines)
    return "\n".join(lines).rstrip() + "\n"


def _introduction() -> list[str]:
    """The page's title and what every file records, while a run is under way and after."""
    return [
        "# Output schema",
        "",
        "Generated from `petsc_contact/io/schema.py` by",
        "`petsc-contact schema > docs/output-schema.md`; a test fails when this page and the",
        "code disagree. Every dataset carries the `units` and `description` attributes listed",
        "here. Units are symbolic: `length` is the unit of `--length` and of the heights (a",
        "file whose run has a length unit writes that unit instead: `pressure/um`), `pressure`",
        "the unit of `--modulus`; `1` is dimensionless, `s` seconds of wall time.",
        "",
        "Every file of `periodic`, `demo`, `punch` and `compare` also records, as root",
        "attributes, what reproduces it: " + ", ".join(f"`{a}`" for a in RUN_ATTRIBUTES) + ".",
        "While a run is under way its finished steps are committed to `OUT.h5.partial` (the",
        "run record and every finished step's scalars as bare datasets, without the units,",
        "descriptions and dimension scales that the finished file gives them; replaced whole",
        "after each step), its",
        "heights and fields to `OUT.h5.parts/`, and the state a `--resume` starts from to",
        "`OUT.h5.state.npz` (on P ranks each rank its own rows: `heights.RofP.h5`,",
        "`step-00000k.RofP.h5` and `OUT.h5.state.RofP.npz`, R of P) (array `state`, the gap",
        "or pressure field, `after_step`, and",
        "`held` and `held_field_0`, what the sweep held: the load path's pressures, mean gaps",
        "and stiffnesses and its older gap, or the punch's last approach, force and dF/d delta);",
        "each part's SHA-256 is in the `.partial`'s attribute `parts`; `OUT.h5` is assembled",
        "from them when the run ends ([reliability.md](reliability.md)).",
        "A finished run's file labels its per-step datasets with the dimension `step` (1, 2,",
        "...) and its maps with `x` and `y` (pixel centres) as HDF5 dimension scales, so that",
        '`xarray.open_dataset(path, engine="h5netcdf")` gives labelled arrays; the step table is',
        "also written beside it as `OUT.csv` (one row per step, the columns below). The",
        "other files are labelled likewise: an ensemble's datasets with `seed` and `step`, a",
        "theory's with `step` and `wavevector`, each solver group of a comparison's with",
        "`iteration`. Every file reads as a table with `read_frame` ([tables](#tables)).",
        "A resumed file adds `resumed`: a JSON list with, for each resume, `after_step`, `time`,",
        "its `command_line`, `petsc_options` and `device` (a run paused on one device may",
        "finish on another), the `petsc_contact_commit` that computed the",
        "steps from there on and `from_saved_state` (false when the state file was missing or",
        "damaged and the next step started from first touch: the",
        "same result to the solver's tolerance, at a different cost).",
        "",
    ]


def _table(lines: list[str], title: str, intro: str, entries: dict[str, Entry]) -> None:
    """One section of the page: its ``title``, ``intro`` and a table of ``entries``."""
    lines.extend([f"## {title}", "", intro, "", "| dataset | units | description |"])
    lines.append("| --- | --- | --- |")
    lines.extend(f"| `{k}` | {e.units} | {e.description} |" for k, e in entries.items())
    lines.append("")


def _dataset_tables(lines: list[str]) -> None:
    """The datasets of each kind of file, one table each."""
    _table(
        lines,
        "coordinates",
        "Dimension scales of a run's file: `step` for every per-step dataset, `x` and `y` for "
        "the maps (`heights`, and the fields as `step x x x y`); of an ensemble's, `seed` and "
        "`step` (its tables `seed x step`); of a theory's, `step` and `wavevector`.",
        COORDINATES,
    )
    _table(
        lines,
        "periodic and demo",
        "One entry per load step; fields with `--fields`; `stiffness` with `--stiffness`.",
        {k: e for k, e in GEOMETRIES["periodic"].items() if k not in COORDINATES},
    )
    _table(
        lines,
        "punch",
        "One entry per approach or force.",
        {k: e for k, e in GEOMETRIES["punch"].items() if k not in COORDINATES},
    )
    _table(
        lines,
        "ensemble summary",
        "Each quantity also has `_mean`, `_std`, `_sem` and `_count` over seeds. Attributes: "
        "`geometry`, `command_line`, `parameters` (the pressures resolved), `petsc_options`, "
        "`versions`, `mpi_size`, `seed_files` (relative to the file's folder), `seed_created` "
        "(each seed file's `created` stamp: a replaced seed file is refused), `complete`.",
        ENSEMBLE,
    )
    _table(
        lines,
        "compare",
        "One group per solver, one entry per TAO iteration (`iteration`, each group's "
        "dimension scale); root attribute `solvers` lists them in order, each committed to "
        "`OUT.h5.partial` as it finishes (`compare --resume` keeps them, and solves again one "
        "whose options changed). Group attributes: `reason`, `converged`, `iterations`, "
        "`solve_time`, `verification`, `petsc_options` (the options that solver ran with: its "
        "own, then the command line's unprefixed ones and those with its prefix) and, for an "
        "options file, `options_file_text`. Root attributes add `reference_mean_gap`, "
        "`reference_natural_residual`, `reference_tolerance`, `reference_iterations`.",
        COMPARE,
    )
    _table(
        lines,
        "experiment",
        "Attributes: `block_modulus`, `thickness`, `table`, `formula`.",
        EXPERIMENT,
    )
    _table(
        lines,
        "theory",
        "Persson's theory from a map's spectrum. Attributes: the run record (as above) and `u0`, "
        "`beta` (p = beta E* exp(-u_bar/u0)), `hurst_fit`, `fit_range`, `crossover_pressure` "
        "(paper Eq. 13 as printed), `crossover_pressure_paper` (the recipe of the paper's quoted "
        "values), `crossover_pressure_appendix` (deprecated reading, half of "
        "`crossover_pressure_paper`), `spectrum_rms_slope` (the h'_rms `area_fraction` takes).",
        THEORY,
    )


def _names(keys: tuple[str, ...]) -> str:
    return ", ".join(f"`{k}`" for k in keys)


def _frames(lines: list[str]) -> None:
    """The page's section on the tables ``read_frame`` gives (:data:`FRAMES`)."""
    lines.extend(
        [
            "## tables",
            "",
            "`read_frame(path)` (`petsc_contact.read_frame`) reads any of these files, finished "
            "or `.partial`, as a pandas `DataFrame`. Its kind is its root attribute `geometry` "
            "(a run's, `periodic ensemble`, `theory`), or `compare` for a file with the root "
            "attribute `solvers`. The columns are those below that the file holds, in this "
            "order (a run's: its per-step scalars, without the histograms and maps; for those, "
            '`xarray.open_dataset(path, engine="h5netcdf")`, with `group=SOLVER` for a '
            "comparison's).",
            "",
            "| kind | rows | index | columns |",
            "| --- | --- | --- | --- |",
        ]
    )
    for kind, frame in FRAMES.items():
        lines.append(
            f"| `{kind}` | {frame.rows} | {_names(frame.index)} | {_names(frame.columns)} |"
        )
    lines.append("")


FILE_RECORD = (
    "rms_slope_inside",
    "filled_fraction",
    "heights_reader",
    "heights_channel",
    "heights_channel_index",
    "file_lengths",
    "file_unit",
    "metadata_overridden",
)
"""What a run records of its measured map, beside its path and digest (of a face cut from a
larger surface, ``rms_slope_inside``)."""

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
    "parent_rms_height",  # a punch face cut from a larger surface (--cut-from): the parent's
    "parent_rms_slope",
    "fft_backend",
    "device",  # cpu, gpu or cpu-array (--device); a GPU's model and memory in bytes:
    "device_name",
    "device_memory",
    "seed",
    "hurst",
    "rolloff_ratio",
    "cutoff_ratio",
    "grid",
    "heights_file",
    "heights_sha256",
    *FILE_RECORD,
    "warnings",  # the package's warnings of the run, a JSON list (conventions.warnings)
    "created",
    "complete",
)
