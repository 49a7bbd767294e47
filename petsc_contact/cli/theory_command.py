"""``theory``: Persson's predictions and the finite-size ``p_c`` from a map's spectrum."""

from __future__ import annotations

import argparse
from collections.abc import Sequence

import numpy as np

from ..conventions.units import pressure_value
from ..paper.predictions import Prediction, predict, predict_profile
from ..paper.theory_file import write_theory
from ..paper.theory_run import compared_runs, line_scan, profile_length, profile_record
from ..workflows.runner import swept
from .common import describe, record_for, scene_for

LOAD_RANGE = (1e-7, 1e-1)  # default pressures, in units of E*


def run_theory(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    """Predict, write ``OUT.h5`` (and the plot) and print the table (rank 0)."""
    run = describe(args)
    modulus = run.modulus_value
    low, high = (v * modulus for v in LOAD_RANGE)
    unit = run.pressure_unit
    pressures = np.array(swept(args.sweep, low, high, lambda v: pressure_value(v, unit, "--sweep")))
    profile = line_scan(args.heights, args.channel)
    if profile is None:
        petsc, run, scene = scene_for(args, petsc_args)
        length_unit = scene.resolved["length_unit"]
    else:
        length_unit = profile.unit or ""
    units = {"length": length_unit, "pressure": run.pressure_unit or ""}
    runs = compared_runs(args.compare, units)  # in the theory's units, before it is computed
    if profile is None:
        result = predict(scene.grid, scene.fft, scene.heights, modulus, pressures)
        if scene.grid.comm.rank != 0:
            return 0
        reading, attributes = scene.reading, record_for(run, argv, petsc, {}, scene)
    else:
        result = predict_profile(
            profile.heights, profile_length(args.length, profile), modulus, pressures
        )
        reading = f"{args.heights}: {profile.describe()}"
        attributes = profile_record(run, " ".join(["petsc-contact", *argv]), profile)
    if not args.quiet and reading:
        print(f"# {reading}", flush=True)
    write_theory(args.output, result, attributes, length_unit, run.pressure_unit or "")
    if not args.quiet:
        _print(result, length_unit, run.pressure_unit or "")
    if args.plot:
        from ..io.plot import plot_theory

        plot_theory(args.plot, result, modulus, runs, units)
    print(f"# wrote {args.output}" + (f" and {args.plot}" if args.plot else ""))
    return 0


def _print(result: Prediction, length_unit: str, pressure_unit: str) -> None:
    """The prediction's lines and table, with the units of ``--length`` and ``--modulus`` (none:
    unit-free numbers)."""
    lengths = length_unit or "units of --length"
    pressures = pressure_unit or "units of E*"
    per_length = f"1/{length_unit}" if length_unit else "1/(unit of --length)"
    print(
        f"# lengths (h_rms, u0, mean_gap) in {lengths}, pressures (p0, p_c) in {pressures}, "
        f"K in {pressures} per {length_unit or 'unit of --length'}, q in {per_length}"
    )
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
    print(
        f"# Persson's contact area A/A0 = erf(sqrt(2) p0 / (E* h'_rms)) with the spectrum's "
        f"h'_rms = {result.spectrum_rms_slope:.4g} (q up to {result.wavevector[-1]:.3g})"
    )
    print(f"{'p0':>12} {'mean_gap':>12} {'K':>12} {'A/A0':>12}")  # in the units above
    columns = (result.nominal_pressure, result.mean_gap, result.stiffness, result.area_fraction)
    for row in zip(*columns, strict=True):
        print(" ".join(f"{v:>12.5g}" for v in row))
