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


def _run_arguments(p: argparse.ArgumentParser, defaults: dict[str, Any] | None = None) -> None:
    d = defaults or {}
    p.add_argument("--length", type=float, default=d.get("length", 1.0), metavar="L",
                   help="side of the periodic cell (default %(default)s)")
    p.add_argument("--modulus", type=float, default=d.get("modulus", 1.0), metavar="ESTAR",
                   help="contact modulus E* (default %(default)s)")
    p.add_argument("--pressures", type=_float_list, required="pressures" not in d,
                   default=_float_list(d["pressures"]) if "pressures" in d else None,
                   metavar="P1,P2,...", help="nominal pressures p0 (units of E*), in order")
    p.add_argument("--output", required="output" not in d, default=d.get("output"),
                   metavar="OUT.h5", help="HDF5 results (written atomically)")
    p.add_argument("--fields", action="store_true",
                   help="store the gap and pressure fields of every step")
    p.add_argument("--plot", metavar="PNG", default=d.get("plot"),
                   help="write a PNG of area and mean gap against pressure")
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
                 getattr(args, o) is not None and args.command == "periodic"]
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
    for p in args.pressures:
        if not (np.isfinite(p) and p > 0):
            raise InputError(f"--pressures must be positive and finite, got {p}")


def _attributes(args: argparse.Namespace, argv: Sequence[str], petsc: Any,
                realised: dict[str, float]) -> dict[str, Any]:
    from .output import file_digest, petsc_options, versions

    params = {k: v for k, v in vars(args).items() if k not in ("quiet",)}
    attrs: dict[str, Any] = {
        "geometry": "periodic", "command_line": " ".join(["petsc-contact", *argv]),
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


HEADER = ("{:>4} {:>11} {:>12} {:>9} {:>6} {:>8} {:>9}  {}".format(
    "step", "p0", "mean_gap", "area", "its", "time_s", "kkt", "tao_reason"))


def _row(i: int, s: dict[str, Any]) -> str:
    flag = "" if s["converged"] else "   <-- NOT CONVERGED: " + s["verification"]
    return (f"{i:>4} {s['nominal_pressure']:>11.4e} {s['mean_gap']:>12.6e} "
            f"{s['area_fraction']:>9.5f} {s['iterations']:>6d} {s['solve_time']:>8.3f} "
            f"{s['kkt_residual']:>9.1e}  {s['tao_reason']}{flag}")


def run_periodic(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    from . import _petsc
    from .output import StepWriter, check_finite, check_writable, load_heights

    _check_numbers(args)
    generated = _generated(args)
    full = None if generated else load_heights(args.heights)
    check_writable(args.output)
    if args.plot:
        check_writable(args.plot)
    petsc = _petsc.init(petsc_args)
    from .fft import make_fft
    from .grid import Grid
    from .periodic import sweep
    from .problem import PeriodicProblem
    from .solve import check_tao_type
    from .surface import rms_of, self_affine

    check_tao_type(petsc)
    n = args.grid if generated else int(full.shape[0])
    grid = Grid(n, args.length)
    fft = make_fft(grid)
    if generated:
        cutoff = args.cutoff_ratio if args.cutoff_ratio is not None else n / 2
        heights = self_affine(grid, fft, hurst=args.hurst, rolloff_ratio=args.rolloff_ratio,
                              cutoff_ratio=cutoff, seed=args.seed, rms_height=args.rms_height,
                              rms_slope=args.rms_slope, exact=args.exact_rms)
        args.cutoff_ratio = cutoff
    else:
        heights = grid.scatter(full)
        check_finite(grid, heights)
    realised = {"rms_height": rms_of(grid, fft, heights),
                "rms_slope": rms_of(grid, fft, heights, slope=True)}
    problem = PeriodicProblem(grid, fft, heights, args.modulus)
    root = grid.comm.rank == 0
    fields = ("gap", "pressure") if args.fields else ()
    writer = StepWriter(args.output, grid, _attributes(args, argv, petsc, realised),
                        heights, fields)
    table: list[dict[str, Any]] = []
    p_full = problem.full_contact_pressure()  # collective: every rank computes it
    try:
        if root and not args.quiet:
            print(f"# periodic {n}x{n}, L = {args.length:g}, E* = {args.modulus:g}, "
                  f"h_rms = {realised['rms_height']:.4g}, h'_rms = {realised['rms_slope']:.4g}, "
                  f"full contact at p0 = {p_full:.4g}", flush=True)
            print(HEADER, flush=True)
        for i, step in enumerate(sweep(petsc, problem, args.pressures, bool(fields))):
            writer.append(step.scalars, {"gap": step.gap, "pressure": step.pressure}
                          if fields else None)
            table.append(step.scalars)
            if root and not args.quiet:
                print(_row(i, step.scalars), flush=True)
    except KeyboardInterrupt:
        writer.abandon()
        return EXIT_INTERRUPTED
    writer.finish()
    if args.plot and root:
        from .plot import plot_sweep

        plot_sweep(args.plot, table, args.modulus, realised["rms_height"])
    failed = [s for s in table if not s["converged"]]
    if failed and root:
        print(f"petsc-contact: error: {len(failed)} of {len(table)} load steps did NOT converge "
              f"(first: p0 = {failed[0]['nominal_pressure']:g}, {failed[0]['verification']}); "
              f"they are flagged converged = False in {args.output}", file=sys.stderr)
    if root and not args.quiet:
        print(f"# wrote {args.output}" + (f" and {args.plot}" if args.plot else ""))
    return EXIT_NOT_CONVERGED if failed else 0


def _interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    ours, petsc_args = split_arguments(argv)
    args = build_parser().parse_args(ours)
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        return run_periodic(args, argv, petsc_args)
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
