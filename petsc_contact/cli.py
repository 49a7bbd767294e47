"""``petsc-contact``: the command line, a thin layer over the Python API.

Options with two dashes (``--grid 512``) are the package's; options with one dash
(``-tao_type bncg``, ``-tao_monitor``, ``-options_file f``, ``-log_view``) go to PETSc
unchanged.  Exit status: 0 all steps converged; 1 some step did not converge (the output
flags it); 2 bad input; 130 interrupted (finished steps kept in ``OUT.h5.partial``).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import sys
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import __version__
from .output import (
    ENSEMBLE,
    EXPERIMENT,
    annotate,
    atomic_h5,
    ensemble_entry,
    schema_markdown,
    write_attributes,
)
from .step import FIELD_NAMES

EXIT_NOT_CONVERGED = 1
EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 130

DEMO = {
    "grid": 512,
    "hurst": 0.7,
    "rms_slope": 0.1,
    "rolloff_ratio": 2.0,
    "cutoff_ratio": 64.0,
    "seed": 1,
    "length": 1.0,
    "modulus": 1.0,
    "pressures": "3e-5,1e-4,3e-4,1e-3,3e-3,1e-2,2e-2,3e-2",
}

_PETSC_OPTION = re.compile(r"^-[A-Za-z_]")
_NUMBER = re.compile(r"^-?(\d|\.\d)")


class InputError(Exception):
    """Bad user input: reported as one line, exit status 2."""


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
        if tok != "-h" and _PETSC_OPTION.match(tok) and not tok.startswith("--"):
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


def _float_list(text: str) -> list[float]:
    try:
        return [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated numbers, got '{text}'"
        ) from None


def _sweep_spec(text: str) -> list[float]:
    values = _float_list(text)
    if len(values) not in (1, 3) or values[0] < 2 or values[0] != int(values[0]):
        raise argparse.ArgumentTypeError(f"expected N or N,PMIN,PMAX with N >= 2, got '{text}'")
    if len(values) == 3 and not 0 < values[1] < values[2]:
        raise argparse.ArgumentTypeError(f"need 0 < PMIN < PMAX, got '{text}'")
    return values


def _seed_list(text: str) -> list[int]:
    try:
        if "-" in text.strip("-") and "," not in text:
            a, b = (int(v) for v in text.split("-", 1))
            seeds = list(range(a, b + 1))
        else:
            seeds = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected K1,K2,... or A-B, got '{text}'") from None
    if not seeds or len(set(seeds)) != len(seeds):
        raise argparse.ArgumentTypeError(f"need distinct seeds, got '{text}'")
    return seeds


def _surface_arguments(p: argparse.ArgumentParser) -> None:
    s = p.add_argument_group("surface (a file, or a generated self-affine surface, paper Eq. 5)")
    s.add_argument(
        "--heights",
        metavar="FILE",
        help="height map: .npy, or a text/.csv matrix; square n x n, length units",
    )
    s.add_argument("--grid", type=int, metavar="N", help="generate an N x N surface")
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
        help="system size over short-wavelength cut-off (default N/2)",
    )
    s.add_argument("--seed", type=int, default=0, metavar="K", help="random seed (default 0)")
    s.add_argument(
        "--exact-rms",
        action="store_true",
        help="rescale the realisation to hit the rms target exactly",
    )


def _run_arguments(
    p: argparse.ArgumentParser, defaults: dict[str, Any] | None = None, punch: bool = False
) -> None:
    d = defaults or {}
    p.add_argument(
        "--length",
        type=float,
        default=d.get("length", 1.0),
        metavar="L",
        help=("side Lp of the square punch footprint" if punch else "side of the periodic cell")
        + " (default %(default)s)",
    )
    p.add_argument(
        "--modulus",
        type=float,
        default=d.get("modulus", 1.0),
        metavar="ESTAR",
        help="contact modulus E* (default %(default)s)",
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
        type=_float_list,
        metavar="D1,D2,...",
        help="rigid approaches beyond first touch (length units), in order",
    )
    loads.add_argument(
        "--forces",
        type=_float_list,
        metavar="F1,F2,...",
        help="total forces (E* x length^2), in order (load control)",
    )
    loads.add_argument(
        "--sweep",
        type=_sweep_spec,
        metavar="N[,DMIN,DMAX]",
        help="N log-spaced approaches from DMIN to DMAX (default: 0.01 and "
        "3 times the rms recess of the punch face)",
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
        type=_float_list,
        default=_float_list(d["pressures"]) if "pressures" in d else None,
        metavar="P1,P2,...",
        help="nominal pressures p0 (units of E*), in order",
    )
    loads.add_argument(
        "--sweep",
        type=_sweep_spec,
        metavar="N[,PMIN,PMAX]",
        help="N log-spaced pressures from PMIN to PMAX (default: 1e-4 and "
        "0.9 times the full-contact pressure -min(K h))",
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


COMMANDS = {  # name: (one-line help, description)
    "plot": (
        "draw a map of a stored field (pressure, gap, contact, heights)",
        "A map of one load step's field over the cell, with physical axes and a colour bar.",
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
        "section III): K* = dp/ds, K = K*/(1 - K* d/E').",
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


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="petsc-contact",
        description="Non-adhesive contact of rough elastic solids with PETSc/TAO. "
        "Options with one dash (-tao_type bncg, -tao_monitor, -options_file F, "
        "-log_view, ...) are passed to PETSc. The package's own PETSc options: "
        "-petsc_contact_no_j0 (no Fourier initial Hessian for the BQNK types), "
        "-petsc_contact_no_ksp_pc (no Fourier KSP preconditioner for tron, bnls, "
        "bntr, bntl).",
        epilog="Exit status: 0 converged, 1 a step did not converge, 2 bad input, 130 interrupted.",
    )
    parser.add_argument("--version", action="version", version=f"petsc-contact {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    _geometry_parsers(sub)
    _compare_parser(sub)
    _experiment_parser(sub)
    _demo_parser(sub)
    _plot_parser(sub)
    _command(sub, "schema")
    return parser


def _plot_parser(sub: Any) -> None:
    p = _command(sub, "plot")
    p.add_argument("file", metavar="OUT.h5", help="a periodic or punch output file")
    p.add_argument("--step", type=int, default=-1, metavar="K", help="load step (default: last)")
    p.add_argument(
        "--field",
        choices=("pressure", "gap", "contact", "heights"),
        default="pressure",
        help="the map to draw (default pressure; fields need a run with --fields)",
    )
    p.add_argument("--output", metavar="PNG", help="default: OUT_FIELD_stepK.png")


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
    cmp_.add_argument(
        "--length",
        type=float,
        default=1.0,
        metavar="L",
        help="side of the periodic cell (default %(default)s)",
    )
    cmp_.add_argument(
        "--modulus",
        type=float,
        default=1.0,
        metavar="ESTAR",
        help="contact modulus E* (default %(default)s)",
    )
    cmp_.add_argument(
        "--pressure",
        type=float,
        required=True,
        metavar="P",
        help="nominal pressure p0 (units of E*)",
    )
    cmp_.add_argument(
        "--solvers",
        type=lambda t: [v for v in t.split(",") if v],
        default=None,
        metavar="S1,S2,...",
        help="TAO types, 'cg' (default solver), 'pk' (Polonsky-Keer) or "
        "options files (default: cg,pk,tron,bnls,bntr,bqnls,blmvm,bncg,gpcg)",
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
    cmp_.add_argument("--output", required=True, metavar="OUT.h5")
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


def _generated(args: argparse.Namespace) -> bool:
    if args.heights is not None:
        given = [
            o
            for o in ("grid", "hurst", "rms_slope", "rms_height")
            if getattr(args, o) is not None and args.command != "demo"
        ]
        if given:
            raise InputError(
                "--heights excludes the surface generation options "
                f"(--{given[0].replace('_', '-')})"
            )
        return False
    missing = [o for o in ("grid", "hurst") if getattr(args, o) is None]
    if missing:
        raise InputError(
            "give --heights FILE, or --grid N --hurst H and --rms-slope or "
            "--rms-height to generate a surface"
        )
    if (args.rms_slope is None) == (args.rms_height is None):
        raise InputError("give exactly one of --rms-slope and --rms-height")
    return True


def _check_numbers(args: argparse.Namespace) -> None:
    for option in ("length", "modulus"):
        v = getattr(args, option)
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"--{option} must be positive and finite, got {v}")
    if getattr(args, "sweep", None) is not None:
        return
    name = next(
        (
            n
            for n in ("pressures", "approaches", "forces", "pressure")
            if getattr(args, n, None) is not None
        ),
        None,
    )
    if name is None:
        return
    values = getattr(args, name)
    values = values if isinstance(values, list) else [values]
    if not values:
        raise InputError(f"--{name} needs at least one value")
    for v in values:
        if not (np.isfinite(v) and (v > 0 or (name == "approaches" and v == 0))):
            raise InputError(f"--{name} must be positive and finite, got {v}")


def _attributes(
    args: argparse.Namespace,
    argv: Sequence[str],
    petsc: Any,
    realised: dict[str, float],
    resolved: dict[str, Any],
) -> dict[str, Any]:
    """What reproduces the run: every option (defaults resolved), versions, PETSc options."""
    from .output import file_digest, petsc_options, versions

    params = {k: v for k, v in vars(args).items() if k not in ("quiet",)} | resolved
    attrs: dict[str, Any] = {
        "geometry": "punch" if args.command == "punch" else "periodic",
        "command_line": " ".join(["petsc-contact", *argv]),
        "parameters": params,
        "petsc_options": petsc_options(petsc),
        "versions": versions(petsc),
        "mpi_size": petsc.COMM_WORLD.getSize(),
        "length": args.length,
        "modulus": args.modulus,
        "units": (
            "SI-free: lengths in the unit of --length and the heights, pressures and "
            "stiffness per area in the unit of --modulus"
        ),
        **realised,
    }
    if args.heights is not None:
        attrs["heights_file"] = os.path.abspath(args.heights)
        attrs["heights_sha256"] = file_digest(args.heights)
    else:
        attrs.update(
            seed=args.seed,
            hurst=args.hurst,
            rolloff_ratio=args.rolloff_ratio,
            cutoff_ratio=params["cutoff_ratio"],
            grid=args.grid,
        )
    return attrs


PERIODIC_COLUMNS = (("p0", "nominal_pressure", "{:>11.4e}"), ("mean_gap", "mean_gap", "{:>12.6e}"))
PUNCH_COLUMNS = (
    ("approach", "approach", "{:>11.4e}"),
    ("force", "force", "{:>12.6e}"),
    ("K_tot", "total_stiffness", "{:>10.4e}"),
)


def _header(columns: tuple[tuple[str, str, str], ...]) -> str:
    widths = [len(fmt.format(0.0)) for _, _, fmt in columns]
    head = " ".join(f"{title:>{w}}" for (title, _, _), w in zip(columns, widths, strict=True))
    return f"{'step':>7} {head} {'area':>9} {'its':>6} {'time_s':>8} {'kkt':>9}  tao_reason"


def _row(i: int, total: int, s: dict[str, Any], columns: tuple[tuple[str, str, str], ...]) -> str:
    flag = "" if s["converged"] else "   <-- NOT CONVERGED: " + s["verification"]
    values = " ".join(fmt.format(s[key]) for _, key, fmt in columns)
    return (
        f"{f'{i + 1}/{total}':>7} {values} {s['area_fraction']:>9.5f} {s['iterations']:>6d} "
        f"{s['solve_time']:>8.3f} {s['kkt_residual']:>9.1e}  {s['tao_reason']}{flag}"
    )


def _scene(
    args: argparse.Namespace, full: np.ndarray | None
) -> tuple[Any, Any, np.ndarray, dict[str, Any]]:
    """The grid, its FFT, this rank's slab of the heights (read, or generated) and the
    parameters the options left to their defaults (``cutoff_ratio``)."""
    from .fft import make_fft
    from .grid import Grid

    grid = Grid(args.grid if full is None else int(full.shape[0]), args.length)
    fft = make_fft(grid)
    resolved = {}
    if full is None:
        resolved["cutoff_ratio"] = (
            args.cutoff_ratio if args.cutoff_ratio is not None else grid.n / 2
        )
    return grid, fft, _surface(args, full, grid, fft, resolved.get("cutoff_ratio")), resolved


def _surface(
    args: argparse.Namespace, full: np.ndarray | None, grid: Any, fft: Any, cutoff: Any
) -> np.ndarray:
    """This rank's slab of the heights: read, or generated (paper Eq. 5)."""
    from .output import check_finite
    from .surface import self_affine

    if full is None:
        return self_affine(
            grid,
            fft,
            hurst=args.hurst,
            rolloff_ratio=args.rolloff_ratio,
            cutoff_ratio=cutoff,
            seed=args.seed,
            rms_height=args.rms_height,
            rms_slope=args.rms_slope,
            exact=args.exact_rms,
        )
    heights = grid.scatter(full)
    check_finite(grid, heights)
    return heights


def _disk(n: int) -> np.ndarray:
    """The disk inscribed in an ``n x n`` footprint (pixel centres within radius n/2)."""
    x = np.arange(n) + 0.5 - n / 2
    return x[:, None] ** 2 + x[None, :] ** 2 < (n / 2) ** 2


def run(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    """Run ``periodic``, ``demo`` or ``punch``; write the HDF5 file (and plot)."""
    petsc, grid, fft, heights, resolved = _prepare(args, petsc_args)
    from .surface import rms_of

    realised = {
        "rms_height": rms_of(grid, fft, heights),
        "rms_slope": rms_of(grid, fft, heights, slope=True),
    }
    if args.command == "punch":
        plan = _punch_plan(args, grid, heights)
    else:
        plan = _periodic_plan(args, grid, fft, heights)
    attributes = _attributes(args, argv, petsc, realised, {**resolved, **plan.resolved})
    attributes["fft_backend"] = plan.fft_backend
    root = grid.comm.rank == 0
    show = root and not args.quiet
    try:
        writer, done, start = _open_writer(args, grid, attributes, heights, len(plan.loads), show)
        table = _finished_rows(args.output, done) if done and root else []
        if show:
            print(
                f"# {args.command} {grid.n}x{grid.n}, L = {args.length:g}, E* = {args.modulus:g}, "
                f"h_rms = {realised['rms_height']:.4g}, h'_rms = {realised['rms_slope']:.4g}"
                f"{plan.intro}",
                flush=True,
            )
            print(_header(plan.columns), flush=True)
        try:
            _run_steps(args, plan, writer, done, start, table, show)
        except KeyboardInterrupt:
            writer.abandon()
            return EXIT_INTERRUPTED
    finally:
        plan.close()
    writer.finish()
    return _conclude(args, plan, table, realised, root)


def _prepare(
    args: argparse.Namespace, petsc_args: list[str], check_type: bool = True
) -> tuple[Any, Any, Any, np.ndarray, dict[str, Any]]:
    """Check the input, then PETSc, the grid, its FFT and this rank's heights."""
    from . import _petsc
    from .output import check_writable, load_heights
    from .solve import check_tao_type

    _check_numbers(args)
    full = None if _generated(args) else load_heights(args.heights)
    check_writable(args.output)
    if getattr(args, "plot", None):
        check_writable(args.plot)
    petsc = _petsc.init(petsc_args)
    if check_type:
        check_tao_type(petsc)
    grid, fft, heights, resolved = _scene(args, full)
    return petsc, grid, fft, heights, resolved


def _open_writer(
    args: argparse.Namespace,
    grid: Any,
    attributes: dict[str, Any],
    heights: np.ndarray,
    total: int,
    show: bool,
) -> tuple[Any, int, np.ndarray | None]:
    """The step writer, the steps already done and the state to start from (``--resume``)."""
    from .output import StepWriter, read_resume

    fields = FIELD_NAMES if args.fields else ()
    done, state = read_resume(args.output, attributes["parameters"]) if args.resume else (0, None)
    if not done:
        return StepWriter(args.output, grid, attributes, heights, fields), 0, None
    if show:
        print(f"# resuming {args.output}.partial after {done} of {total} steps", flush=True)
    start = grid.scatter(state) if state is not None else None
    return StepWriter.reopen(args.output, grid, fields), done, start


def _run_steps(
    args: argparse.Namespace,
    plan: Plan,
    writer: Any,
    done: int,
    start: np.ndarray | None,
    table: list[dict[str, Any]],
    show: bool,
) -> None:
    """Solve the remaining loads; write, tabulate and print each step as it finishes."""
    total = len(plan.loads)
    for i, step in enumerate(plan.steps(plan.loads[done:], start, args.fields), done):
        fields = {name: step.field(name) for name in FIELD_NAMES} if args.fields else None
        writer.append(step.scalars, fields, state=step.state)
        table.append(step.scalars)
        if show:
            print(_row(i, total, step.scalars, plan.columns), flush=True)


def _conclude(
    args: argparse.Namespace,
    plan: Plan,
    table: list[dict[str, Any]],
    realised: dict[str, float],
    root: bool,
) -> int:
    """Plot, report the steps that did not converge, and return the exit status."""
    if args.plot and root:
        from .plot import plot_punch, plot_sweep

        if args.command == "punch":
            plot_punch(args.plot, table)
        else:
            plot_sweep(args.plot, table, args.modulus, realised["rms_height"])
    failed = [s for s in table if not s["converged"]]
    if failed and root:
        load = plan.columns[0]
        print(
            f"petsc-contact: error: {len(failed)} of {len(table)} load steps did NOT converge "
            f"(first: {load[0]} = {failed[0][load[1]]:g}, {failed[0]['verification']}); "
            f"they are flagged converged = False in {args.output}",
            file=sys.stderr,
        )
    if root and not args.quiet:
        print(f"# wrote {args.output}" + (f" and {args.plot}" if args.plot else ""))
    return EXIT_NOT_CONVERGED if failed else 0


@dataclass
class Plan:
    """What a geometry runs: its loads, a step generator, table columns, a closer."""

    loads: list[float]
    steps: Callable[[list[float], np.ndarray | None, bool], Iterator[Any]]
    columns: tuple[tuple[str, str, str], ...]
    intro: str
    close: Callable[[], None] = lambda: None
    fft_backend: str = ""  # class name of the operator's FFT backend (fft module)
    resolved: dict[str, Any] = field(default_factory=dict)  # options the plan resolved


def _periodic_plan(args: argparse.Namespace, grid: Any, fft: Any, heights: np.ndarray) -> Plan:
    from .periodic import sweep
    from .problem import PeriodicProblem

    problem = PeriodicProblem(grid, fft, heights, args.modulus)
    p_full = problem.full_contact_pressure()
    resolved = {}
    pressures = args.pressures
    if args.sweep is not None:
        n, lo, hi = (
            (args.sweep + [1e-4 * p_full, 0.9 * p_full])[:3] if len(args.sweep) == 1 else args.sweep
        )
        pressures = [float(p) for p in np.geomspace(lo, hi, int(n))]
        resolved = {"pressures": pressures, "sweep": None}  # the file records the loads

    def steps(loads: list[float], start: np.ndarray | None, fields: bool) -> Iterator[Any]:
        return sweep(problem, loads, fields, stiffness=args.stiffness, start=start)

    return Plan(
        list(pressures),
        steps,
        PERIODIC_COLUMNS,
        f", full contact at p0 = {p_full:.4g}",
        fft_backend=type(fft).__name__,
        resolved=resolved,
    )


def _punch_plan(args: argparse.Namespace, grid: Any, heights: np.ndarray) -> Plan:
    from .punch import PHARR_BETA, PunchProblem, PunchSolver

    mask = grid.scatter(_disk(grid.n)) > 0 if args.footprint == "disk" else None
    beta = 1.0 if args.footprint == "disk" else PHARR_BETA
    problem = PunchProblem(grid, heights, args.modulus, mask, args.flat_stiffness, beta)
    solver = PunchSolver(problem)
    by_force = args.forces is not None
    resolved = {}
    approaches = args.approaches
    if args.sweep is not None:
        n, lo, hi = (
            (args.sweep + [0.01 * problem.scale_length, 3 * problem.scale_length])[:3]
            if len(args.sweep) == 1
            else args.sweep
        )
        approaches = [float(d) for d in np.geomspace(lo, hi, int(n))]
        resolved = {"approaches": approaches, "sweep": None}  # the file records the loads

    def steps(loads: list[float], start: np.ndarray | None, fields: bool) -> Iterator[Any]:
        if start is not None:
            solver.restart_from(start)
        for v in loads:
            if by_force:
                yield solver.at_force(v, fields, stiffness=args.stiffness)
            else:
                yield solver.at_approach(v, fields, stiffness=args.stiffness)

    intro = (
        f", K_flat = {solver.k_flat:.6g} ({args.flat_stiffness}; analytic "
        f"{solver.k_flat_analytic:.6g})"
    )
    return Plan(
        list(args.forces if by_force else approaches),
        steps,
        PUNCH_COLUMNS + (("p0", "nominal_pressure", "{:>10.3e}"),),
        intro,
        solver.close,
        type(problem.compliance.fft).__name__,
        resolved,
    )


def _finished_rows(path: str, steps: int) -> list[dict[str, Any]]:
    """The per-step scalars already in an interrupted run's partial file (for the plot)."""
    import h5py

    with h5py.File(path + ".partial", "r") as f:
        names = [k for k in f if f[k].ndim == 1 and f[k].shape[0] >= steps]
        rows = [{k: f[k][i] for k in names} for i in range(steps)]
    for row in rows:
        for k, v in row.items():
            row[k] = v.decode() if isinstance(v, bytes) else v
    return rows


def run_ensemble(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    """One periodic run per seed (each resumable), then statistics over seeds in OUT.h5."""
    import h5py

    from .ensemble import ensemble_statistics
    from .output import check_writable

    if args.heights is not None:
        raise InputError("ensemble needs a generated surface (--grid, --hurst, ...), not --heights")
    check_writable(args.output)
    if args.plot:
        check_writable(args.plot)
    pressures = args.pressures if args.pressures is not None else _ensemble_loads(args, petsc_args)
    stem = args.output[:-3] if args.output.endswith(".h5") else args.output
    files, status = [], 0
    for seed in args.seeds:
        path = f"{stem}_seed{seed}.h5"
        files.append(path)
        if args.resume and os.path.exists(path):
            continue  # finished earlier: nothing recomputed
        one = argparse.Namespace(
            **{
                **vars(args),
                **{"seed": seed, "output": path, "command": "periodic", "plot": None},
                **{"pressures": pressures, "sweep": None},
            }
        )
        del one.seeds
        code = run(one, argv, petsc_args)
        if code == EXIT_INTERRUPTED:
            return code
        status = max(status, code)
    from mpi4py import MPI

    record = _ensemble_record(args, argv, pressures)  # collective: every rank joins
    if MPI.COMM_WORLD.rank == 0:
        summary = _write_ensemble(args, files, ensemble_statistics, h5py, record)
        if args.plot:
            from .plot import plot_ensemble

            plot_ensemble(args.plot, summary, args.modulus)
        if not args.quiet:
            plotted = f" and {args.plot}" if args.plot else ""
            print(f"# wrote {args.output}{plotted} ({len(files)} seeds)")
    return status


def _ensemble_loads(args: argparse.Namespace, petsc_args: list[str]) -> list[float]:
    """``--sweep N[,PMIN,PMAX]``'s pressures, the same for every seed: the default range is
    ``1e-4`` to ``0.9`` times the full-contact pressure of the first seed's surface."""
    if len(args.sweep) == 3:
        n, lo, hi = args.sweep
    else:
        from .problem import PeriodicProblem

        first = argparse.Namespace(**{**vars(args), "seed": args.seeds[0]})
        _, grid, fft, heights, _ = _prepare(first, petsc_args)
        p_full = PeriodicProblem(grid, fft, heights, args.modulus).full_contact_pressure()
        n, lo, hi = args.sweep[0], 1e-4 * p_full, 0.9 * p_full
    return [float(p) for p in np.geomspace(lo, hi, int(n))]


def _ensemble_record(
    args: argparse.Namespace, argv: Sequence[str], pressures: list[float]
) -> dict[str, Any]:
    """What reproduces an ensemble: its command, options, versions and PETSc options."""
    from . import _petsc
    from .output import petsc_options, versions

    petsc = _petsc.petsc()
    return {
        "command_line": " ".join(["petsc-contact", *argv]),
        "parameters": {k: v for k, v in vars(args).items() if k != "quiet"}
        | {"pressures": pressures, "sweep": None},
        "petsc_options": petsc_options(petsc),
        "versions": versions(petsc),
        "mpi_size": petsc.COMM_WORLD.getSize(),
    }


ENSEMBLE_QUANTITIES = tuple(k for k in ENSEMBLE if k not in ("seeds", "nominal_pressure"))


def _write_ensemble(
    args: argparse.Namespace, files: list[str], stats: Any, h5py: Any, record: dict[str, Any]
) -> dict[str, np.ndarray]:
    """The summary over seeds, written to ``OUT.h5`` with the run record; returned too."""
    tables: dict[str, list[np.ndarray]] = {}
    for path in files:
        with h5py.File(path, "r") as f:
            ok = f["converged"][:]
            pressure = f["nominal_pressure"][:]
            for q in ENSEMBLE_QUANTITIES:
                if q in f:
                    tables.setdefault(q, []).append(np.where(ok, f[q][:], np.nan))
    summary: dict[str, np.ndarray] = {"seeds": np.array(args.seeds), "nominal_pressure": pressure}
    for q, rows in tables.items():
        summary[q] = np.array(rows)
        summary.update({f"{q}_{name}": v for name, v in stats(summary[q]).items()})
    with atomic_h5(args.output) as out:
        write_attributes(out, {"geometry": "periodic ensemble", **record})
        out.attrs["seed_files"] = json.dumps([os.path.abspath(p) for p in files])
        for name, values in summary.items():
            out[name] = values
        out.attrs["complete"] = True
        annotate(out, ensemble_entry)
    return summary


def run_compare(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    """``petsc-contact compare``: every solver on one scene, error against time."""
    from .compare import DEFAULT_SOLVERS, compare, solver_options, write_compare
    from .problem import PeriodicProblem
    from .surface import rms_of

    if not args.time_limit >= 0 or args.stall_iterations < 0:
        raise InputError("--time-limit and --stall-iterations must not be negative")
    solvers = args.solvers or list(DEFAULT_SOLVERS)
    for name in solvers:
        solver_options(name)  # unknown options files fail here, before any work
    petsc, grid, fft, heights, resolved = _prepare(args, petsc_args, check_type=False)
    problem = PeriodicProblem(grid, fft, heights, args.modulus)
    show = grid.comm.rank == 0 and not args.quiet
    if show:
        print(
            f"{'solver':>16} {'converged':>9} {'its':>6} {'time_s':>8} {'gap_err':>9} "
            f"{'p_err':>9} {'residual':>9} {'compl':>9}  reason",
            flush=True,
        )

    reference, trajectories = compare(
        problem,
        args.pressure,
        solvers,
        args.time_limit,
        stall_iterations=args.stall_iterations,
        report=_print_trajectory if show else None,
    )
    realised = {"rms_height": rms_of(grid, fft, heights), "pressure": args.pressure}  # collective
    status = 0 if all(t.converged for t in trajectories) else EXIT_NOT_CONVERGED
    if grid.comm.rank != 0:
        return status  # the same on every rank: the verdicts come from reduced residuals
    attrs = _attributes(args, argv, petsc, realised, resolved)
    csv, png = write_compare(args.output, reference, trajectories, attrs)
    if show:
        print(
            f"# reference: mean gap {reference['mean_gap']:.10e}, natural residual "
            f"{reference['natural_residual']:.1e} (tolerance {reference['tolerance']:.0e})"
        )
        print(f"# wrote {args.output}, {csv} and {png}")
    return status


def _print_trajectory(trajectory: Any) -> None:
    """One row of the ``compare`` table, printed as the solver finishes."""
    from .compare import table_rows

    ((name, reason, ok, its, t, eg, ep, r, c),) = table_rows([trajectory])
    print(
        f"{name:>16} {str(ok):>9} {its:>6d} {t:>8.3f} {eg:>9.1e} {ep:>9.1e} "
        f"{r:>9.1e} {c:>9.1e}  {reason}",
        flush=True,
    )


def run_plot(args: argparse.Namespace) -> int:
    """``petsc-contact plot``: one field of one step as a map."""
    import h5py

    from .output import ENTRIES, check_writable
    from .plot import plot_field

    if not os.path.isfile(args.file):
        raise InputError(f"'{args.file}' does not exist")
    with h5py.File(args.file, "r") as f:
        if args.field not in f:
            hint = " (run with --fields)" if args.field != "heights" else ""
            raise InputError(f"'{args.file}' has no dataset '{args.field}'{hint}")
        data = f[args.field]
        steps = data.shape[0] if data.ndim == 3 else 1
        if not -steps <= args.step < steps:
            raise InputError(f"--step {args.step} is out of range: the file has {steps} steps")
        values = data[args.step] if data.ndim == 3 else data[...]
        length = float(f.attrs.get("length", 1.0))
        step = args.step % steps
        load = f["nominal_pressure"][step] if "nominal_pressure" in f else np.nan
        per_step = data.ndim == 3
    stem = args.file[:-3] if args.file.endswith(".h5") else args.file
    out = args.output or f"{stem}_{args.field}_step{step}.png"
    check_writable(out)
    title = f"{args.field}, step {step}" + (f", p0 = {load:.3g}" if per_step else "")
    unit = {"length": "in the unit of --length", "pressure": "in the unit of --modulus"}
    label = f"{args.field} {unit.get(ENTRIES[args.field].units, '(1: in contact)')}"
    plot_field(out, values, length, title, label, args.field == "contact")
    print(f"# wrote {out}")
    return 0


def run_experiment(args: argparse.Namespace) -> int:
    """``petsc-contact experiment``: Eq. C3 on a measured ``p(s)`` table."""
    from .output import check_writable, load_table
    from .theory import block_corrected_stiffness

    for name in ("modulus", "thickness"):
        v = getattr(args, name)
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"--{name} must be positive and finite, got {v}")
    if not os.path.isfile(args.table):
        raise InputError(f"table '{args.table}' does not exist")
    table = load_table(args.table, 2)
    check_writable(args.output)
    p, disp = table[:, 0], table[:, 1]
    k_star, k = block_corrected_stiffness(p, disp, args.modulus, args.thickness)

    with atomic_h5(args.output) as f:
        f["pressure"], f["displacement"] = p, disp
        f["measured_stiffness"], f["stiffness"] = k_star, k
        f.attrs.update(
            geometry="experiment",
            block_modulus=args.modulus,
            thickness=args.thickness,
            table=os.path.abspath(args.table),
            formula="K* = dp/ds (2nd-order differences), K = K*/(1 - K* d/E')",
        )
        annotate(f, EXPERIMENT.__getitem__)
    if not args.quiet:
        print(f"{'p':>12} {'s':>12} {'K*':>12} {'K':>12}")
        for row in zip(p, disp, k_star, k, strict=True):
            print(" ".join(f"{v:>12.5g}" for v in row))
    if args.plot:
        from .plot import plot_experiment

        plot_experiment(args.plot, p, k_star, k)
    return 0


def _interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    ours, petsc_args = split_arguments(argv)
    args = build_parser().parse_args(ours)
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        status = _dispatch(args, argv, petsc_args)
        _report_unused(petsc_args)
        return status
    except (InputError, ValueError, OSError) as exc:
        _error(str(exc))
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED
    except Exception as exc:
        if type(exc).__name__ == "Error" and "petsc4py" in type(exc).__module__:
            _error(f"PETSc error: {exc}")
            return EXIT_BAD_INPUT
        raise


def _dispatch(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    if args.command == "ensemble":
        return run_ensemble(args, argv, petsc_args)
    if args.command == "experiment":
        return run_experiment(args)
    if args.command == "compare":
        return run_compare(args, argv, petsc_args)
    if args.command == "schema":
        sys.stdout.write(schema_markdown())
        return 0
    if args.command == "plot":
        return run_plot(args)
    return run(args, argv, petsc_args)


def _report_unused(petsc_args: list[str]) -> None:
    """Warn about the user's PETSc options that nothing read (a misspelt ``-tao_typo``)."""
    if not petsc_args or "petsc4py.PETSc" not in sys.modules:
        return
    from . import _petsc

    names = [a[1:] for a in petsc_args if a.startswith("-") and not _is_number(a)]
    unused = _petsc.unused_options(names)
    if unused:
        _error(f"PETSc options never used: {' '.join(unused)}", "warning")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _error(message: str, kind: str = "error") -> None:
    from mpi4py import MPI

    if MPI.COMM_WORLD.rank == 0:
        print(f"petsc-contact: {kind}: {message}", file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())
