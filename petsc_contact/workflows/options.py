"""The options of the commands that describe a run and its scene, each described once.

:data:`OPTIONS` is the one description of every option of ``periodic``, ``punch``,
``ensemble``, ``demo``, ``compare`` and ``theory`` (and ``experiment``'s ``--quiet``): its
flags, help, unit, default, commands and the parser of its text.  The command line's parser
(:func:`~petsc_contact.cli.arguments.build_parser`) is made from it, the option tables of
docs/cli.md are rendered from it (:func:`with_tables`; ``python -m
petsc_contact.workflows.options docs/cli.md`` writes them), and the options that are
:class:`~petsc_contact.workflows.description.Run`'s fields (``field``) give Run its
defaults (:func:`run_default`).  An option whose help differs between commands (``--sweep``
of pressures or of approaches) has one description per meaning, under the same name.

The parsers turn an option's text into its value and raise
:class:`argparse.ArgumentTypeError` naming what is wrong.  Those of :data:`RULED` read
``Run``'s values too (:func:`check_rules`): their rule is written once, for both doors.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from ..conventions.validation import log_range
from ..devices.device import DEVICES
from ..physics.greens import BASES
from ..substrates.layer import DEFAULT_POISSON

SEED_LIMIT = 2**63  # seeds are stored as 64-bit integers


DEFAULT_DATA = os.path.join("data", "paper")  # study --data: the repository's, from its root


def quantity(text: str) -> float | str:
    """A number (returned as a float), or a number with a unit (kept as text, converted when
    the run's units are known: ``2MPa``, ``1mN``, ``10nm``)."""
    try:
        return float(text)
    except ValueError:
        pass
    if not text.strip() or not (text.strip()[0].isdigit() or text.strip()[0] in "+-."):
        raise argparse.ArgumentTypeError(f"expected a number with an optional unit, got '{text}'")
    return text.strip()


def one_quantity(text: str) -> float | str:
    """:func:`quantity`, refusing a list in words (``compare`` solves one load)."""
    if "," in text:
        raise argparse.ArgumentTypeError(
            f"one pressure only (compare solves one load), got '{text}'"
        )
    return quantity(text)


def _items(text: str, separator: str = ",") -> list[str]:
    """The items of a list (``1e-3,2e-3``); an empty one (``1e-3,,2e-3``, a trailing comma)
    is an error, not a load or a name fewer."""
    items = [v.strip() for v in re.split(separator, text)]
    if "" in items:
        raise argparse.ArgumentTypeError(f"an empty item in '{text}'")
    return items


def quantity_list(text: str) -> list[float | str]:
    """Comma-separated numbers, each with an optional unit (``1e5,2MPa``)."""
    return [quantity(v) for v in _items(text)]


def _float_list(text: str) -> list[float]:
    try:
        return [float(v) for v in _items(text)]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated numbers, got '{text}'"
        ) from None


def whole(text: str | float) -> int:
    """A whole number, from text or a number (``ArgumentTypeError`` naming ``text``
    otherwise: ``2.5`` and ``"2.5"`` alike)."""
    try:
        value = int(text)
    except (TypeError, ValueError):
        value = None
    if value is None or (not isinstance(text, str) and value != text):
        raise argparse.ArgumentTypeError(f"expected a whole number, got '{text}'")
    return value


def seed(text: str) -> int:
    """A seed: a whole number from 0 to 2^63 - 1."""
    value = whole(text)
    if not 0 <= value < SEED_LIMIT:
        raise argparse.ArgumentTypeError(f"a seed is from 0 to 2^63 - 1, got {text}")
    return value


def cut_from(text: str | float) -> int:
    """``--cut-from M``: a whole number, 1 or more (text, or ``Run``'s value)."""
    value = whole(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"M is 1 or more, got {text}")
    return value


def minutes(text: str | float) -> float:
    """A time budget: minutes, zero or more and finite (text, or ``Run``'s value)."""
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise argparse.ArgumentTypeError(f"expected minutes, got '{text}'") from None
    if not (np.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"minutes must be zero or more and finite, got {text}")
    return value


def grid_size(value: Any) -> int | tuple[int, int]:
    """``--grid`` as ``N`` or ``(NX, NY)``, from a number, a pair, or text (``"128"``,
    ``"128,64"``, ``"128x64"``); ``ValueError`` for anything else."""
    items = re.split(r"[,x]", value) if isinstance(value, str) else np.ravel(value).tolist()
    try:
        sizes = [int(v) for v in items]
        whole = all(float(v) == n for v, n in zip(items, sizes, strict=True))
    except (TypeError, ValueError):
        whole = False
    if not whole or len(sizes) not in (1, 2) or min(sizes) < 2:
        raise ValueError(f"--grid takes N or (NX, NY), whole numbers of 2 or more: got {value!r}")
    return sizes[0] if len(sizes) == 1 else (sizes[0], sizes[1])


def grid_shape(text: str) -> int | tuple[int, int]:
    """``N`` (square) or ``NX,NY`` / ``NXxNY`` (rectangle): :func:`grid_size` of the text."""
    _items(text, "[,x]")  # an empty item is said to be one
    try:
        return grid_size(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected N or NX,NY with at least 2, got '{text}'"
        ) from None


def sweep_spec(text: str | Sequence[float | str]) -> list[float | str]:
    """``N`` or ``N,MIN,MAX`` (text, or ``Run``'s sequence), the bounds with an optional unit
    (``12,1kPa,10MPa``: checked once the run's units are known,
    :func:`~petsc_contact.workflows.description.swept`)."""
    parts = _items(text) if isinstance(text, str) else list(text)
    if len(parts) not in (1, 3):
        written = ",".join(str(v) for v in parts)
        raise argparse.ArgumentTypeError(f"expected N or N,PMIN,PMAX, got '{written}'")
    count = _float_list(str(parts[0]))[0]
    bounds = [quantity(v) if isinstance(v, str) else float(v) for v in parts[1:]]
    numbers = [b for b in bounds if isinstance(b, float)]
    try:
        log_range("the sweep", count, (numbers[0], numbers[1]) if len(numbers) == 2 else None)
    except ValueError as bad:
        raise argparse.ArgumentTypeError(str(bad)) from None
    return [count, *bounds]


def cycle_spec(text: str | Sequence[float | str]) -> list[float | str]:
    """A periodic ``--sweep``: :func:`sweep_spec`'s ``N[,PMIN,PMAX]``, or ``N,PMIN,PMAX`` with
    ``PMIN < 0 < PMAX`` (numbers; a tensile end is an adhesive load cycle's:
    :func:`~petsc_contact.workflows.description.cycled`, ``--adhesion`` checked by ``Run``)."""
    parts = _items(text) if isinstance(text, str) else list(text)
    if len(parts) == 3 and all(isinstance(quantity(str(v)), float) for v in parts):
        count, low, high = (float(v) for v in parts)
        if low < 0 < high < np.inf:
            sweep_spec(parts[:1])  # the count's rule
            return [count, low, high]
    return sweep_spec(text)


def solver_list(text: str) -> list[str]:
    """``compare --solvers``: distinct names (or options files)."""
    if not text.replace(",", "").strip():
        raise argparse.ArgumentTypeError("names no solver: give cg,tron,... or leave it out")
    names = _items(text)
    twice = sorted({v for v in names if names.count(v) > 1})
    if twice:
        raise argparse.ArgumentTypeError(f"a solver named twice: {', '.join(twice)}")
    return names


def seed_list(text: str) -> list[int]:
    """``ensemble --seeds``: ``K1,K2,...`` or ``A-B`` (inclusive), distinct seeds."""
    try:
        if "-" in text.strip("-") and "," not in text:
            a, b = (int(v) for v in text.split("-", 1))
            if b < a:
                raise argparse.ArgumentTypeError(f"a range A-B of seeds with B >= A, got '{text}'")
            seeds = list(range(a, b + 1))
        else:
            seeds = [int(v) for v in _items(text)]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected K1,K2,... or A-B, got '{text}'") from None
    if not seeds or len(set(seeds)) != len(seeds):
        raise argparse.ArgumentTypeError(f"need distinct seeds, got '{text}'")
    if not all(0 <= k < SEED_LIMIT for k in seeds):
        raise argparse.ArgumentTypeError(f"a seed is from 0 to 2^63 - 1, got '{text}'")
    if len(seeds) > 100_000:
        raise argparse.ArgumentTypeError(f"{len(seeds)} seeds are too many for one ensemble")
    return seeds


Unit = Literal["", "length", "pressure", "force", "minutes", "seconds"]
"""What an option's value measures: a length (the unit of ``--length``), a pressure (the
unit of ``--modulus``), a force (``E* x length^2``), a time, or nothing."""

Section = Literal["surface", "run", "compare", "theory"]

SCENE = ("periodic", "punch", "ensemble", "demo", "compare", "theory")  # a surface and a cell
RUNS = ("periodic", "punch", "ensemble", "demo")  # load sweeps
PERIODIC = ("periodic", "ensemble", "demo")
PUNCH = ("punch",)

SECTIONS: dict[str, tuple[str, ...]] = {
    "surface": SCENE,
    "run": RUNS,
    "compare": ("compare",),
    "theory": ("theory",),
}
"""Each section's commands (a table of docs/cli.md; ``surface`` is also a group of the
commands' ``--help``)."""


@dataclass(frozen=True)
class Option:
    """One option of the command line, as every command that has it reads it.

    Attributes
    ----------
    name
        Where its value goes: the attribute of the parsed arguments and, when ``field``,
        :class:`~petsc_contact.workflows.description.Run`'s field.
    flags
        Its spellings, the first the one to use (``--rms-slope``); the others are in
        ``deprecated``.
    help
        What it means, in one sentence for ``--help`` (no default: that is added).
    commands
        The commands that have it.
    default
        Its value when not given (``False``: a switch, given or not).
    unit
        What its value measures (:data:`Unit`).
    metavar, parse, choices, nargs
        How its value is written and read (``parse``: text to value, one of this module's
        parsers or a type).
    required
        Whether it must be given; in an ``exclusive`` group, whether one of the group must.
    exclusive
        The mutually exclusive group it belongs to (``loads``).
    section
        Its table of docs/cli.md (:data:`SECTIONS`).
    field
        Whether ``name`` is a field of ``Run``.
    shown_default
        How the default reads where it is not a value (``the file's size, else 1``).
    more
        What docs/cli.md says beyond ``help`` (Markdown).
    deprecated
        Spellings still read, with a warning.
    ignored_by
        Commands that no longer have the option but still read its default value (an old
        script's ``periodic --cut-from 1``), saying in a warning that it is ignored; another
        value is refused as an unknown argument.
    """

    name: str
    flags: tuple[str, ...]
    help: str
    commands: tuple[str, ...]
    default: Any = None
    unit: Unit = ""
    metavar: str | None = None
    parse: Callable[[str], Any] | None = None
    choices: tuple[str, ...] | None = None
    nargs: str | None = None
    required: bool = False
    exclusive: str | None = None
    section: Section = "run"
    field: bool = True
    shown_default: str | None = None
    more: str = ""
    deprecated: tuple[str, ...] = ()
    ignored_by: tuple[str, ...] = ()

    @property
    def switch(self) -> bool:
        """Whether the option is a switch (given or not: no value)."""
        return self.default is False


def _surface(name: str, help: str, **kw: Any) -> Option:
    """An option of the surface, shared by every command with a scene."""
    flag = "--" + name.replace("_", "-")
    return Option(name, (flag,), help, kw.pop("commands", SCENE), section="surface", **kw)


def _option(name: str, help: str, commands: tuple[str, ...], **kw: Any) -> Option:
    """An option spelt as its name (``stop_after``: ``--stop-after``)."""
    return Option(name, ("--" + name.replace("_", "-"),), help, commands, **kw)


_SURFACE = (
    _surface(
        "heights",
        "height map: .npy, .npz, text/.csv, .h5/.nc, or an instrument file (.di, .opd, .sur, "
        ".x3p, .plu, .nid, .ibw, .gwy, .datx, ...; docs/measured.md); nx x ny",
        metavar="FILE",
        more="Peaks point toward the elastic body; a `.npy` is memory-mapped, an instrument "
        "file is read by SurfaceTopography",
    ),
    _surface(
        "channel",
        "which map of a FILE with several (an instrument channel, an HDF5 dataset, an .npz "
        "array), by name or index; the run records which",
        metavar="NAME|INDEX",
        shown_default="the file's default channel",
        more="It is printed, and recorded as `heights_channel` and `heights_channel_index`",
    ),
    _surface(
        "height_unit",
        "unit of the heights in FILE when it has none (m, mm, um, nm, A, pm); they are "
        "converted to the unit of --length",
        metavar="UNIT",
    ),
    _surface(
        "override_metadata",
        "let --length and --height-unit replace the sides and unit FILE states (else a "
        "difference is an error); the run records both and what was overridden",
        default=False,
        more="The file records what FILE said (`file_lengths`, `file_unit`) and what was "
        "replaced (`metadata_overridden`)",
    ),
    _surface(
        "detrend",
        "remove the map's mean, plane or quadratic before contact",
        default="none",
        choices=("none", "height", "slope", "curvature"),
    ),
    _surface(
        "fill_undefined",
        "what to do with undefined (NaN) heights",
        default="error",
        choices=("error", "mean", "harmonic"),
    ),
    _surface(
        "grid",
        "generate an N x N (or NX x NY) self-affine surface (paper Eq. 5)",
        metavar="N|NX,NY",
        parse=grid_shape,
        more="`C0` is chosen so that the *expected* rms value of the discrete spectrum "
        "equals the target (`--rms-slope` or `--rms-height`); the realised values are "
        "reported",
    ),
    _surface("hurst", "Hurst exponent (0..1)", metavar="H", parse=float),
    _surface("rms_slope", "target rms slope h'_rms", metavar="S", parse=float),
    _surface("rms_height", "target rms height h_rms", metavar="R", parse=float, unit="length"),
    _surface(
        "rolloff_ratio",
        "system size over roll-off wavelength",
        default=1.0,
        metavar="L/lambda_r",
        parse=float,
    ),
    _surface(
        "cutoff_ratio",
        "system size over short-wavelength cut-off (on a rectangle L is the longer side)",
        metavar="L/lambda_1",
        parse=float,
        shown_default="the Nyquist limit, N/2",
    ),
    _surface("seed", "random seed (0 to 2^63 - 1)", default=0, metavar="K", parse=seed),
    _surface("exact_rms", "rescale the realisation to hit the rms target exactly", default=False),
    _surface(
        "cut_from",
        "cut the face from the periodic surface of M times the sides (same pixel size and "
        "spectrum), its central patch, with the tilt and edges of the longer wavelengths "
        "(1: the face is a periodic surface)",
        commands=PUNCH,
        default=1,
        metavar="M",
        parse=cut_from,
        more="The parent's `L/lambda_r` and `L/lambda_1` are `M` times the run's. The file "
        "records `cut_from` and the parent's realised `parent_rms_height`, "
        "`parent_rms_slope` (the face's own spectral `rms_slope` includes the jump at its "
        "edges). `periodic --cut-from 1` is still read, with a warning, and ignored",
        ignored_by=("periodic",),
    ),
    _surface(
        "skip_memory_check",
        "run even when the grid needs more memory than the machine has available "
        "(estimated from the measured bytes per point; refused otherwise)",
        default=False,
        more="The estimate is made before anything is allocated",
    ),
)

_SCENE = (
    _option(
        "length",
        "sides of the periodic cell, the punch footprint or the map, with an optional unit "
        "(100um, 2mm,1mm); one value: square pixels",
        SCENE,
        metavar="L|LX,LY",
        unit="length",
        shown_default="the file's size, else 1",
    ),
    _option(
        "modulus",
        "contact modulus E*, with an optional unit (1GPa: pressures then in GPa)",
        SCENE,
        default=1.0,
        metavar="ESTAR",
        parse=quantity,
        unit="pressure",
    ),
)

_LOADS: dict[str, Any] = {"exclusive": "loads", "required": True, "parse": quantity_list}
_SWEEP: dict[str, Any] = {"exclusive": "loads", "required": True, "parse": sweep_spec}

_PERIODIC_LOADS = (
    _option(
        "pressures",
        "nominal pressures p0 (units of E*, or with a unit: 2MPa), in order",
        PERIODIC,
        metavar="P1,P2,...",
        unit="pressure",
        more="Each is solved from the previous converged gap; a unit needs one on `--modulus`",
        **_LOADS,
    ),
    _option(
        "sweep",
        "N log-spaced pressures from PMIN to PMAX, with an optional unit (12,1kPa,10MPa; "
        "default: 1e-4 and 0.9 times the full-contact pressure -min(K h); a measured map's: "
        "from its first resolved contact to about half the area, by Persson's area law)",
        PERIODIC,
        metavar="N[,PMIN,PMAX]",
        unit="pressure",
        more="The file records the pressures themselves; an ensemble takes the range of its "
        "first seed's surface, so that every seed gets the same pressures. With `--adhesion` "
        "a sweep is a load cycle and needs its bounds: N equally spaced pressures up to PMAX "
        "(PMAX/N, 2 PMAX/N, ..., PMAX: loading), then N equally spaced down to PMIN "
        "(unloading; PMIN < 0, tension, is taken only there), each step from the last "
        "converged one on its branch",
        **{**_SWEEP, "parse": cycle_spec},
    ),
    _option(
        "mean_gaps",
        "prescribed mean gaps u_bar (length units, or with a unit: 10nm), in order "
        "(displacement control: the nominal pressure p0 is each step's result)",
        ("periodic",),
        metavar="G1,G2,...",
        unit="length",
        more="Safeguarded Newton on ln p0 with the exact derivative -du_bar/d(ln p0) = p0/K "
        "aims at `1e-6` of the smaller of the mean gap and its approach from first touch "
        "(stored: `mean_gap_tolerance`, `mean_gap_mismatch`); within `1e-4` of it a mean gap "
        "is accepted, one further off is flagged not converged. Each must lie between 0 "
        "(full contact) and max(h) - mean(h) (first touch); every step has the exact "
        "`stiffness` (docs/formulation.md)",
        **_LOADS,
    ),
)

_PUNCH_LOADS = (
    _option(
        "approaches",
        "rigid approaches beyond first touch (length units, or with a unit: 10nm), in order",
        PUNCH,
        metavar="D1,D2,...",
        unit="length",
        **_LOADS,
    ),
    _option(
        "forces",
        "total forces (E* x length^2, or with a unit: 1mN), in order (load control)",
        PUNCH,
        metavar="F1,F2,...",
        unit="force",
        more="Safeguarded Newton on the approach with the exact `dF/d delta` aims at `1e-6` "
        "relative and stops earlier where the solve no longer tells the approaches apart; "
        "a force within `1e-4` relative of its target is accepted, one further off is "
        "flagged not converged",
        **_LOADS,
    ),
    _option(
        "pressures",
        "nominal pressures over the punch's face (units of E*, or with a unit: 2MPa), in "
        "order (load control: the force is the pressure times the face's area)",
        PUNCH,
        metavar="P1,P2,...",
        unit="pressure",
        **_LOADS,
    ),
    _option(
        "sweep",
        "N log-spaced approaches from DMIN to DMAX, with an optional unit (6,1nm,50nm; "
        "default: 0.01 and 3 times the rms recess of the punch face)",
        PUNCH,
        metavar="N[,DMIN,DMAX]",
        unit="length",
        **_SWEEP,
    ),
    _option(
        "footprint",
        "punch outline: the whole square, or the inscribed disk (pressure held at zero outside)",
        PUNCH,
        default="square",
        choices=("square", "disk"),
    ),
    _option(
        "flat_stiffness",
        "flat-punch stiffness in Eq. 2: computed on the same grid, or beta x 2 E* "
        "sqrt(A/pi) with the exact beta = 1.0212 (square, from the unit square's capacitance "
        "0.3667874) or 1 (disk), or King's estimate beta = 1.012 (square only, 0.9% low)",
        PUNCH,
        default="grid",
        choices=("grid", "analytic", "king"),
        more=(
            "On the same grid the discretisation errors cancel; the square's grid value "
            "approaches the exact one as 1/n (0.27% below it at 128 pixels a side, 0.017% at "
            "2048). Each step records `flat_punch_stiffness` and its `flat_punch_beta`"
        ),
    ),
    _option(
        "hardness",
        "cap the pressure at the hardness H (units of E*, or with a unit: 5GPa): Kato's "
        "perfectly plastic surface layer",
        ("periodic", "punch", "compare"),
        metavar="H",
        parse=quantity,
        unit="pressure",
        shown_default="none: the hard wall",
        more="A pixel at the cap carries `H` and the punch sinks into it by the plastic "
        "displacement (`--fields`: `plastic_displacement`); each step records "
        "`plastic_area_fraction`, and its stiffness holds the plastic pixels at the cap "
        "([formulation.md](formulation.md)). A periodic run takes `--pressures` or a "
        "`--sweep`: each load is solved on the hard wall first, and posed in the pressure "
        "only where that reaches the cap (`cap_reached`; `compare` poses it so); a nominal "
        "pressure (the punch's: over its face) not below `H` is refused",
    ),
)

LAYERED = ("periodic", "ensemble")  # the periodic runs that pose their own substrate

_LAYER = (
    _option(
        "thickness",
        "press an elastic layer of thickness T on a rigid base instead of the half-space, "
        "with an optional unit (10um)",
        LAYERED,
        metavar="T",
        parse=quantity,
        unit="length",
        shown_default="none: the half-space",
        more='Its stiffness is `E* q/2 f(qT, nu)` ([formulation.md](formulation.md), "A layer '
        'on a rigid base"); the file records `thickness`, `poisson` and `base`',
    ),
    _option(
        "poisson",
        "the layer's Poisson ratio nu (0 to 0.5); its contact modulus E/(1 - nu^2) is --modulus",
        LAYERED,
        default=DEFAULT_POISSON,
        metavar="NU",
        parse=float,
        more="Only a bonded layer depends on it (the frictionless base's stiffness in units of "
        "`E*` does not); the default is that of most metals, glasses and ceramics (0.2 to "
        "0.35), the coatings a layer usually is: give 0.5 for rubber",
    ),
    _option(
        "base",
        "how the layer rests on its rigid base: bonded (no displacement there) or "
        "frictionless (no normal displacement, no shear)",
        LAYERED,
        default="bonded",
        choices=BASES,
    ),
)

_ADHESION = (
    _option(
        "adhesion",
        "an adhesive law beside the hard wall: exponential (the interaction energy per area "
        "-w exp(-g/rho)) or maugis (Maugis-Dugdale: the attraction w/rho below g = rho)",
        ("periodic", "punch", "compare"),
        choices=("exponential", "maugis"),
        shown_default="none: the hard wall",
        more="Posed in the gap with the interaction energy added (not convex; "
        '[formulation.md](formulation.md), "Adhesion"): solved by TAO\'s bound solvers '
        "(`-tao_type blmvm` or `bncg`; the package's CG, a QP solver, is refused), each "
        "nominal pressure (tension too) or mean gap (held by a stiff loading machine to "
        "1e-6) from the last converged step. Each step records `adhesive_pressure`, "
        "`interaction_energy`, `pressure_scale`, `pull_off_pressure` and `branch_jump`; a "
        "step under tension whose surfaces came apart is not converged (`pulled off`); a "
        "`--mean-gaps` cycle back to its first mean gap records `hysteresis_energy`, the "
        "energy per area it lost. Takes `--pressures`, a `--sweep` (a load cycle) or "
        "`--mean-gaps` on the periodic half-space; the punch (posed in the "
        "displacement of its zero-padded cell) takes `--approaches` (any sign: negative "
        "pulls back beyond first touch), `--forces` or `--pressures` (tension too). `compare` "
        "solves its scene with the law (the reference: `blmvm` at 1e-12; `cg` and `pk` "
        "refused)",
    ),
    _option(
        "work_of_adhesion",
        "the work of adhesion w of --adhesion: an energy per area (units of E* times the "
        "length unit)",
        ("periodic", "punch", "compare"),
        metavar="W",
        parse=float,
    ),
    _option(
        "interaction_range",
        "the range rho of --adhesion, with an optional unit (5nm)",
        ("periodic", "punch", "compare"),
        metavar="RHO",
        parse=quantity,
        unit="length",
    ),
)

_UNCONVERGED_STIFFNESS = (
    "A solve that stops short of its tolerance (`-stiffness_ksp_max_it`, "
    "`-stiffness_ksp_rtol`) leaves that stiffness NaN, with a one-line warning"
)

_RUN = (
    _option(
        "stiffness",
        "add the exact incremental stiffness per area -dp0/du_bar (contact set held fixed, "
        "one CG solve) as the dataset 'stiffness'",
        PERIODIC,
        default=False,
        more=_UNCONVERGED_STIFFNESS,
    ),
    _option(
        "stiffness",
        "add the interfacial stiffness per area of Eq. 2 (from the exact total stiffness "
        "dF/d delta, contact set held fixed, and the flat punch's) as the dataset "
        "'stiffness'",
        PUNCH,
        default=False,
        more=_UNCONVERGED_STIFFNESS,
    ),
    _option(
        "device",
        "where the solves run: cpu (PETSc/TAO), gpu (the package's CG on CuPy) or cpu-array "
        "(the GPU's code on NumPy)",
        (*RUNS, "study"),
        default="cpu",
        choices=DEVICES,
        more="`gpu` and `cpu-array` run periodic sweeps and the punch (`--stiffness`, "
        "`--fields`, `--resume`, ensembles, the study's pieces) without petsc4py, reading the "
        "PETSc options they understand; `cpu-array` on any number of MPI ranks, `gpu` on one. "
        "The file "
        "records `device` (a GPU's `device_name` and `device_memory`) and each step's "
        "`solve_time`. No CuPy or no GPU: exit status 69 ([gpu.md](gpu.md))",
    ),
    _option(
        "output",
        "HDF5 results (written atomically)",
        RUNS,
        metavar="OUT.h5",
        required=True,
        more="Every finished step is committed to `OUT.h5.partial` (fields and heights to "
        "`OUT.h5.parts/`), and `OUT.h5` is assembled when the run ends "
        "([reliability.md](reliability.md)); a second run on an output in use is refused",
    ),
    _option(
        "fields",
        "store the gap, pressure and contact fields of every step (compressed)",
        RUNS,
        default=False,
        more="The pressure is exactly zero off contact, the gap exactly zero in it",
    ),
    _option(
        "plot",
        "write a PNG of the results against load",
        RUNS,
        metavar="PNG",
        field=False,
        more="A periodic run: area, mean gap and (with `--stiffness`) `K` against pressure; a "
        "punch: force and interfacial stiffness; an ensemble: the mean area fraction and "
        "stiffness with their standard errors. Each axis is in the run's units with the prefix "
        "that suits its values (MPa, nm, µN; `K` in MPa/µm, a pressure per "
        "micrometre), and dimensionless (`p0/E*`, `u_bar/h_rms`, `K h_rms/E*`, a punch's "
        "`delta/h_rms`) only where the run has no unit: both geometries alike. A unit-free "
        "ensemble scales each seed's `K` by its own `h_rms`",
    ),
    _option(
        "quiet",
        "no table on standard output",
        (*RUNS, "compare", "theory", "experiment"),
        default=False,
        field=False,
    ),
    _option(
        "resume",
        "continue an interrupted run from OUT.h5.partial (same options): finished steps are "
        "kept, not recomputed",
        RUNS,
        default=False,
        more="The next step starts from the last state and what the sweep held, kept beside "
        "it in `OUT.h5.state.npz` until the run ends, and equals the uninterrupted run's "
        "(missing or damaged: from first touch, with a warning). On a complete `OUT.h5` of "
        "the same run nothing is computed or written (its steps are the result); one of "
        "other parameters is refused (`--overwrite`). `ensemble --resume` keeps "
        "the seeds finished with this ensemble's parameters and continues an interrupted "
        "one; a seed file of other parameters is refused (`--overwrite`)",
    ),
    _option(
        "overwrite",
        "start afresh even where OUT.h5.partial holds finished steps of an interrupted run "
        "(they are deleted)",
        RUNS,
        default=False,
        more="Without it (or `--resume`) such an output is refused. An existing `OUT.h5` is "
        "replaced when the run ends; without `--overwrite` a warning says so (deprecated: "
        "refused from 0.3.0), except `demo`'s own `demo.h5`. `ensemble --overwrite` "
        "first deletes the summary and every `OUT_seedK` file; an ensemble whose output or "
        "seed files exist needs `--resume` or `--overwrite`",
    ),
    _option(
        "stop_after",
        "after the step that ends past MINUTES of wall time, stop; --resume continues (exit "
        "status 75)",
        RUNS,
        metavar="MINUTES",
        parse=minutes,
        unit="minutes",
    ),
    _option(
        "options_prefix",
        "read the run's PETSc options with this prefix (a_: -a_tao_type bncg, "
        "-a_petsc_contact_two_level 0, -a_stiffness_ksp_rtol 1e-8)",
        RUNS,
        default="",
        metavar="PREFIX",
        more="Unprefixed options are then not the run's (said to be never used), on the "
        "command line as from Python (`Run(options_prefix=...)`)",
    ),
    _option(
        "scalars_only",
        "do not store the height map (for compact result files of large grids)",
        RUNS,
        default=False,
    ),
    _option(
        "seeds",
        "the seeds (a list, or a range A-B inclusive)",
        ("ensemble",),
        metavar="K1,K2,...|A-B",
        parse=seed_list,
        required=True,
        field=False,
    ),
)

_COMPARE = (
    Option(
        "pressure",
        ("--pressures", "--pressure"),
        "nominal pressure p0 of the scene (units of E*, or with a unit: 2MPa; one value)",
        ("compare",),
        metavar="P",
        parse=one_quantity,
        unit="pressure",
        required=True,
        section="compare",
        field=False,
        more="`--pressure P`, its former spelling, is read with a warning",
        deprecated=("--pressure",),
    ),
    _option(
        "solvers",
        "TAO types, 'cg' (default solver), 'pk' (Polonsky-Keer) or options files",
        ("compare",),
        metavar="S1,S2,...",
        parse=solver_list,
        section="compare",
        field=False,
        shown_default="cg,pk,tron,bnls,bntr,bqnls,blmvm,bncg,gpcg, each with its "
        "options/NAME.opts, which the command line's PETSc options override",
        more="The files are shipped with the package, as are `bqpip.opts` and `tight.opts`, "
        "which `bqpip` and `tight` run with; a path runs that file instead, another "
        "TAO type PETSc's defaults; `-tao_type` is refused ([solvers.md](solvers.md)). Each "
        "solver's options prefix is its name: `-bncg_tao_max_it 50` reaches `bncg` alone, "
        "an unprefixed option every solver; each solver's group records the options it ran "
        "with (`petsc_options`), and `--resume` solves again a solver whose options changed",
    ),
    _option(
        "time_limit",
        "stop a solver after S seconds of wall time",
        ("compare",),
        default=120.0,
        metavar="S",
        parse=float,
        unit="seconds",
        section="compare",
        field=False,
    ),
    _option(
        "stall_iterations",
        "stop a solver whose natural residual has not fallen 10% below its best for N "
        "iterations (0: never)",
        ("compare",),
        default=1000,
        metavar="N",
        parse=int,
        section="compare",
        field=False,
    ),
    _option(
        "output",
        "results; each finished solver is committed to OUT.h5.partial",
        ("compare",),
        metavar="OUT.h5",
        required=True,
        section="compare",
        more="Also `OUT.csv` (the table) and `OUT.png` (the plot)",
    ),
    _option(
        "resume",
        "go on from OUT.h5.partial (same options): finished solvers are kept",
        ("compare",),
        default=False,
        section="compare",
        more="The rest are run, the reference solved again (same scene, `--pressures`, "
        "`--solvers`, `--time-limit`, `--stall-iterations`; otherwise refused). On a "
        "complete `OUT.h5` every solver is kept and only the reference solved again",
    ),
    _option(
        "overwrite",
        "start afresh even where OUT.h5.partial holds finished solvers (they are deleted)",
        ("compare",),
        default=False,
        section="compare",
        more="Without it (or `--resume`) such an output is refused. An existing `OUT.h5` is "
        "replaced when the comparison ends; without `--overwrite` a warning says so "
        "(deprecated: refused from 0.3.0)",
    ),
)

_THEORY = (
    _option(
        "sweep",
        "N log-spaced pressures of the predictions, the bounds with an optional unit (from "
        "1e-7 E* to 0.1 E* unless given)",
        ("theory",),
        default=(40,),
        metavar="N[,PMIN,PMAX]",
        parse=sweep_spec,
        unit="pressure",
        section="theory",
    ),
    _option(
        "output", "HDF5 results", ("theory",), metavar="OUT.h5", required=True, section="theory"
    ),
    _option(
        "plot",
        "spectrum, u(p) and K(p) with p_c marked",
        ("theory",),
        metavar="PNG",
        section="theory",
        field=False,
    ),
    _option(
        "compare",
        "with --plot: draw these periodic runs' mean gap, stiffness and contact area beside "
        "the theory's, in its units",
        ("theory",),
        metavar="RUN.h5",
        nargs="+",
        section="theory",
        field=False,
        more="Without `--plot`, given another geometry's file, a run on a layer "
        "(`--thickness`: the theory is the half-space's), or a run with a unit (lengths, "
        "pressures) where the theory has none or the other way round, it is refused (exit 2, "
        "before the theory is computed)",
    ),
)

OPTIONS: tuple[Option, ...] = (
    *_SURFACE,
    *_SCENE,
    *_PERIODIC_LOADS,
    *_PUNCH_LOADS,
    *_COMPARE,
    *_LAYER,
    *_ADHESION,
    *_RUN,
    *_THEORY,
)
"""Every option of the commands with a scene, in the order of their ``--help``."""


def options_of(command: str) -> list[Option]:
    """The options of ``command``, in the order of its ``--help``."""
    return [o for o in OPTIONS if command in o.commands]


def check_choices(values: Callable[[str], Any]) -> None:
    """``ValueError`` naming the option, as the command line does, for a field of ``Run``
    (``values(name)``) that is not one of its option's choices (``None``: not given)."""
    for option in OPTIONS:
        if option.field and option.choices is not None:
            value = values(option.name)
            if value is not None and value not in option.choices:
                raise ValueError(
                    f"{option.flags[0]} must be one of {', '.join(option.choices)}, not '{value}'"
                )


RULED = ("sweep", "cut_from", "stop_after")
"""``Run``'s fields whose option's parser is their rule (:func:`check_rules`)."""


def check_rules(values: Callable[[str], Any]) -> None:
    """``ValueError`` naming the option (``--cut-from: M is 1 or more, got 0``) for a field of
    ``Run`` among :data:`RULED` (``values(name)``; ``None``: not given) that its option's
    parser refuses: the rule the command line applies to the option's text."""
    for name in RULED:
        value = values(name)
        option = next(o for o in OPTIONS if o.name == name and o.parse is not None)
        if value is None or option.parse is None:
            continue
        try:
            option.parse(value)
        except argparse.ArgumentTypeError as bad:
            raise ValueError(f"{option.flags[0]}: {bad}") from None


def run_default(name: str) -> Any:
    """The default of ``Run``'s field ``name``: its option's, the same for every command that
    runs (``ValueError`` for a field with no such option, or with two defaults)."""
    runs = set(RUNS)
    defaults = [o.default for o in OPTIONS if o.field and o.name == name and runs & {*o.commands}]
    if not defaults or any(d != defaults[0] for d in defaults):
        raise ValueError(f"Run's field {name} needs one default among OPTIONS: {defaults}")
    return defaults[0]


def run_fields(command: str) -> list[str]:
    """The options of ``command`` that are fields of ``Run``."""
    return [o.name for o in options_of(command) if o.field]


def shown(value: Any) -> str:
    """A default as the command line writes it (``1``, ``0.1``, ``3e-05,0.0001``)."""
    if isinstance(value, (list, tuple)):
        return ",".join(shown(v) for v in value)
    return f"{value:g}" if isinstance(value, float) else str(value)


def default_text(option: Option, default: Any) -> str | None:
    """How the help and the docs name an option's default (``None``: none to name)."""
    if option.shown_default is not None:
        return option.shown_default
    if option.switch or default is None or default == "":
        return None
    return shown(default)


def _spelling(option: Option) -> str:
    """The option's first column in docs/cli.md: each spelling with its value."""
    value = "|".join(option.choices) if option.choices else option.metavar
    suffix = "" if value is None else " " + value + (" ..." if option.nargs == "+" else "")
    cells = [f"`{flag}{suffix}`" for flag in option.flags if flag not in option.deprecated]
    cells += [f"`{flag}{suffix}` (deprecated)" for flag in option.deprecated]
    return ", ".join(cells).replace("|", "\\|")


def _cell(text: str) -> str:
    """Plain help text as a Markdown table cell (``E*`` is no emphasis, ``|`` no column)."""
    return text.replace("*", "\\*").replace("|", "\\|")


def markdown(section: str) -> str:
    """The Markdown table of a section's options (docs/cli.md): option, meaning (prefixed
    by its commands where not every command of the section has it), unit and default."""
    rows = ["| option | meaning | unit | default |", "| --- | --- | --- | --- |"]
    for o in OPTIONS:
        if o.section != section:
            continue
        inside = [c for c in SECTIONS[section] if c in o.commands]
        where = "" if len(inside) == len(SECTIONS[section]) else f"({', '.join(inside)}) "
        meaning = where + _cell(o.help) + (f". {o.more}" if o.more else "")
        default = "required" if o.required and not o.exclusive else default_text(o, o.default)
        rows.append(f"| {_spelling(o)} | {meaning} | {o.unit} | {_cell(default or '')} |")
    return "\n".join(rows)


_TABLE = re.compile(r"(<!-- options: (\w+) -->\n)(?:.*?\n)??(<!-- end of options -->)", re.S)


def with_tables(page: str) -> str:
    """``page`` (docs/cli.md) with each table between ``<!-- options: SECTION -->`` and
    ``<!-- end of options -->`` rendered again from :data:`OPTIONS`."""
    return _TABLE.sub(lambda m: m[1] + markdown(m[2]) + "\n" + m[3], page)


def write_tables(paths: Sequence[str]) -> None:
    """Render the option tables of the pages at ``paths`` again, in place."""
    for path in map(Path, paths):
        path.write_text(with_tables(path.read_text()))


if __name__ == "__main__":  # python -m petsc_contact.workflows.options docs/cli.md
    write_tables(sys.argv[1:])
