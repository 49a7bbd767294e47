"""What every command shares: exit codes, input errors, the scene and the run record."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..validation import non_negative, positive

EXIT_NOT_CONVERGED = 1
EXIT_BAD_INPUT = 2
EXIT_PAUSED = 75  # --stop-after reached: the run continues with --resume
EXIT_INTERRUPTED = 130


class InputError(Exception):
    """Bad user input: reported as one line, exit status 2."""


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
        positive(f"--{option}", getattr(args, option))
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
    check = non_negative if name == "approaches" else positive  # an approach may be 0
    for v in values:
        check(f"--{name}", v)


def swept(spec: list[float], low: float, high: float) -> list[float]:
    """The loads of ``--sweep N[,MIN,MAX]``: ``N`` log-spaced, by default from ``low`` to
    ``high``."""
    n, lo, hi = spec if len(spec) == 3 else (spec[0], low, high)
    return [float(v) for v in np.geomspace(lo, hi, int(n))]


def run_record(
    args: argparse.Namespace,
    argv: Sequence[str],
    petsc: Any,
    realised: dict[str, float],
    resolved: dict[str, Any],
) -> dict[str, Any]:
    """What reproduces the run: every option (defaults resolved), versions, PETSc options."""
    from ..output import file_digest, petsc_options, versions

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


def _scene(
    args: argparse.Namespace, full: np.ndarray | None
) -> tuple[Any, Any, np.ndarray, dict[str, Any]]:
    """The grid, its FFT, this rank's slab of the heights (read, or generated) and the
    parameters the options left to their defaults (``cutoff_ratio``)."""
    from ..fft import make_fft
    from ..grid import Grid

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
    from ..output import check_finite
    from ..surface import self_affine

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


def prepare_scene(
    args: argparse.Namespace, petsc_args: list[str], check_type: bool = True
) -> tuple[Any, Any, Any, np.ndarray, dict[str, Any]]:
    """Check the input, then PETSc, the grid, its FFT and this rank's heights."""
    from .. import _petsc
    from ..output import check_writable, load_heights
    from ..solve import check_tao_type

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


def say(message: str, kind: str = "error") -> None:
    from mpi4py import MPI

    if MPI.COMM_WORLD.rank == 0:
        print(f"petsc-contact: {kind}: {message}", file=sys.stderr)
