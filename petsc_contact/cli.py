"""``petsc-contact``: the command line, a thin layer over the Python API.

Options with two dashes (``--grid 512``) are the package's; options with one dash
(``-tao_type bncg``, ``-tao_monitor``, ``-options_file f``, ``-log_view``) go to PETSc
unchanged.  Exit status: 0 all steps converged; 1 some step did not converge (the output
flags it); 2 bad input; 130 interrupted (finished steps kept in ``OUT.h5.partial``).
"""

from __future__ import annotations

import argparse
import os
import re
import signal
import sys
from typing import Any, Sequence

import numpy as np

EXIT_NOT_CONVERGED = 1
EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 130

DEMO = {"grid": 512, "hurst": 0.7, "rms_slope": 0.1, "rolloff_ratio": 2.0,
        "cutoff_ratio": 64.0, "seed": 1, "length": 1.0, "modulus": 1.0,
        "pressures": "3e-5,1e-4,3e-4,1e-3,3e-3,1e-2,2e-2,3e-2"}

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
            if i + 1 < len(tokens) and (not tokens[i + 1].startswith("-")
                                         or _NUMBER.match(tokens[i + 1])):
                petsc.append(tokens[i + 1])
                i += 1
        else:
            ours.append(tok)
            if tok.startswith("--") and "=" not in tok and i + 1 < len(tokens) \
                    and _NUMBER.match(tokens[i + 1]):
                ours.append(tokens[i + 1])
                i += 1
        i += 1
    return ours, petsc


def _float_list(text: str) -> list[float]:
    try:
        return [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got '{text}'")


def _surface_arguments(p: argparse.ArgumentParser) -> None:
    s = p.add_argument_group("surface (a file, or a generated self-affine surface, paper Eq. 5)")
    s.add_argument("--heights", metavar="FILE",
                   help="height map: .npy, or a text/.csv matrix; square n x n, length units")
    s.add_argument("--grid", type=int, metavar="N", help="generate an N x N surface")
    s.add_argument("--hurst", type=float, metavar="H", help="Hurst exponent (0..1)")
    s.add_argument("--rms-slope", type=float, metavar="S", help="target rms slope h'_rms")
    s.add_argument("--rms-height", type=float, metavar="R", help="target rms height h_rms")
    s.add_argument("--rolloff-ratio", type=float, metavar="L/lambda_r", default=1.0,
                   help="system size over roll-off wavelength (default 1)")
    s.add_argument("--cutoff-ratio", type=float, metavar="L/lambda_1",
                   help="system size over short-wavelength cut-off (default N/2)")
    s.add_argument("--seed", type=int, default=0, metavar="K", help="random seed (default 0)")
    s.add_argument("--exact-rms", action="store_true",
                   help="rescale the realisation to hit the rms target exactly")


def _run_arguments(p: argparse.ArgumentParser, defaults: dict[str, Any] | None = None,
                   punch: bool = False) -> None:
    d = defaults or {}
    p.add_argument("--length", type=float, default=d.get("length", 1.0), metavar="L",
                   help=("side Lp of the square punch footprint" if punch else
                         "side of the periodic cell") + " (default %(default)s)")
    p.add_argument("--modulus", type=float, default=d.get("modulus", 1.0), metavar="ESTAR",
                   help="contact modulus E* (default %(default)s)")
    if punch:
        loads = p.add_mutually_exclusive_group(required=True)
        loads.add_argument("--approaches", type=_float_list, metavar="D1,D2,...",
                           help="rigid approaches beyond first touch (length units), in order")
        loads.add_argument("--forces", type=_float_list, metavar="F1,F2,...",
                           help="total forces (E* x length^2), in order (load control)")
        p.add_argument("--footprint", choices=("square", "disk"), default="square",
                       help="punch outline: the whole square, or the inscribed disk")
        p.add_argument("--flat-stiffness", choices=("grid", "analytic"), default="grid",
                       help="flat-punch stiffness in Eq. 2: computed on the same grid "
                            "(default) or beta x 2 E* sqrt(A/pi), beta = 1.012 (square) or 1 "
                            "(disk)")
    else:
        p.add_argument("--pressures", type=_float_list, required="pressures" not in d,
                       default=_float_list(d["pressures"]) if "pressures" in d else None,
                       metavar="P1,P2,...", help="nominal pressures p0 (units of E*), in order")
    p.add_argument("--stiffness", action="store_true",
                   help="add the exact incremental stiffness per area (contact set held "
                        "fixed) as the dataset 'stiffness'")
    p.add_argument("--output", required="output" not in d, default=d.get("output"),
                   metavar="OUT.h5", help="HDF5 results (written atomically)")
    p.add_argument("--fields", action="store_true",
                   help="store the gap and pressure fields of every step")
    p.add_argument("--plot", metavar="PNG", default=d.get("plot"),
                   help="write a PNG of the results against load")
    p.add_argument("--quiet", action="store_true", help="no table on standard output")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="petsc-contact",
        description="Non-adhesive contact of rough elastic solids with PETSc/TAO. "
                    "Options with one dash (-tao_type bncg, -tao_monitor, -options_file F, "
                    "-log_view, ...) are passed to PETSc.",
        epilog="Exit status: 0 converged, 1 a step did not converge, 2 bad input, "
               "130 interrupted.")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    per = sub.add_parser("periodic", help="periodic, load-controlled contact of a rough surface",
                         description="Hard-wall contact of a rigid rough surface on a periodic "
                                     "elastic half-space, one TAO solve per nominal pressure.")
    _surface_arguments(per)
    _run_arguments(per)
    pun = sub.add_parser("punch", help="rigid rough square punch on a free half-space",
                         description="A rigid punch with a rough face pressed into a "
                                     "non-periodic elastic half-space (Hockney padding), "
                                     "displacement (--approaches) or load (--forces) "
                                     "controlled.")
    _surface_arguments(pun)
    _run_arguments(pun, punch=True)
    demo = sub.add_parser("demo", help="the default scene (periodic 512^2, H=0.7, slope 0.1)",
                          description="The default scene: periodic 512 x 512 self-affine "
                                      "surface, H = 0.7, rms slope 0.1, L/lambda_r = 2, "
                                      "L/lambda_1 = 64, loads from first contact to ~50% area.")
    _surface_arguments(demo)
    _run_arguments(demo, {**DEMO, "output": "demo.h5", "plot": "demo.png"})
    demo.set_defaults(**{k: v for k, v in DEMO.items() if k != "pressures"})
    return parser


def _generated(args: argparse.Namespace) -> bool:
    if args.heights is not None:
        given = [o for o in ("grid", "hurst", "rms_slope", "rms_height") if
                 getattr(args, o) is not None and args.command != "demo"]
        if given:
            raise InputError("--heights excludes the surface generation options "
                             f"(--{given[0].replace('_', '-')})")
        return False
    missing = [o for o in ("grid", "hurst") if getattr(args, o) is None]
    if missing:
        raise InputError("give --heights FILE, or --grid N --hurst H and --rms-slope or "
                         "--rms-height to generate a surface")
    if (args.rms_slope is None) == (args.rms_height is None):
        raise InputError("give exactly one of --rms-slope and --rms-height")
    return True


def _check_numbers(args: argparse.Namespace) -> None:
    for name in ("length", "modulus"):
        v = getattr(args, name)
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"--{name} must be positive and finite, got {v}")
    name = next(n for n in ("pressures", "approaches", "forces")
                if getattr(args, n, None) is not None)
    values = getattr(args, name)
    if not values:
        raise InputError(f"--{name} needs at least one value")
    for v in values:
        if not (np.isfinite(v) and (v > 0 or (name == "approaches" and v == 0))):
            raise InputError(f"--{name} must be positive and finite, got {v}")


def _attributes(args: argparse.Namespace, argv: Sequence[str], petsc: Any,
                realised: dict[str, float]) -> dict[str, Any]:
    from .output import file_digest, petsc_options, versions

    params = {k: v for k, v in vars(args).items() if k not in ("quiet",)}
    attrs: dict[str, Any] = {
        "geometry": "punch" if args.command == "punch" else "periodic", "command_line": " ".join(["petsc-contact", *argv]),
        "parameters": params, "petsc_options": petsc_options(petsc),
        "versions": versions(petsc), "mpi_size": petsc.COMM_WORLD.getSize(),
        "length": args.length, "modulus": args.modulus, "units": (
            "SI-free: lengths in the unit of --length and the heights, pressures and "
            "stiffness per area in the unit of --modulus"), **realised}
    if args.heights is not None:
        attrs["heights_file"] = os.path.abspath(args.heights)
        attrs["heights_sha256"] = file_digest(args.heights)
    else:
        attrs.update(seed=args.seed, hurst=args.hurst, rolloff_ratio=args.rolloff_ratio,
                     cutoff_ratio=args.cutoff_ratio, grid=args.grid)
    return attrs


PERIODIC_COLUMNS = (("p0", "nominal_pressure", "{:>11.4e}"), ("mean_gap", "mean_gap", "{:>12.6e}"))
PUNCH_COLUMNS = (("approach", "approach", "{:>11.4e}"), ("force", "force", "{:>12.6e}"),
                 ("K_tot", "total_stiffness", "{:>10.4e}"))


def _header(columns: tuple[tuple[str, str, str], ...]) -> str:
    widths = [len(fmt.format(0.0)) for _, _, fmt in columns]
    head = " ".join(f"{title:>{w}}" for (title, _, _), w in zip(columns, widths))
    return f"{'step':>4} {head} {'area':>9} {'its':>6} {'time_s':>8} {'kkt':>9}  tao_reason"


def _row(i: int, s: dict[str, Any], columns: tuple[tuple[str, str, str], ...]) -> str:
    flag = "" if s["converged"] else "   <-- NOT CONVERGED: " + s["verification"]
    values = " ".join(fmt.format(s[key]) for _, key, fmt in columns)
    return (f"{i:>4} {values} {s['area_fraction']:>9.5f} {s['iterations']:>6d} "
            f"{s['solve_time']:>8.3f} {s['kkt_residual']:>9.1e}  {s['tao_reason']}{flag}")


def _surface(args: argparse.Namespace, full: np.ndarray | None, grid: Any, fft: Any
             ) -> np.ndarray:
    """This rank's slab of the heights: read, or generated (paper Eq. 5)."""
    from .output import check_finite
    from .surface import self_affine

    if full is None:
        cutoff = args.cutoff_ratio if args.cutoff_ratio is not None else grid.n / 2
        args.cutoff_ratio = cutoff
        return self_affine(grid, fft, hurst=args.hurst, rolloff_ratio=args.rolloff_ratio,
                           cutoff_ratio=cutoff, seed=args.seed, rms_height=args.rms_height,
                           rms_slope=args.rms_slope, exact=args.exact_rms)
    heights = grid.scatter(full)
    check_finite(grid, heights)
    return heights


def _disk(n: int) -> np.ndarray:
    """The disk inscribed in an ``n x n`` footprint (pixel centres within radius n/2)."""
    x = np.arange(n) + 0.5 - n / 2
    return x[:, None] ** 2 + x[None, :] ** 2 < (n / 2) ** 2


def run(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    """Run ``periodic``, ``demo`` or ``punch``; write the HDF5 file (and plot)."""
    from . import _petsc
    from .output import StepWriter, check_writable, load_heights

    _check_numbers(args)
    generated = _generated(args)
    full = None if generated else load_heights(args.heights)
    check_writable(args.output)
    if args.plot:
        check_writable(args.plot)
    petsc = _petsc.init(petsc_args)
    from .fft import make_fft
    from .grid import Grid
    from .solve import check_tao_type
    from .surface import rms_of

    check_tao_type(petsc)
    n = args.grid if generated else int(full.shape[0])
    grid = Grid(n, args.length)
    fft = make_fft(grid)
    heights = _surface(args, full, grid, fft)
    realised = {"rms_height": rms_of(grid, fft, heights),
                "rms_slope": rms_of(grid, fft, heights, slope=True)}
    punch = args.command == "punch"
    root = grid.comm.rank == 0
    fields = ("gap", "pressure") if args.fields else ()
    if punch:
        steps, columns, intro, solver = _punch_steps(petsc, args, grid, heights, fields)
    else:
        steps, columns, intro, solver = _periodic_steps(petsc, args, grid, fft, heights, fields)
    writer = StepWriter(args.output, grid, _attributes(args, argv, petsc, realised),
                        heights, fields)
    table: list[dict[str, Any]] = []
    try:
        if root and not args.quiet:
            print(f"# {args.command} {n}x{n}, L = {args.length:g}, E* = {args.modulus:g}, "
                  f"h_rms = {realised['rms_height']:.4g}, h'_rms = {realised['rms_slope']:.4g}"
                  f"{intro}", flush=True)
            print(_header(columns), flush=True)
        for i, step in enumerate(steps):
            if punch and args.stiffness:
                step.scalars["stiffness"] = step.scalars["interfacial_stiffness"]
            writer.append(step.scalars, {"gap": step.gap, "pressure": step.pressure}
                          if fields else None)
            table.append(step.scalars)
            if root and not args.quiet:
                print(_row(i, step.scalars, columns), flush=True)
    except KeyboardInterrupt:
        writer.abandon()
        return EXIT_INTERRUPTED
    finally:
        if solver is not None:
            solver.close()
    writer.finish()
    if args.plot and root:
        from .plot import plot_punch, plot_sweep

        if punch:
            plot_punch(args.plot, table)
        else:
            plot_sweep(args.plot, table, args.modulus, realised["rms_height"])
    failed = [s for s in table if not s["converged"]]
    if failed and root:
        load = columns[0]
        print(f"petsc-contact: error: {len(failed)} of {len(table)} load steps did NOT converge "
              f"(first: {load[0]} = {failed[0][load[1]]:g}, {failed[0]['verification']}); "
              f"they are flagged converged = False in {args.output}", file=sys.stderr)
    if root and not args.quiet:
        print(f"# wrote {args.output}" + (f" and {args.plot}" if args.plot else ""))
    return EXIT_NOT_CONVERGED if failed else 0


def _periodic_steps(petsc: Any, args: argparse.Namespace, grid: Any, fft: Any,
                    heights: np.ndarray, fields: tuple[str, ...]) -> tuple[Any, ...]:
    from .periodic import sweep
    from .problem import PeriodicProblem

    problem = PeriodicProblem(grid, fft, heights, args.modulus)
    p_full = problem.full_contact_pressure()  # collective: every rank computes it
    steps = sweep(petsc, problem, args.pressures, bool(fields), stiffness=args.stiffness)
    return steps, PERIODIC_COLUMNS, f", full contact at p0 = {p_full:.4g}", None


def _punch_steps(petsc: Any, args: argparse.Namespace, grid: Any, heights: np.ndarray,
                 fields: tuple[str, ...]) -> tuple[Any, ...]:
    from .punch import PHARR_BETA, PunchProblem, PunchSolver

    mask = grid.scatter(_disk(grid.n)) > 0 if args.footprint == "disk" else None
    problem = PunchProblem(grid, heights, args.modulus, mask)
    solver = PunchSolver(petsc, problem, args.flat_stiffness,
                         1.0 if args.footprint == "disk" else PHARR_BETA)

    def steps() -> Any:
        if args.approaches is not None:
            for d in args.approaches:
                yield solver.at_approach(d, bool(fields))
        else:
            for f in args.forces:
                yield solver.at_force(f, bool(fields))

    intro = (f", K_flat = {solver.k_flat:.6g} ({args.flat_stiffness}; analytic "
             f"{solver.k_flat_analytic:.6g})")
    return steps(), PUNCH_COLUMNS + (("p0", "nominal_pressure", "{:>10.3e}"),), intro, solver


def _interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    ours, petsc_args = split_arguments(argv)
    args = build_parser().parse_args(ours)
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        return run(args, argv, petsc_args)
    except (InputError, ValueError, OSError) as exc:
        _error(str(exc))
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED
    except Exception as exc:  # noqa: BLE001 - PETSc errors become one line, not a traceback
        if type(exc).__name__ == "Error" and "petsc4py" in type(exc).__module__:
            _error(f"PETSc error: {exc}")
            return EXIT_BAD_INPUT
        raise


def _error(message: str) -> None:
    from mpi4py import MPI

    if MPI.COMM_WORLD.rank == 0:
        print(f"petsc-contact: error: {message}", file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())
