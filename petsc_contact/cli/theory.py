"""``theory``: Persson's predictions and the finite-size ``p_c`` from a map's spectrum."""

from __future__ import annotations

import argparse
from collections.abc import Sequence

import numpy as np

from ..io.schema import THEORY, annotate, write_attributes
from ..io.store import atomic_h5
from ..workflows.predictions import Prediction, predict
from ..workflows.runner import swept
from .common import record_for, scene_for

LOAD_RANGE = (1e-7, 1e-1)  # default pressures, in units of E*


def run_theory(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    """Predict, write ``OUT.h5`` (and the plot) and print the table (rank 0)."""
    petsc, run, scene = scene_for(args, petsc_args)
    modulus = run.modulus_value
    low, high = (v * modulus for v in LOAD_RANGE)
    pressures = np.array(swept(args.sweep, low, high))
    result = predict(scene.grid, scene.fft, scene.heights, modulus, pressures)
    if scene.grid.comm.rank != 0:
        return 0
    if not args.quiet and scene.reading:
        print(f"# {scene.reading}", flush=True)
    resolved = scene.resolved
    attributes = record_for(run, argv, petsc, {}, scene)
    attributes.update(geometry="theory", **result.scalars())
    with atomic_h5(args.output) as f:
        for name in THEORY:
            f[name] = getattr(result, name)
        write_attributes(f, attributes)
        annotate(f, THEORY.__getitem__, resolved["length_unit"], run.pressure_unit or "")
    if not args.quiet:
        _print(result)
    if args.plot:
        from ..io.plot import plot_theory

        plot_theory(args.plot, result, modulus)
    print(f"# wrote {args.output}" + (f" and {args.plot}" if args.plot else ""))
    return 0


def _print(result: Prediction) -> None:
    lo, hi = result.fit_range
    print(
        f"# h_rms = {result.rms_height:.4g}, h'_rms = {result.rms_slope:.4g}, "
        f"H = {result.hurst_fit:.3f} (spectrum fitted for {lo:.3g} <= q <= {hi:.3g})"
    )
    print(
        f"# Persson: p = beta E* exp(-u/u0) with u0 = {result.u0:.4g} "
        f"({result.u0 / result.rms_height:.3f} h_rms), beta = {result.beta:.4g}"
    )
    print(
        f"# finite-size crossover p_c = {result.crossover_pressure:.3g} (paper Eq. 13 as "
        f"printed), {result.crossover_pressure_appendix:.3g} (q_r ~ pi/L, theta ~ 1)"
    )
    print(f"{'p0':>12} {'mean_gap':>12} {'K':>12}")
    for row in zip(result.nominal_pressure, result.mean_gap, result.stiffness, strict=True):
        print(" ".join(f"{v:>12.5g}" for v in row))
