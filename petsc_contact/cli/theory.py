"""``theory``: Persson's predictions and the finite-size ``p_c`` from a map's spectrum."""

from __future__ import annotations

import argparse
import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..conventions.units import pressure_value
from ..io.results import trusted
from ..workflows.predictions import Prediction, predict, predict_profile
from ..workflows.runner import swept
from ..workflows.theory_file import write_theory
from .common import describe, record_for, scene_for

LOAD_RANGE = (1e-7, 1e-1)  # default pressures, in units of E*


def run_theory(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    """Predict, write ``OUT.h5`` (and the plot) and print the table (rank 0)."""
    run = describe(args)
    modulus = run.modulus_value
    low, high = (v * modulus for v in LOAD_RANGE)
    unit = run.pressure_unit
    pressures = np.array(swept(args.sweep, low, high, lambda v: pressure_value(v, unit, "--sweep")))
    profile = _line_scan(args)
    if profile is None:
        petsc, run, scene = scene_for(args, petsc_args)
        result = predict(scene.grid, scene.fft, scene.heights, modulus, pressures)
        if scene.grid.comm.rank != 0:
            return 0
        reading, length_unit = scene.reading, scene.resolved["length_unit"]
        attributes = record_for(run, argv, petsc, {}, scene)
    else:
        result = predict_profile(
            profile.heights, _profile_length(args, profile), modulus, pressures
        )
        reading, length_unit = f"{args.heights}: {profile.describe()}", profile.unit or ""
        attributes = _profile_record(run, argv, profile)
    runs = [(os.path.basename(path), _run_table(path)) for path in args.compare or ()]
    if not args.quiet and reading:
        print(f"# {reading}", flush=True)
    write_theory(args.output, result, attributes, length_unit, run.pressure_unit or "")
    if not args.quiet:
        _print(result)
    if args.plot:
        from ..io.plot import plot_theory

        plot_theory(args.plot, result, modulus, runs, {"length": length_unit})
    print(f"# wrote {args.output}" + (f" and {args.plot}" if args.plot else ""))
    return 0


def _line_scan(args: argparse.Namespace) -> Any:
    """The line scan ``--heights`` holds (read and checked), or ``None`` for a map."""
    from ..io.topography import NotAMap, read_profile, read_topography

    if args.heights is None:
        return None
    try:
        read_topography(args.heights, args.channel)
        return None
    except NotAMap as exc:
        if "line scan" not in str(exc):
            raise
    profile = read_profile(args.heights, args.channel)
    undefined = int(np.count_nonzero(~np.isfinite(profile.heights)))
    if undefined:
        raise ValueError(f"the line scan has {undefined} undefined heights")
    return profile


def _profile_length(args: argparse.Namespace, profile: Any) -> float:
    """The scan's length: the file's, else ``--length`` (its unit must agree)."""
    from ..conventions.units import factor, parse_lengths

    if args.length is None:
        if profile.length is None:
            raise ValueError("the line scan has no length: give --length")
        return float(profile.length)
    given = parse_lengths(args.length)
    if given.unit and profile.unit:
        return given.values[0] * factor(given.unit, profile.unit)
    return given.values[0]


def _profile_record(run: Any, argv: Sequence[str], profile: Any) -> dict[str, Any]:
    """What reproduces a prediction for a line scan."""
    from ..io.provenance import file_digest, versions

    unit = profile.unit or ""
    return {
        "command_line": " ".join(["petsc-contact", *argv]),
        "parameters": run.parameters(),
        "versions": versions(),
        "heights_file": os.path.abspath(run.heights),
        "heights_sha256": file_digest(run.heights),
        "heights_reader": profile.reader + profile.note,
        "length": profile.length or 0.0,
        "length_unit": unit,
        "modulus": run.modulus_value,
        "pressure_unit": run.pressure_unit or "",
        "units": f"lengths and heights in {unit or 'the unit of --length'}",
    }


def _print(result: Prediction) -> None:
    lo, hi = result.fit_range
    print(
        f"# h_rms = {result.rms_height:.4g}, h'_rms = {result.rms_slope:.4g}, "
        f"H = {result.hurst_fit:.3f} (spectrum fitted for {lo:.3g} <= q <= {hi:.3g}, "
        f"R^2 = {result.hurst_fit_r2:.3f}); spectrum: {result.spectrum}"
    )
    print(
        f"# Persson: p = beta E* exp(-u/u0) with u0 = {result.u0:.4g} "
        f"({result.u0 / result.rms_height:.3f} h_rms), beta = {result.beta:.4g}"
    )
    print(
        f"# finite-size crossover p_c = {result.crossover_pressure:.3g} (paper Eq. 13 as "
        f"printed), {result.crossover_pressure_paper:.3g} (the paper's recipe: q_r h_rms with "
        "q_r = 2 pi/L, q_r L = pi, theta = 1)"
    )
    print(f"{'p0':>12} {'mean_gap':>12} {'K':>12}")
    for row in zip(result.nominal_pressure, result.mean_gap, result.stiffness, strict=True):
        print(" ".join(f"{v:>12.5g}" for v in row))


def check_compared(args: argparse.Namespace) -> None:
    """``ValueError`` unless ``--compare`` comes with ``--plot`` (it draws the runs there) and
    names periodic runs' files (a punch's mean gap is over its footprint, not a cell's)."""
    if not args.compare:
        return
    if not args.plot:
        raise ValueError("--compare draws runs beside the theory's plot: give --plot PNG")
    for path in args.compare:
        geometry = _geometry(path)
        if geometry != "periodic":
            what = f"geometry '{geometry}'" if geometry else "no geometry: not a run's file"
            raise ValueError(f"--compare takes periodic runs; '{path}' is not one ({what})")


def _geometry(path: str) -> str:
    """The ``geometry`` attribute of a results file ('' when it has none)."""
    import h5py

    try:
        with h5py.File(path, "r") as f:
            return str(f.attrs.get("geometry", ""))
    except OSError:
        raise ValueError(f"--compare: '{path}' is not an HDF5 results file") from None


def _run_table(path: str) -> dict[str, np.ndarray]:
    """A simulation's loads, mean gaps and stiffnesses, to draw beside the theory."""
    import h5py

    try:
        with h5py.File(path, "r") as f:
            table = {k: f[k][...] for k in ("nominal_pressure", "mean_gap", "stiffness") if k in f}
            if "converged" in f:
                table = {k: v[trusted(f)] for k, v in table.items()}
    except OSError as exc:
        raise OSError(f"--compare: cannot read '{path}' ({exc})") from None
    if "mean_gap" not in table:
        raise ValueError(f"--compare: '{path}' is not a periodic run's file (no mean_gap)")
    return table
