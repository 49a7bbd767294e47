"""The scene of a run: its surface (generated, or a measured map read, filled, detrended and
put in one length unit), its grid, its FFT and this rank's slab of the heights.

:func:`prepare_scene` checks a :class:`~petsc_contact.workflows.description.Run`'s surface
and sizes before anything large is allocated (the memory estimate, the height scale), and
says what it read.  Doubtful maps warn with
:class:`~petsc_contact.conventions.warnings.DoubtfulMap` (many heights filled, an implausible
rms slope, opposite edges that do not match in a periodic run: :func:`check_map`); the run
keeps their texts and the command line prints them.

No rank holds the whole grid but the one that reads a measured map: the first rank of the
run's communicator reads it (an instrument's file is read whole by its reader), prepares it
and sends every other rank its rows (:meth:`~petsc_contact.conventions.grid.Grid.slab_from`);
a face cut from a larger surface moves from the parent's slabs to the face's in the same way.
The scene's warnings are given by that first rank.
"""

from __future__ import annotations

import pickle
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..conventions.grid import Grid, block_rows, grid_for, world
from ..conventions.units import Lengths, factor, parse_lengths, unit_name
from ..conventions.validation import check_finite
from ..conventions.warnings import DoubtfulMap, option, user_level
from ..devices.device import get_device
from ..devices.fft import make_fft
from ..io.topography import Topography, as_topography, check_guessed_sides
from .description import Run

SLOPE_LIMIT = 1e6  # heights this many times the cell's side are no contact surface
FILLED_WARNING = 0.05  # a filled share above this warns: contact may sit on filled points
FILE_ONLY = ("height_unit", "detrend", "fill_undefined", "channel", "override_metadata")
GENERATION = ("grid", "hurst", "rms_slope", "rms_height")
MapWarning = DoubtfulMap  # its name before the package's warnings had one vocabulary


@dataclass
class Scene:
    """A run's grid, FFT and heights (this rank's slab), and what it records of them."""

    grid: Grid
    fft: Any
    heights: np.ndarray
    resolved: dict[str, Any]  # what defaults became: lengths, unit, cutoff ratio
    record: dict[str, Any] = field(default_factory=dict)  # what was read, and how
    reading: str = ""  # one line on the map read ("" for a generated surface)
    filled: np.ndarray | None = None  # this rank's pixels whose heights were filled
    realised: dict[str, float] = field(default_factory=dict)  # a cut face: its parent, its inside


def check_surface(run: Run) -> None:
    """``ValueError`` for a surface that is neither generated nor given, or both."""
    defaults = Run()
    if run.cut_from != 1 and (run.measured or run.geometry != "punch"):
        raise ValueError("--cut-from makes a punch face from a generated surface")
    if run.measured:
        given = [o for o in GENERATION if getattr(run, o) is not None]
        if given:
            raise ValueError(
                "--heights excludes the surface generation options "
                f"(--{given[0].replace('_', '-')})"
            )
        return
    extra = [o for o in FILE_ONLY if getattr(run, o) != getattr(defaults, o)]
    if extra:
        raise ValueError(f"--{extra[0].replace('_', '-')} applies to a --heights file")
    if run.grid is None or run.hurst is None:
        raise ValueError(
            "give --heights FILE, or --grid N --hurst H and --rms-slope or "
            "--rms-height to generate a surface"
        )
    if (run.rms_slope is None) == (run.rms_height is None):
        raise ValueError("give exactly one of --rms-slope and --rms-height")


def given_lengths(run: Run) -> Lengths | None:
    """The sides ``run.length`` gives (text with a unit, a number or a pair), if any."""
    if run.length is None:
        return None
    if isinstance(run.length, str):
        try:
            return parse_lengths(run.length)
        except ValueError as exc:
            raise ValueError(f"--length: {exc}") from None
    values = tuple(float(v) for v in np.atleast_1d(run.length))
    return Lengths(values, None)


def shape_of(run: Run) -> tuple[int, int]:
    """The generated surface's ``(nx, ny)``."""
    grid = run.grid
    return (int(grid[0]), int(grid[1])) if isinstance(grid, (tuple, list)) else (grid, grid)  # type: ignore[return-value]


def prepare_scene(run: Run, comm: Any = None, default_solver: bool = True) -> Scene:
    """The checked scene of ``run``: its map read and prepared (or its surface generated),
    the memory it will need checked, its grid and FFT made (collective; the FFT of the run's
    device, :class:`~petsc_contact.devices.device.DeviceUnavailable` where it cannot be used).

    ``comm`` is the run's communicator (:func:`~petsc_contact.conventions.grid.world` when
    not given).  A measured map is read, prepared and checked on its first rank only, which
    holds it once (an instrument's file is read whole by its reader) and sends every other
    rank its rows and its rows of the ``filled`` mask; no other rank holds the whole map.
    Its shape, lengths, record and reading line are broadcast, and a failure to read it is
    raised on every rank.  ``default_solver`` says whether the run uses the package's solver
    (the memory estimate is larger for TAO's own types)."""
    check_surface(run)
    comm = world() if comm is None else comm
    given = given_lengths(run)
    if run.measured:
        return measured_scene(run, given, comm, default_solver)
    grid, fft, resolved = sized(
        run, shape_of(run), given or Lengths((1.0,), None), comm, default_solver
    )
    from ..physics.surface import nyquist_ratio

    cutoff = run.cutoff_ratio if run.cutoff_ratio is not None else nyquist_ratio(grid)
    resolved["cutoff_ratio"] = cutoff
    parent: dict[str, float] = {}
    if run.cut_from == 1:
        heights = generated(run, grid, fft, 1, cutoff)
    else:
        heights, parent = cut_face(run, grid, cutoff)
    check_height_scale(np.array([grid.max(float(np.max(np.abs(heights))))]), grid.lengths)
    return Scene(grid, fft, heights, resolved, realised=parent)


def sized(
    run: Run, shape: tuple[int, int], lengths: Lengths, comm: Any, default_solver: bool
) -> tuple[Grid, Any, dict[str, Any]]:
    """The memory ``run`` needs on a grid of ``shape`` checked, then that grid, its FFT
    (collective) and the lengths the run resolved."""
    if not run.skip_memory_check:
        from ..conventions.resources import check_memory

        check_memory(shape[0] * shape[1], run.geometry, default_solver, run.fields)
    grid = grid_for(shape, lengths.pair, comm)
    fft = make_fft(grid, get_device(run.device))  # the device's: the surface transformed there
    return grid, fft, {"length": list(grid.lengths), "length_unit": lengths.unit or ""}


def measured_scene(run: Run, given: Lengths | None, comm: Any, default_solver: bool) -> Scene:
    """:func:`prepare_scene` of a measured map: read and prepared on the first rank of
    ``comm`` (:func:`measured`), every rank's slab and filled pixels sent to it from there."""
    full = mask = failure = None
    said: Any = None
    if comm.rank == 0:
        try:
            full, lengths, record, reading = measured(run, given, comm)
            mask = record.pop("filled")
            said = (full.shape, lengths, record, reading)
        except Exception as exc:
            said, failure = portable(exc), exc
    said = comm.bcast(said, root=0) if comm.size > 1 else said
    if isinstance(said, Exception):
        raise failure or said
    shape, lengths, record, reading = said
    grid, fft, resolved = sized(run, shape, lengths, comm, default_solver)
    held = [slice(0, shape[0]) if q == 0 else slice(0, 0) for q in range(comm.size)]
    local = grid.slab_from(_held(full, shape, float), held)
    check_finite(grid, local)
    filled = None
    if record["filled_fraction"] > 0:
        filled = grid.slab_from(_held(mask, shape, bool), held)
    return Scene(grid, fft, local, resolved, record, reading, filled)


def _held(full: np.ndarray | None, shape: tuple[int, int], dtype: type) -> np.ndarray:
    """The rows of a whole map this rank holds: all of them where it was read, none elsewhere."""
    return np.empty((0, shape[1]), dtype) if full is None else np.asarray(full, dtype=dtype)


def portable(exc: Exception) -> Exception:
    """``exc`` where other ranks can raise it (pickled through MPI), else a ``RuntimeError``
    naming it."""
    try:
        pickle.loads(pickle.dumps(exc))
    except Exception:
        return RuntimeError(f"{type(exc).__name__}: {exc}")
    return exc


def generated(run: Run, grid: Grid, fft: Any, scale: int, cutoff: float) -> np.ndarray:
    """This rank's slab of the run's surface (paper Eq. 5) on ``grid``, whose sides are
    ``scale`` times the run's: ``L/lambda_r`` and ``L/lambda_1`` scaled with them, so that
    ``lambda_r`` and ``lambda_1`` are the run's."""
    from ..physics.surface import self_affine

    return self_affine(
        grid,
        fft,
        hurst=run.hurst,  # type: ignore[arg-type]
        rolloff_ratio=scale * run.rolloff_ratio,
        cutoff_ratio=scale * cutoff,
        seed=run.seed,
        rms_height=run.rms_height,
        rms_slope=run.rms_slope,
        exact=run.exact_rms,
    )


def cut_face(run: Run, grid: Grid, cutoff: float) -> tuple[np.ndarray, dict[str, float]]:
    """A punch face cut from a larger surface (``run.cut_from``, :class:`Run`): the central
    ``nx x ny`` patch of the periodic surface of ``M`` times the sides with the same pixel
    size, spectrum, rms target and seed (its own ``L/lambda_r = M L_p/lambda_r``), this rank's
    slab; with that parent surface's realised ``rms_height`` and ``rms_slope`` (spectral: the
    cut face's own are its edges' too) and the face's ``rms_slope_inside`` (finite differences
    inside it, :func:`rms_slope_inside`).  The patch's rows move from the parent's slabs to the
    face's (:meth:`~petsc_contact.conventions.grid.Grid.slab_from`): no rank holds more than
    its slab of the parent and of the face."""
    from ..physics.surface import rms_of

    m = run.cut_from
    parent = grid_for(
        (m * grid.shape[0], m * grid.shape[1]),
        (m * grid.lengths[0], m * grid.lengths[1]),
        grid.comm,
    )
    parent_fft = make_fft(parent, get_device(run.device))  # the run's, as its own surface's
    heights = generated(run, parent, parent_fft, m, cutoff)
    stats = {
        "parent_rms_height": rms_of(parent, parent_fft, heights),
        "parent_rms_slope": rms_of(parent, parent_fft, heights, slope=True),
    }
    (i, j), (nx, ny) = ((m - 1) * n // 2 for n in grid.shape), grid.shape
    held = []  # the patch's rows (its own numbering) in each rank's slab of the parent
    for q in range(grid.comm.size):
        rows = block_rows(parent.shape[0], grid.comm.size, q)
        start = min(max(rows.start, i), i + nx)
        held.append(slice(start - i, max(start, min(rows.stop, i + nx)) - i))
    mine, first = held[grid.comm.rank], parent.rows.start - i
    face = grid.slab_from(heights[mine.start - first : mine.stop - first, j : j + ny], held)
    stats["rms_slope_inside"] = rms_slope_inside(grid, face)
    return face, stats


def rms_slope_inside(grid: Grid, local: np.ndarray) -> float:
    """:func:`~petsc_contact.physics.preparation.rms_slope` of the field whose slab is
    ``local``, from the slabs: each rank's differences and those down to the next rank's
    first row (sent up to it), summed over the ranks; the serial value to rounding, and
    exactly on one rank."""
    from ..physics.preparation import slope_rms, slope_squares

    below = None
    if grid.comm.size > 1:
        from mpi4py import MPI

        rows, rank = grid.rows, grid.comm.rank
        up = rank - 1 if rank > 0 and rows.stop > rows.start else MPI.PROC_NULL
        down = rank + 1 if rows.stop < grid.shape[0] else MPI.PROC_NULL
        below = grid.comm.sendrecv(local[0] if len(local) else None, dest=up, source=down)
    along_x, along_y = grid.sum(*slope_squares(local, grid.spacing, below))
    return slope_rms(float(along_x), float(along_y), grid.shape)


def measured(
    run: Run, given: Lengths | None, comm: Any
) -> tuple[np.ndarray, Lengths, dict[str, Any], str]:
    """The prepared map (filled, detrended, in the lengths' unit), its lengths, what the run
    records of it (its reader, channel and metadata, what was overridden, the ``filled``
    mask), and one line on what was read; warns about implausible slopes and, for periodic
    runs, edge mismatch.  Called on the first rank of the run's ``comm`` only, which reads the
    whole map (:func:`measured_scene`)."""
    from ..physics.preparation import detrend, fill_undefined

    topo = as_topography(run.heights, run.channel)
    lengths, scale, overridden = _units(run, topo, given)
    grid = grid_for(topo.heights.shape, lengths.pair, comm)
    filled = ~np.isfinite(topo.heights)
    share = float(np.mean(filled))
    full = fill_undefined(topo.heights, run.fill_undefined)
    if share > FILLED_WARNING:
        warnings.warn(
            f"{share:.1%} of the map's heights were undefined and are filled "
            f"({run.fill_undefined}): the contact may sit on filled points; the output's "
            "'filled' map and filled_contact_fraction say where and how much",
            DoubtfulMap,
            stacklevel=user_level(),
        )
    full = detrend(full, grid.spacing, run.detrend)
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
        "filled_fraction": share,
        "filled": filled,  # the mask itself: the scene keeps it, the record does not
    }
    record["rms_slope_inside"] = check_map(full, grid, run.geometry == "periodic", run.detrend)
    name = run.heights if isinstance(run.heights, str) else record["heights_reader"]
    how = f", filled ({run.fill_undefined})" if share > 0 else ""
    return full, lengths, record, f"{name}: {topo.describe()}{how}"


def _units(run: Run, topo: Topography, lengths: Lengths | None) -> tuple[Lengths, float, list[str]]:
    """The run's lengths (with their unit), the factor that puts the map's heights in it, and
    which of the file's metadata ``override_metadata`` replaced.

    Without ``override_metadata`` contradictions are errors: a height unit other than the
    file's, sides other than the file's.  Heights with a unit need lengths with one."""
    from ..conventions.grid import sides

    override = run.override_metadata
    if override and run.height_unit is None and lengths is None:
        raise ValueError(
            "--override-metadata needs --length or --height-unit to replace the file's"
        )
    overridden = []
    given = unit_name(run.height_unit) if run.height_unit else None
    if given and topo.unit and given != topo.unit:
        if not override:
            raise ValueError(
                f"--height-unit {given} contradicts the file's unit {topo.unit} (add "
                "--override-metadata to replace it)"
            )
        overridden.append("height_unit")
    heights_unit = given or topo.unit
    if lengths is not None:
        check_guessed_sides(topo, lengths.values)
    if lengths is None:
        lengths = Lengths(topo.lengths, topo.unit) if topo.lengths else Lengths((1.0,), None)
    elif topo.lengths:
        mine = np.array(sides(topo.heights.shape, lengths.values)) * factor(lengths.unit, topo.unit)
        comparable = (topo.unit is None) == (lengths.unit is None)
        if comparable and not np.allclose(mine, topo.lengths, rtol=1e-6):
            theirs = Lengths(topo.lengths, topo.unit).describe()
            if not override:
                raise ValueError(
                    f"--length {lengths.describe()} contradicts the file's {theirs} (add "
                    "--override-metadata to replace it)"
                )
            overridden.append("length")
    if heights_unit and not lengths.unit:
        raise ValueError(f"heights in {heights_unit} need lengths with a unit, e.g. --length 100um")
    return lengths, factor(heights_unit, lengths.unit), overridden


def check_height_scale(heights: np.ndarray, length: Any) -> None:
    """``ValueError`` for heights so large against the sides that no contact computation
    means anything (and its squares overflow): a unit mistaken by many orders."""
    top = float(np.max(np.abs(heights)))
    side = max(np.atleast_1d(np.asarray(length, dtype=float)))
    if not top <= SLOPE_LIMIT * side:
        raise ValueError(
            f"heights up to {top:.3g} on sides of {side:.3g}: more than {SLOPE_LIMIT:g} times "
            "the cell, no elastic contact; are the units right (--height-unit, --length)?"
        )


def check_map(full: np.ndarray, grid: Grid, periodic: bool, detrended: str = "none") -> float:
    """Warn (:class:`~petsc_contact.conventions.warnings.DoubtfulMap`) about an implausible
    rms slope and, for a ``periodic`` contact, opposite edges that do not match; the rms slope
    from finite differences inside the map (on the first rank of the run's communicator, the
    grid's; NaN on the others, which skip the passes and say nothing).

    Parameters
    ----------
    full
        The whole map (as prepared: filled, detrended, in the lengths' unit), on the host
        or on the device (where it lives: nothing but sums crosses).
    grid
        The map's grid: its pixel's sides, and the run's communicator.
    periodic
        Whether the contact takes the map as periodic (the edges then matter).
    detrended
        What was removed from the map (``none``, ``center``, ``slope``, ``curvature``): the
        remedy named for mismatched edges.
    """
    from ..physics.preparation import (
        EDGE_MISMATCH_LIMIT,
        SLOPE_RANGE,
        edge_mismatch,
        rms_slope,
        step_squares,
    )

    if grid.comm.rank != 0:  # only the run's first rank speaks: the others skip the passes
        return float("nan")
    steps = step_squares(full)  # once, for both checks
    slope = rms_slope(full, grid.spacing, steps)
    if slope > 0 and not SLOPE_RANGE[0] <= slope <= SLOPE_RANGE[1]:
        warnings.warn(
            f"the map's rms slope (finite differences inside the map) is {slope:.3g}, outside "
            f"{SLOPE_RANGE[0]:g}..{SLOPE_RANGE[1]:g}: are the units right ({option('length')}, "
            f"{option('height_unit')})?",
            DoubtfulMap,
            stacklevel=user_level(),
        )
    mismatch = edge_mismatch(full, steps)
    if periodic and mismatch > EDGE_MISMATCH_LIMIT:
        done = detrended in ("slope", "curvature")
        remedy = (
            f"the free-boundary geometry ({option('geometry', 'punch')}) needs no periodicity"
            if done
            else f"consider {option('detrend', 'slope')}, or the free-boundary geometry "
            f"({option('geometry', 'punch')}), which needs no periodicity"
        )
        warnings.warn(
            f"the map's opposite edges differ by {mismatch:.3g} times its typical neighbour "
            f"step{' after ' + option('detrend', detrended) if done else ''}, so treated as "
            f"periodic it has a step at its edges; {remedy}",
            DoubtfulMap,
            stacklevel=user_level(),
        )
    return slope
