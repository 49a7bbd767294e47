"""The scene of a run: the surface (generated, or a measured map read, filled, detrended and
put in one length unit), its grid and its FFT."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from .common import InputError, check_numbers, say

FILE_ONLY = {
    "height_unit": None,
    "detrend": "none",
    "fill_undefined": "error",
    "channel": None,
    "override_metadata": False,
}


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
    extra = [o for o, default in FILE_ONLY.items() if getattr(args, o, default) != default]
    if extra:
        raise InputError(f"--{extra[0].replace('_', '-')} applies to a --heights file")
    missing = [o for o in ("grid", "hurst") if getattr(args, o) is None]
    if missing:
        raise InputError(
            "give --heights FILE, or --grid N --hurst H and --rms-slope or "
            "--rms-height to generate a surface"
        )
    if (args.rms_slope is None) == (args.rms_height is None):
        raise InputError("give exactly one of --rms-slope and --rms-height")
    return True


def _units(args: argparse.Namespace, topo: Any, lengths: Any) -> tuple[Any, float, list[str]]:
    """The run's lengths (with their unit), the factor that puts the file's heights in it, and
    which of the file's metadata ``--override-metadata`` replaced.

    Without ``--override-metadata`` contradictions are input errors: a height unit other than
    the file's, sides other than the file's.  Heights with a unit need lengths with one."""
    from ..conventions.grid import sides
    from ..conventions.units import Lengths, factor, unit_name

    override = args.override_metadata
    if override and args.height_unit is None and lengths is None:
        raise InputError(
            "--override-metadata replaces the file's data with --length or --height-unit"
        )
    overridden = []
    given = unit_name(args.height_unit) if args.height_unit else None
    if given and topo.unit and given != topo.unit:
        if not override:
            raise InputError(
                f"--height-unit {given} contradicts the file's unit {topo.unit} (add "
                "--override-metadata to replace it)"
            )
        overridden.append("height_unit")
    heights_unit = given or topo.unit
    if lengths is None:
        lengths = Lengths(topo.lengths, topo.unit) if topo.lengths else Lengths((1.0,), None)
    elif topo.lengths and topo.unit and lengths.unit:
        mine = np.array(sides(topo.heights.shape, lengths.values)) * factor(lengths.unit, topo.unit)
        if not np.allclose(mine, topo.lengths, rtol=1e-6):
            theirs = Lengths(topo.lengths, topo.unit).describe()
            if not override:
                raise InputError(
                    f"--length {lengths.describe()} contradicts the file's {theirs} (add "
                    "--override-metadata to replace it)"
                )
            overridden.append("length")
    if heights_unit and not lengths.unit:
        raise InputError(f"heights in {heights_unit} need lengths with a unit, e.g. --length 100um")
    return lengths, factor(heights_unit, lengths.unit), overridden


def measured(args: argparse.Namespace, given: Any) -> tuple[np.ndarray, Any, dict[str, Any]]:
    """The prepared map of ``--heights`` (filled, detrended, in the lengths' unit), the
    lengths, and what the run records of the file (its reader, channel and metadata, and what
    was overridden); warns about implausible slopes and, for periodic runs, edge mismatch."""
    from ..conventions.grid import grid_for
    from ..io.topography import read_topography
    from ..physics.preparation import detrend, fill_undefined

    topo = read_topography(args.heights, args.channel)
    lengths, scale, overridden = _units(args, topo, given)
    spacing = grid_for(topo.heights.shape, lengths.pair).spacing
    full = fill_undefined(topo.heights, args.fill_undefined)
    full = detrend(full, spacing, args.detrend)
    if scale != 1.0:
        full = np.asarray(full, dtype=float) * scale
    check_height_scale(full, lengths.pair)
    record = {
        "heights_reader": topo.reader,
        "heights_channel": topo.channel,
        "heights_channel_index": topo.channel_index,
        "file_lengths": list(topo.lengths) if topo.lengths else [],
        "file_unit": topo.unit or "",
        "metadata_overridden": overridden,
    }
    if not getattr(args, "quiet", False) and grid_comm_rank() == 0:
        print(f"# {args.heights}: {topo.describe()}", flush=True)
    _warn(args, full, spacing)
    return full, lengths, record


SLOPE_LIMIT = 1e6  # heights this many times the cell's side are no contact surface


def check_height_scale(heights: np.ndarray, length: Any) -> None:
    """``InputError`` for heights so large against the sides that no contact computation
    means anything (and its squares overflow): a unit mistaken by many orders."""
    top = float(np.max(np.abs(heights)))
    side = max(np.atleast_1d(np.asarray(length, dtype=float)))
    if not top <= SLOPE_LIMIT * side:
        raise InputError(
            f"heights up to {top:.3g} on sides of {side:.3g}: more than {SLOPE_LIMIT:g} times "
            "the cell, no elastic contact; are the units right (--height-unit, --length)?"
        )


def grid_comm_rank() -> int:
    from mpi4py import MPI

    return int(MPI.COMM_WORLD.rank)


def _warn(args: argparse.Namespace, full: np.ndarray, spacing: tuple[float, float]) -> None:
    from mpi4py import MPI

    from ..physics.preparation import EDGE_MISMATCH_LIMIT, SLOPE_RANGE, edge_mismatch, rms_slope

    if MPI.COMM_WORLD.rank != 0:  # only rank 0 speaks: the others skip the passes over the map
        return
    slope = rms_slope(full, spacing)
    if slope > 0 and not SLOPE_RANGE[0] <= slope <= SLOPE_RANGE[1]:
        say(
            f"the map's rms slope is {slope:.3g}, outside {SLOPE_RANGE[0]:g}..{SLOPE_RANGE[1]:g}:"
            " are the units right (--length, --height-unit)?",
            "warning",
        )
    mismatch = edge_mismatch(full)
    if args.command != "punch" and mismatch > EDGE_MISMATCH_LIMIT:
        say(
            f"the map's opposite edges differ by {mismatch:.3g} times its typical neighbour "
            "step, so treated as periodic it has a step at its edges; consider --detrend "
            "slope, or the free-boundary geometry (petsc-contact punch)",
            "warning",
        )


def _scene(
    args: argparse.Namespace, full: np.ndarray | None, lengths: Any
) -> tuple[Any, Any, np.ndarray, dict[str, Any]]:
    """The grid, its FFT, this rank's slab of the heights (read, or generated) and the
    parameters the options left to their defaults (lengths, ``cutoff_ratio``)."""
    from ..conventions.fft import make_fft
    from ..conventions.grid import grid_for
    from ..io.output import check_finite
    from ..physics.surface import nyquist_ratio

    shape = full.shape if full is not None else _shape(args.grid)
    grid = grid_for(shape, lengths.pair)
    fft = make_fft(grid)
    resolved: dict[str, Any] = {"length": list(grid.lengths), "length_unit": lengths.unit or ""}
    if full is None:
        cutoff = args.cutoff_ratio if args.cutoff_ratio is not None else nyquist_ratio(grid)
        resolved["cutoff_ratio"] = cutoff
        heights = _generate(args, grid, fft, cutoff)
        top = grid.max(float(np.max(np.abs(heights))))
        check_height_scale(np.array([top]), grid.lengths)
        return grid, fft, heights, resolved
    heights = grid.scatter(full)
    check_finite(grid, heights)
    return grid, fft, heights, resolved


def _shape(grid: int | tuple[int, int]) -> tuple[int, int]:
    return grid if isinstance(grid, tuple) else (grid, grid)


def _generate(args: argparse.Namespace, grid: Any, fft: Any, cutoff: float) -> np.ndarray:
    """This rank's slab of a generated surface (paper Eq. 5)."""
    from ..physics.surface import self_affine

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


def prepare_scene(
    args: argparse.Namespace, petsc_args: list[str], check_type: bool = True
) -> tuple[Any, Any, Any, np.ndarray, dict[str, Any]]:
    """Check the input, then PETSc, the grid, its FFT and this rank's heights."""
    from ..backend import _petsc
    from ..backend.solve import check_tao_type
    from ..conventions.units import Lengths, parse_lengths
    from ..io.store import check_writable

    check_numbers(args)
    try:
        given = parse_lengths(args.length) if args.length is not None else None
    except ValueError as exc:
        raise InputError(f"--length: {exc}") from None
    record: dict[str, Any] = {}
    if _generated(args):
        full, lengths = None, given or Lengths((1.0,), None)
    else:
        full, lengths, record = measured(args, given)
    check_writable(args.output)
    if getattr(args, "plot", None):
        check_writable(args.plot)
    shape = full.shape if full is not None else _shape(args.grid)
    if not args.skip_memory_check:
        from ..conventions.resources import check_memory

        tao_type = dict(zip(petsc_args, petsc_args[1:], strict=False)).get("-tao_type", "python")
        default = tao_type == "python" and args.command != "compare"
        check_memory(shape[0] * shape[1], args.command, default, getattr(args, "fields", False))
    petsc = _petsc.init(petsc_args)
    if check_type:
        check_tao_type(petsc)
    grid, fft, heights, resolved = _scene(args, full, lengths)
    return petsc, grid, fft, heights, resolved | record
