"""The command line's arguments: the package's own (two dashes) and PETSc's (one dash)."""

from __future__ import annotations

import argparse
import os
import re
from collections.abc import Sequence
from typing import Any, NoReturn

import numpy as np

from .._version import __version__
from ..conventions.validation import log_range

DEMO = {
    "grid": 512,
    "hurst": 0.7,
    "rms_slope": 0.1,
    "rolloff_ratio": 2.0,
    "cutoff_ratio": 64.0,
    "seed": 1,
    "modulus": 1.0,
    "pressures": "3e-5,1e-4,3e-4,1e-3,3e-3,1e-2,2e-2,3e-2",
}


_PETSC_OPTION = re.compile(r"^-[A-Za-z_]")


_NUMBER = re.compile(r"^-?(\d|\.\d)")


def is_petsc_option(token: str) -> bool:
    """``-tao_type`` is a PETSc option; ``--grid``, ``-h`` and numbers such as ``-1`` are not."""
    return token != "-h" and bool(_PETSC_OPTION.match(token)) and not token.startswith("--")


def options_files(petsc_args: Sequence[str]) -> list[str]:
    """The files named by ``-options_file`` among PETSc's options."""
    return [b for a, b in zip(petsc_args, petsc_args[1:], strict=False) if a == "-options_file"]


def split_arguments(argv: Sequence[str]) -> tuple[list[str], list[str]]:
    """Split a command line into the package's arguments and PETSc's options.

    A token like ``-tao_type`` starts a PETSc option; the token after it is its value unless
    it starts with a dash (numbers such as ``-1`` are values).  ``-h`` is the package's help.
    """
    ours: list[str] = []
    petsc: list[str] = []
    tokens = list(argv)
    i = 0
    while i < len(tokens):
        tok = tokens[i]
        if is_petsc_option(tok):
            petsc.append(tok)
            if i + 1 < len(tokens) and (
                not tokens[i + 1].startswith("-") or _NUMBER.match(tokens[i + 1])
            ):
                petsc.append(tokens[i + 1])
                i += 1
        else:
            ours.append(tok)
            if (
                tok.startswith("--")
                and "=" not in tok
                and i + 1 < len(tokens)
                and _NUMBER.match(tokens[i + 1])
            ):
                ours.append(tokens[i + 1])
                i += 1
        i += 1
    return ours, petsc


def _quantity(text: str) -> float | str:
    """A number (returned as a float), or a number with a unit (kept as text, converted when
    the run's units are known: ``2MPa``, ``1mN``, ``10nm``)."""
    try:
        return float(text)
    except ValueError:
        pass
    if not text.strip() or not (text.strip()[0].isdigit() or text.strip()[0] in "+-."):
        raise argparse.ArgumentTypeError(f"expected a number with an optional unit, got '{text}'")
    return text.strip()


def _items(text: str, separator: str = ",") -> list[str]:
    """The items of a list (``1e-3,2e-3``); an empty one (``1e-3,,2e-3``, a trailing comma)
    is an error, not a load or a name fewer."""
    items = [v.strip() for v in re.split(separator, text)]
    if "" in items:
        raise argparse.ArgumentTypeError(f"an empty item in '{text}'")
    return items


def _quantity_list(text: str) -> list[float | str]:
    """Comma-separated numbers, each with an optional unit (``1e5,2MPa``)."""
    return [_quantity(v) for v in _items(text)]


def _float_list(text: str) -> list[float]:
    try:
        return [float(v) for v in _items(text)]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated numbers, got '{text}'"
        ) from None


SEED_LIMIT = 2**63  # seeds are stored as 64-bit integers


def _seed(text: str) -> int:
    """A seed: a whole number from 0 to 2^63 - 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got '{text}'") from None
    if not 0 <= value < SEED_LIMIT:
        raise argparse.ArgumentTypeError(f"a seed is from 0 to 2^63 - 1, got {text}")
    return value


def _cut_from(text: str) -> int:
    """``--cut-from M``: a whole number, 1 or more."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got '{text}'") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"M is 1 or more, got {text}")
    return value


def _minutes(text: str) -> float:
    """A time budget: minutes, zero or more and finite."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected minutes, got '{text}'") from None
    if not (np.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"minutes must be zero or more and finite, got {text}")
    return value


def _grid_shape(text: str) -> int | tuple[int, int]:
    """``N`` (square) or ``NX,NY`` / ``NXxNY`` (rectangle)."""
    parts = _items(text, "[,x]")
    try:
        sizes = [int(v) for v in parts]
    except ValueError:
        sizes = []
    if len(sizes) not in (1, 2) or min(sizes) < 2:
        raise argparse.ArgumentTypeError(f"expected N or NX,NY with at least 2, got '{text}'")
    return sizes[0] if len(sizes) == 1 else (sizes[0], sizes[1])


def _sweep_spec(text: str) -> list[float | str]:
    """``N`` or ``N,MIN,MAX``, the bounds with an optional unit (``12,1kPa,10MPa``: checked
    once the run's units are known)."""
    parts = _items(text)
    if len(parts) not in (1, 3):
        raise argparse.ArgumentTypeError(f"expected N or N,PMIN,PMAX, got '{text}'")
    count = _float_list(parts[0])[0]
    bounds = [_quantity(v) for v in parts[1:]]
    numbers = [b for b in bounds if isinstance(b, float)]
    try:
        log_range("the sweep", count, (numbers[0], numbers[1]) if len(numbers) == 2 else None)
    except ValueError as bad:
        raise argparse.ArgumentTypeError(str(bad)) from None
    return [count, *bounds]


def _solver_list(text: str) -> list[str]:
    """``compare --solvers``: distinct names (or options files)."""
    if not text.replace(",", "").strip():
        raise argparse.ArgumentTypeError("names no solver: give cg,tron,... or leave it out")
    names = _items(text)
    twice = sorted({v for v in names if names.count(v) > 1})
    if twice:
        raise argparse.ArgumentTypeError(f"a solver named twice: {', '.join(twice)}")
    return names


def _seed_list(text: str) -> list[int]:
    try:
        if "-" in text.strip("-") and "," not in text:
            a, b = (int(v) for v in text.split("-", 1))
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


def _surface_arguments(p: argparse.ArgumentParser) -> None:
    s = p.add_argument_group("surface (a file, or a generated self-affine surface, paper Eq. 5)")
    s.add_argument(
        "--heights",
        metavar="FILE",
        help="height map: .npy, .npz, text/.csv, .h5/.nc, or an instrument file (.di, .opd, "
        ".sur, .x3p, .plu, .nid, .ibw, .gwy, .datx, ...; docs/measured.md); nx x ny",
    )
    s.add_argument(
        "--channel",
        metavar="NAME|INDEX",
        help="which map of a FILE with several (an instrument channel, an HDF5 dataset, an .npz "
        "array), by name or index (default: the file's default channel; the run records it)",
    )
    s.add_argument(
        "--height-unit",
        metavar="UNIT",
        help="unit of the heights in FILE when it has none (m, mm, um, nm, A, pm); they are "
        "converted to the unit of --length",
    )
    s.add_argument(
        "--override-metadata",
        action="store_true",
        help="let --length and --height-unit replace the sides and unit FILE states (else a "
        "difference is an error); the run records both and what was overridden",
    )
    s.add_argument(
        "--detrend",
        choices=("none", "height", "slope", "curvature"),
        default="none",
        help="remove the map's mean, plane or quadratic before contact (default none)",
    )
    s.add_argument(
        "--fill-undefined",
        choices=("error", "mean", "harmonic"),
        default="error",
        help="what to do with undefined (NaN) heights (default error)",
    )
    s.add_argument(
        "--grid", type=_grid_shape, metavar="N|NX,NY", help="generate an N x N (or NX x NY) surface"
    )
    s.add_argument("--hurst", type=float, metavar="H", help="Hurst exponent (0..1)")
    s.add_argument("--rms-slope", type=float, metavar="S", help="target rms slope h'_rms")
    s.add_argument("--rms-height", type=float, metavar="R", help="target rms height h_rms")
    s.add_argument(
        "--rolloff-ratio",
        type=float,
        metavar="L/lambda_r",
        default=1.0,
        help="system size over roll-off wavelength (default 1)",
    )
    s.add_argument(
        "--cutoff-ratio",
        type=float,
        metavar="L/lambda_1",
        help="system size over short-wavelength cut-off (default: the Nyquist limit, N/2; "
        "on a rectangle L is the longer side)",
    )
    s.add_argument("--seed", type=_seed, default=0, metavar="K", help="random seed (default 0)")
    s.add_argument(
        "--exact-rms",
        action="store_true",
        help="rescale the realisation to hit the rms target exactly",
    )
    s.add_argument(
        "--cut-from",
        type=_cut_from,
        default=1,
        metavar="M",
        help="punch: cut the face from the periodic surface of M times the sides (same pixel "
        "size and spectrum), its central patch, with the tilt and edges of the longer "
        "wavelengths (default 1: the face is a periodic surface)",
    )
    s.add_argument(
        "--skip-memory-check",
        action="store_true",
        help="run even when the grid needs more memory than the machine has available "
        "(estimated from the measured bytes per point; refused otherwise)",
    )


def _run_arguments(
    p: argparse.ArgumentParser, defaults: dict[str, Any] | None = None, punch: bool = False
) -> None:
    d = defaults or {}
    p.add_argument(
        "--length",
        default=d.get("length"),
        metavar="L|LX,LY",
        help=("sides of the punch footprint" if punch else "sides of the periodic cell")
        + ", with an optional unit (100um, 2mm,1mm); one value: square pixels "
        "(default: the file's size, else 1)",
    )
    p.add_argument(
        "--modulus",
        type=_quantity,
        default=d.get("modulus", 1.0),
        metavar="ESTAR",
        help="contact modulus E*, with an optional unit (1GPa: pressures then in GPa; "
        "default %(default)s)",
    )
    if punch:
        _punch_loads(p)
    else:
        _periodic_loads(p, d)
    _output_arguments(p, d)


def _punch_loads(p: argparse.ArgumentParser) -> None:
    loads = p.add_mutually_exclusive_group(required=True)
    loads.add_argument(
        "--approaches",
        type=_quantity_list,
        metavar="D1,D2,...",
        help="rigid approaches beyond first touch (length units, or with a unit: 10nm), in order",
    )
    loads.add_argument(
        "--forces",
        type=_quantity_list,
        metavar="F1,F2,...",
        help="total forces (E* x length^2, or with a unit: 1mN), in order (load control)",
    )
    loads.add_argument(
        "--pressures",
        type=_quantity_list,
        metavar="P1,P2,...",
        help="nominal pressures over the punch's face (units of E*, or with a unit: 2MPa), in "
        "order (load control: the force is the pressure times the face's area)",
    )
    loads.add_argument(
        "--sweep",
        type=_sweep_spec,
        metavar="N[,DMIN,DMAX]",
        help="N log-spaced approaches from DMIN to DMAX, with an optional unit (6,1nm,50nm; "
        "default: 0.01 and 3 times the rms recess of the punch face)",
    )
    p.add_argument(
        "--footprint",
        choices=("square", "disk"),
        default="square",
        help="punch outline: the whole square, or the inscribed disk",
    )
    p.add_argument(
        "--flat-stiffness",
        choices=("grid", "analytic"),
        default="grid",
        help="flat-punch stiffness in Eq. 2: computed on the same grid "
        "(default) or beta x 2 E* sqrt(A/pi), beta = 1.012 (square) or 1 "
        "(disk)",
    )


def _periodic_loads(p: argparse.ArgumentParser, d: dict[str, Any]) -> None:
    loads = p.add_mutually_exclusive_group(required="pressures" not in d)
    loads.add_argument(
        "--pressures",
        type=_quantity_list,
        default=_quantity_list(d["pressures"]) if "pressures" in d else None,
        metavar="P1,P2,...",
        help="nominal pressures p0 (units of E*, or with a unit: 2MPa), in order",
    )
    loads.add_argument(
        "--sweep",
        type=_sweep_spec,
        metavar="N[,PMIN,PMAX]",
        help="N log-spaced pressures from PMIN to PMAX, with an optional unit (12,1kPa,10MPa; "
        "default: 1e-4 and 0.9 times the full-contact pressure -min(K h))",
    )


def _output_arguments(p: argparse.ArgumentParser, d: dict[str, Any]) -> None:
    p.add_argument(
        "--stiffness",
        action="store_true",
        help="add the exact incremental stiffness per area (contact set held "
        "fixed) as the dataset 'stiffness'",
    )
    p.add_argument(
        "--output",
        required="output" not in d,
        default=d.get("output"),
        metavar="OUT.h5",
        help="HDF5 results (written atomically)",
    )
    p.add_argument(
        "--fields",
        action="store_true",
        help="store the gap, pressure and contact fields of every step (compressed)",
    )
    p.add_argument(
        "--plot",
        metavar="PNG",
        default=d.get("plot"),
        help="write a PNG of the results against load",
    )
    p.add_argument("--quiet", action="store_true", help="no table on standard output")
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue an interrupted run from OUT.h5.partial (same options): "
        "finished steps are kept, not recomputed",
    )
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="start afresh even where OUT.h5.partial holds finished steps of an "
        "interrupted run (they are deleted)",
    )
    p.add_argument(
        "--stop-after",
        type=_minutes,
        default=None,
        metavar="MINUTES",
        help="after the step that ends past MINUTES of wall time, stop; --resume continues "
        "(exit status 75)",
    )
    p.add_argument(
        "--options-prefix",
        default="",
        metavar="PREFIX",
        help="read the run's PETSc options with this prefix (a_: -a_tao_type bncg, "
        "-a_petsc_contact_two_level 0, -a_stiffness_ksp_rtol 1e-8)",
    )
    p.add_argument(
        "--scalars-only",
        action="store_true",
        help="do not store the height map (for compact result files of large grids)",
    )


COMMANDS = {  # name: (one-line help, description)
    "plot": (
        "draw a map of a stored field (pressure, gap, contact, heights)",
        "A map of one load step's field over the cell, with physical axes and a colour bar.",
    ),
    "study": (
        "the paper's datasets at the paper's parameters, in resumable pieces",
        "Runs the pieces of the paper's figures and of the datasets beyond them (periodic "
        "sweeps and punches, with the exact stiffness, scalars only) into DATA/FIGURE/ "
        "(fig1, ..., hertz, seeds, punch), skipping complete pieces and "
        "stopping cleanly after --minutes; run it again to go on. Pieces another run is "
        "writing are left to it: start one study per core on the same DATA to share them.",
    ),
    "schema": (
        "print the HDF5 output schema (docs/output-schema.md)",
        "Every dataset the commands write, with its units and description.",
    ),
    "periodic": (
        "periodic, load-controlled contact of a rough surface",
        "Hard-wall contact of a rigid rough surface on a periodic "
        "elastic half-space, one TAO solve per nominal pressure.",
    ),
    "punch": (
        "rigid rough square punch on a free half-space",
        "A rigid punch with a rough face pressed into a "
        "non-periodic elastic half-space (Hockney padding), "
        "displacement (--approaches) or load (--forces) "
        "controlled.",
    ),
    "ensemble": (
        "periodic sweeps over many seeds, with statistics",
        "The periodic scene for each seed (one resumable file "
        "OUT_seedK.h5 per seed), then mean, std and standard "
        "error over seeds of every per-step quantity in OUT.h5. Every seed gets the "
        "same pressures: --sweep N takes its default range from the first seed's surface.",
    ),
    "compare": (
        "error against wall time for several solvers",
        "One periodic scene solved by each solver from first "
        "touch; errors against a tightly converged reference "
        "at every iteration; a table (stdout and OUT.csv), "
        "OUT.h5 and a plot OUT.png.",
    ),
    "experiment": (
        "K(p) from a measured p(s) table (paper Eq. C3)",
        "Interfacial stiffness from a squeeze test of an elastic "
        "block of thickness d and effective modulus E' (paper "
        "Appendix C): K* = dp/ds, K = K*/(1 - K* d/E').",
    ),
    "theory": (
        "Persson's theory and the finite-size p_c from a map's spectrum",
        "What theory predicts for a height map (measured, or generated): the radially "
        "averaged spectrum, Persson's mean gap u(p) and stiffness K(p), the exponential "
        "law's u0 and beta, and the finite-size crossover p_c (paper Eq. 13) with a Hurst "
        "exponent fitted to the spectrum.",
    ),
    "demo": (
        "the default scene (periodic 512^2, H=0.7, slope 0.1)",
        "The default scene: periodic 512 x 512 self-affine "
        "surface, H = 0.7, rms slope 0.1, L/lambda_r = 2, "
        "L/lambda_1 = 64, loads from first contact to ~50% area.",
    ),
}


def _command(sub: Any, name: str) -> argparse.ArgumentParser:
    """The subcommand ``name`` with its help and description from :data:`COMMANDS`."""
    summary, description = COMMANDS[name]
    parser: argparse.ArgumentParser = sub.add_parser(name, help=summary, description=description)
    return parser


class _Parser(argparse.ArgumentParser):
    """Argument errors in one line (what is wrong, where the help is), exit status 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"petsc-contact: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="petsc-contact",
        description="Non-adhesive contact of rough elastic solids with PETSc/TAO. "
        "Options with one dash (-tao_type bncg, -tao_monitor, -options_file F, "
        "-log_view, ...) are passed to PETSc. The package's own PETSc options: "
        "-petsc_contact_no_j0 (no Fourier initial Hessian for the BQNK types), "
        "-petsc_contact_no_ksp_pc (no Fourier KSP preconditioner for tron, bnls, "
        "bntr, bntl); the default solver's two-level preconditioner: "
        "-petsc_contact_two_level 0 (off), -petsc_contact_two_level_block B (aggregate "
        "block side, pixels; default 16), -petsc_contact_two_level_max_fraction F (largest "
        "contact fraction it is used at; default 0.1).",
        epilog="Exit status: 0 converged, 1 a step did not converge or is not accurate, 2 bad "
        "input or an output "
        "in use, 69 a package cannot be loaded, 74 results cannot be written (disk full, "
        "unwritable), 75 paused, 130 interrupted.",
    )
    parser.add_argument("--version", action="version", version=f"petsc-contact {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    _geometry_parsers(sub)
    _compare_parser(sub)
    _experiment_parser(sub)
    _demo_parser(sub)
    _plot_parser(sub)
    _study_parser(sub)
    _theory_parser(sub)
    _command(sub, "schema")
    return parser


def _cell_arguments(p: argparse.ArgumentParser, what: str) -> None:
    """``--length`` and ``--modulus`` of the commands without load sweeps."""
    p.add_argument(
        "--length",
        default=None,
        metavar="L|LX,LY",
        help=f"sides of {what}, with an optional unit (default: the file's size, else 1)",
    )
    p.add_argument(
        "--modulus",
        type=_quantity,
        default=1.0,
        metavar="ESTAR",
        help="contact modulus E*, with an optional unit (1GPa; default %(default)s)",
    )


def _theory_parser(sub: Any) -> None:
    p = _command(sub, "theory")
    _surface_arguments(p)
    _cell_arguments(p, "the map")
    p.add_argument(
        "--sweep",
        type=_sweep_spec,
        default=[40],
        metavar="N[,PMIN,PMAX]",
        help="N log-spaced pressures of the predictions, the bounds with an optional unit "
        "(default 40, from 1e-7 E* to 0.1 E*)",
    )
    p.add_argument("--output", required=True, metavar="OUT.h5", help="HDF5 results")
    p.add_argument("--plot", metavar="PNG", help="spectrum, u(p) and K(p) with p_c marked")
    p.add_argument(
        "--compare",
        nargs="+",
        metavar="RUN.h5",
        help="with --plot: draw these periodic runs' mean gap and stiffness beside the theory",
    )
    p.add_argument("--quiet", action="store_true", help="no table on standard output")


def _study_parser(sub: Any) -> None:
    p = _command(sub, "study")
    p.add_argument(
        "--figure",
        choices=("1", "2", "3", "hertz", "seeds", "punch", "all"),
        default="all",
        help="the paper's Figs. 1-3, or the datasets beyond them: the Hertz regime, the "
        "distribution over 64 seeds, the punch's periodic and cut faces (default all)",
    )
    p.add_argument("--minutes", type=_minutes, default=45.0, help="time budget (default 45)")
    p.add_argument("--data", default=os.path.join("data", "paper"), help="default data/paper")
    p.add_argument("--shrink", type=int, default=1, help="divide every grid (a quick look)")
    p.add_argument(
        "--list",
        action="store_true",
        help="print every piece: done, todo or steps kept (13/25), and stop",
    )
    p.add_argument("--quiet", action="store_true", help="no tables")


def _plot_parser(sub: Any) -> None:
    p = _command(sub, "plot")
    p.add_argument(
        "file", metavar="OUT.h5", help="a periodic, punch, ensemble or theory output file"
    )
    p.add_argument(
        "--step",
        type=int,
        default=-1,
        metavar="K",
        help="load step, counted from 1 as the run's table counts (-1, the default: the last)",
    )
    p.add_argument(
        "--field",
        choices=("pressure", "gap", "contact", "heights", "filled"),
        default="pressure",
        help="the map to draw (default pressure; fields need a run with --fields; filled: the "
        "points --fill-undefined filled)",
    )
    p.add_argument(
        "--scale",
        choices=("auto", "linear", "log"),
        default="auto",
        help="colour scale (auto: log for a pressure spanning more than two decades)",
    )
    p.add_argument("--vmin", type=float, metavar="V", help="lower end of the colour scale")
    p.add_argument("--vmax", type=float, metavar="V", help="upper end of the colour scale")
    p.add_argument(
        "--sweep",
        action="store_true",
        help="draw the run's load plot again (what --plot drew; a theory or ensemble file "
        "always gets its plot) instead of a map",
    )
    p.add_argument(
        "--output",
        metavar="PNG",
        help="default: OUT_FIELD_stepK.png for a map, OUT_redrawn.png for a load plot",
    )


def _geometry_parsers(sub: Any) -> None:
    """``periodic``, ``punch`` and ``ensemble``."""
    per = _command(sub, "periodic")
    _surface_arguments(per)
    _run_arguments(per)
    pun = _command(sub, "punch")
    _surface_arguments(pun)
    _run_arguments(pun, punch=True)
    ens = _command(sub, "ensemble")
    _surface_arguments(ens)
    _run_arguments(ens)
    ens.add_argument(
        "--seeds",
        type=_seed_list,
        required=True,
        metavar="K1,K2,...|A-B",
        help="the seeds (a list, or a range A-B inclusive)",
    )


def _compare_parser(sub: Any) -> None:
    cmp_ = _command(sub, "compare")
    _surface_arguments(cmp_)
    _cell_arguments(cmp_, "the periodic cell")
    cmp_.add_argument(
        "--pressure",
        type=float,
        required=True,
        metavar="P",
        help="nominal pressure p0 (units of E*)",
    )
    cmp_.add_argument(
        "--solvers",
        type=_solver_list,
        default=None,
        metavar="S1,S2,...",
        help="TAO types, 'cg' (default solver), 'pk' (Polonsky-Keer) or "
        "options files (default: cg,pk,tron,bnls,bntr,bqnls,blmvm,bncg,gpcg, each with "
        "its options/NAME.opts, which the command line's PETSc options override)",
    )
    cmp_.add_argument(
        "--time-limit",
        type=float,
        default=120.0,
        metavar="S",
        help="stop a solver after S seconds of wall time (default 120)",
    )
    cmp_.add_argument(
        "--stall-iterations",
        type=int,
        default=1000,
        metavar="N",
        help="stop a solver whose natural residual has not fallen 10%% below "
        "its best for N iterations (default 1000; 0: never)",
    )
    cmp_.add_argument(
        "--output",
        required=True,
        metavar="OUT.h5",
        help="results; each finished solver is committed to OUT.h5.partial",
    )
    cmp_.add_argument(
        "--resume",
        action="store_true",
        help="go on from OUT.h5.partial (same options): finished solvers are kept",
    )
    cmp_.add_argument(
        "--overwrite",
        action="store_true",
        help="start afresh even where OUT.h5.partial holds finished solvers (they are deleted)",
    )
    cmp_.add_argument("--quiet", action="store_true", help="no table on standard output")


def _experiment_parser(sub: Any) -> None:
    exp = _command(sub, "experiment")
    exp.add_argument(
        "--table",
        required=True,
        metavar="FILE",
        help="two columns, comma- or whitespace-separated: nominal pressure p, displacement "
        "s of the block's top (# comments and one header line are skipped)",
    )
    exp.add_argument(
        "--modulus",
        type=float,
        required=True,
        metavar="EPRIME",
        help="effective Young's modulus E' of the block (pressure units)",
    )
    exp.add_argument(
        "--thickness",
        type=float,
        required=True,
        metavar="D",
        help="block thickness d (length units of s)",
    )
    exp.add_argument("--output", required=True, metavar="OUT.h5")
    exp.add_argument("--plot", metavar="PNG", help="K and K* against p")
    exp.add_argument("--quiet", action="store_true", help="no table on standard output")


def _demo_parser(sub: Any) -> None:
    demo = _command(sub, "demo")
    _surface_arguments(demo)
    _run_arguments(demo, {**DEMO, "output": "demo.h5", "plot": "demo.png"})
    demo.set_defaults(**{k: v for k, v in DEMO.items() if k != "pressures"})
