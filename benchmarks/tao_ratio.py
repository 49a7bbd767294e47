"""TAO's types against the default solver: the solve-time ratio, alternated in one process.

usage: .venv/bin/python benchmarks/tao_ratio.py [--grid 512] [--pressures 1e-6 1e-3 1e-2]
       [--solvers bncg blmvm] [--repeat 3] [--hurst 0.7] [--rolloff-ratio 2]
       [--cutoff-ratio 64] [-- PETSC OPTIONS FOR THE TAO TYPES]

Each load is solved from first touch by the default solver and by each TAO type (with its
shipped ``options/NAME.opts`` and the options after ``--``), one after the other, ``--repeat``
times; prints per load and type the iterations, objective evaluations, the median solve time,
the median and range of the per-round ratios to the default's solve time, and the largest
relative difference of the mean gap to the default's.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from mpi4py import MPI

from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft
from petsc_contact.physics.surface import self_affine
from petsc_contact.workflows.periodic_sweep import periodic_contact

OPTIONS = Path(__file__).resolve().parent.parent / "petsc_contact" / "options"


def surface(args: argparse.Namespace) -> np.ndarray:
    """The scene's heights (rms slope 0.1, seed 1)."""
    grid = Grid(args.grid, 1.0, MPI.COMM_SELF)
    return self_affine(
        grid,
        make_fft(grid),
        hurst=args.hurst,
        rolloff_ratio=args.rolloff_ratio,
        cutoff_ratio=args.cutoff_ratio,
        seed=1,
        rms_slope=0.1,
    )


def solve(heights: np.ndarray, p0: float, options: list[str]) -> dict[str, float]:
    """One load from first touch: the step's solve time, iterations, evaluations, mean gap."""
    (step,) = periodic_contact(heights, length=1.0, pressures=p0, options=options)
    s = step.scalars
    if not s["converged"]:
        print(f"not converged: {options} at {p0:g}: {s['tao_reason']}", flush=True)
    return {
        "time": float(s["solve_time"]),
        "its": int(s["iterations"]),
        "evals": int(s["objective_gradient_evaluations"]),
        "gap": float(s["mean_gap"]),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--grid", type=int, default=512)
    parser.add_argument("--pressures", type=float, nargs="+", default=[1e-6, 1e-3, 1e-2])
    parser.add_argument("--solvers", nargs="+", default=["bncg", "blmvm"])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--hurst", type=float, default=0.7)
    parser.add_argument("--rolloff-ratio", type=float, default=2.0)
    parser.add_argument("--cutoff-ratio", type=float, default=64.0)
    parser.add_argument("extra", nargs="*", help="PETSc options for the TAO types (after --)")
    args = parser.parse_args()
    heights = surface(args)
    print("| p0/E* | solver | iterations | evaluations | solve (s) | ratio (range) | gap diff |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for p0 in args.pressures:
        runs: dict[str, list[dict[str, float]]] = {"cg": []}
        runs.update({name: [] for name in args.solvers})
        for _ in range(args.repeat):
            for name in runs:
                options = [] if name == "cg" else ["-options_file", str(OPTIONS / f"{name}.opts")]
                runs[name].append(
                    solve(heights, p0, options + (args.extra if name != "cg" else []))
                )
        base = runs["cg"]
        for name, rs in runs.items():
            ratios = [r["time"] / b["time"] for r, b in zip(rs, base, strict=True)]
            gap = max(abs(r["gap"] - base[0]["gap"]) / abs(base[0]["gap"]) for r in rs)
            print(
                f"| {p0:g} | {name} | {rs[0]['its']} | {rs[0]['evals']} | "
                f"{np.median([r['time'] for r in rs]):.3f} | {np.median(ratios):.2f} "
                f"({min(ratios):.2f}-{max(ratios):.2f}) | {gap:.1e} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
