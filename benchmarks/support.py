"""Iterations against the interfacial stiffness the default solver's preconditioner is held by.

usage: .venv/bin/python benchmarks/support.py [--grid 1024] [--pressures 1e-3 1e-2]
       [--factors 0 0.25 0.5 1 2 4]
One load from first touch on a paper-bandwidth surface (H = 0.7, rms slope 0.1,
L/lambda_r = 1, L/lambda_1 = n/2, seed 1), with the preconditioner held by ``factor`` times
Persson's ``p0/(0.4 h_rms)``; factor 0 is the free compliance ``2/(E* q)`` with the mean mode
``2/(E* q0)`` (the solver before the support, up to the Schur form's and the mean mode's
contact-count rule). Prints iterations, solve time and the mean gap (the same for all).
"""

from __future__ import annotations

import argparse

from mpi4py import MPI

from petsc_contact.backend import _petsc
from petsc_contact.backend.solve import BoundSolver
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft
from petsc_contact.geometries.periodic import PeriodicProblem
from petsc_contact.physics.surface import self_affine


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=1024)
    ap.add_argument("--pressures", type=float, nargs="+", default=[1e-3, 1e-2])
    ap.add_argument("--factors", type=float, nargs="+", default=[0, 0.25, 0.5, 1, 2, 4])
    args = ap.parse_args()
    n = args.grid
    grid = Grid(n, 1.0, MPI.COMM_SELF)
    fft = make_fft(grid)
    heights = self_affine(
        grid, fft, hurst=0.7, rolloff_ratio=1, cutoff_ratio=n / 2, seed=1, rms_slope=0.1
    )
    _petsc.init([])
    problem = PeriodicProblem(grid, fft, heights, 1.0)
    x0 = problem.initial_gap().reshape(-1) / problem.scale_length
    print(f"{'p0/E*':>7} {'factor':>6} {'its':>5} {'solve_s':>8} {'mean_gap':>16}")
    with BoundSolver(grid, problem.hessian, problem.preconditioner) as solver:
        for p0 in args.pressures:
            for factor in args.factors:
                problem.set_pressure(p0, factor * problem.stiffness_estimate(p0))
                problem.start(x0)
                x, info = solver.solve(problem.objective_gradient, problem.start_point)
                flag = "" if info.reason_code > 0 else f"  {info.reason}"
                print(
                    f"{p0:>7.0e} {factor:>6g} {info.iterations:>5d} {info.solve_time:>8.2f} "
                    f"{x.mean() * problem.scale_length:>16.10e}{flag}",
                    flush=True,
                )


if __name__ == "__main__":
    main()
