"""Coarse-to-fine starts for one load from first touch against the default start (not kept).

usage: .venv/bin/python benchmarks/cascade.py [--grid 1024] [--pressure 1e-3] [--levels 0 1 2]
Surface: H = 0.7, rms slope 0.1, L/lambda_r = 1, L/lambda_1 = n/2 (paper bandwidth), seed 1.
With L levels the surface is first solved on the (n/2^L)^2 grid, restricted to its longest
wavelengths by truncating its spectrum; the displacement ``g + h`` of each converged level is
prolonged to the next grid by zero-padding its spectrum, and the next level starts from
``max(u - h, 0)`` (the finer roughness then sticks out where it touches). Prints each level's
iterations and solve time, and the total, for L = 0 (the default start) and the others.
"""

from __future__ import annotations

import argparse

import numpy as np
from mpi4py import MPI

from petsc_contact.backend import _petsc
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft
from petsc_contact.geometries.periodic import PeriodicProblem
from petsc_contact.physics.surface import self_affine
from petsc_contact.workflows.periodic_sweep import sweep


def resample(field: np.ndarray, m: int) -> np.ndarray:
    """``field`` on an ``m x m`` grid with the spectrum truncated or zero-padded (the modes
    both grids share, Nyquist rows dropped)."""
    n = field.shape[0]
    k = min(n, m) // 2
    spectrum = np.fft.rfft2(field)
    out = np.zeros((m, m // 2 + 1), complex)
    out[:k, : k + 1] = spectrum[:k, : k + 1]
    out[-k:, : k + 1] = spectrum[-k:, : k + 1]
    return np.fft.irfft2(out, s=(m, m)) * (m / n) ** 2


def cascade(petsc, heights: np.ndarray, p0: float, levels: int) -> list[tuple[int, int, float]]:
    """Solve ``p0`` on ``levels`` coarser grids, then on the full one; each level's
    (grid, iterations, solve time)."""
    n = heights.shape[0]
    rows = []
    displacement = None
    for level in range(levels, -1, -1):
        m = n >> level
        grid = Grid(m, 1.0, MPI.COMM_SELF)
        problem = PeriodicProblem(grid, make_fft(grid), resample(heights, m), 1.0)
        start = (
            None
            if displacement is None
            else np.maximum(resample(displacement, m) - problem.heights, 0.0)
        )
        (step,) = sweep(problem, [p0], start=start)
        if not step.converged:
            raise SystemExit(f"level {m}^2 did not converge: {step.scalars['verification']}")
        rows.append((m, step.scalars["iterations"], step.scalars["solve_time"]))
        displacement = step.state + problem.heights
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=1024)
    ap.add_argument("--pressure", type=float, default=1e-3, help="p0/E*")
    ap.add_argument("--levels", type=int, nargs="+", default=[0, 1, 2])
    args = ap.parse_args()
    n = args.grid
    grid = Grid(n, 1.0, MPI.COMM_SELF)
    heights = self_affine(
        grid, make_fft(grid), hurst=0.7, rolloff_ratio=1, cutoff_ratio=n / 2, seed=1, rms_slope=0.1
    )
    petsc = _petsc.init([])
    for levels in args.levels:
        rows = cascade(petsc, heights, args.pressure, levels)
        steps = ", ".join(f"{m}^2: {its} its {t:.2f} s" for m, its, t in rows)
        print(f"levels {levels}: {steps}; total solve {sum(r[2] for r in rows):.2f} s", flush=True)


if __name__ == "__main__":
    main()
