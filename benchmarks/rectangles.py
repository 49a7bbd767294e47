"""Speed per grid point of rectangular grids against square ones with as many points.

usage: .venv/bin/python benchmarks/rectangles.py [--points 1048576] [--repeat 3]

Runs ``periodic`` (5 loads, --stiffness) and ``punch`` (2 approaches) on a square grid and on
4:1 rectangles (square pixels, and oblong ones) of the same number of points, alternating,
and prints the solve time per operator application per million points, the median of the
repeats: the cost of the transforms and of the CG's passes, which is what the grid's shape
could change (iteration counts differ between surfaces and are not compared).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

SURFACE = ["--hurst", "0.7", "--rms-slope", "0.1", "--seed", "1"]


def shapes(points: int) -> dict[str, tuple[str, str]]:
    n = int(round(np.sqrt(points)))
    return {
        "square": (f"{n}", "1"),
        "4:1 square pixels": (f"{2 * n},{n // 2}", "4,1"),
        "4:1 oblong pixels": (f"{2 * n},{n // 2}", "2,1"),
    }


def run(command: str, grid: str, length: str, out: str) -> float:
    """Solve seconds per operator application per million points of one run."""
    loads = ["--sweep", "5,1e-4,1e-2", "--stiffness"] if command == "periodic" else ["--sweep", "2"]
    argv = [sys.executable, "-m", "petsc_contact.cli", command, "--grid", grid, "--length"]
    subprocess.run(
        [*argv, length, *SURFACE, *loads, "--quiet", "--scalars-only", "--output", out], check=True
    )
    with h5py.File(out) as f:
        points = np.prod([int(v) for v in grid.split(",")]) if "," in grid else int(grid) ** 2
        if command == "punch":
            points *= 4  # the padded transform
        applications = f["hessian_applications"][:].sum()
        return float(f["solve_time"][:].sum() / applications / points * 1e6)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=1 << 20)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for command in ("periodic", "punch"):
            points = args.points if command == "periodic" else args.points // 4
            times: dict[str, list[float]] = {name: [] for name in shapes(points)}
            for _ in range(args.repeat):
                for name, (grid, length) in shapes(points).items():
                    times[name].append(run(command, grid, length, os.path.join(tmp, "o.h5")))
            base = np.median(times["square"])
            for name, values in times.items():
                m = np.median(values)
                print(
                    f"{command:>8} {name:>18}: {m:.4f} s per application per 1e6 points "
                    f"({m / base:.3f} of the square's)"
                )


if __name__ == "__main__":
    main()
