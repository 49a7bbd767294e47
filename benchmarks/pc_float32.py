"""The periodic contact's preconditioner in float32 against float64, over seeds and surfaces.

usage: PYTHONPATH=. .venv/bin/python benchmarks/pc_float32.py [--device cpu-array]
       [--grids 256,512] [--hursts 0.3,0.7] [--seeds 1-8] [--out pc_float32.json]

For each grid, Hurst exponent and seed: a surface of rms slope 0.1, ``L/lambda_r = 2``,
``L/lambda_1 = n/4``, solved twice by ``periodic_contact`` on ``--device`` over 6 loads from
1e-4 to 1e-1 E* with the exact stiffness, once as the package's default (float64) and once with
``-petsc_contact_pc_float32``.  Prints per surface and in total the iterations (float32 over
float64, and the largest difference at one step), the mean gaps' and the stiffnesses' largest
relative difference, and the contact solves' seconds; writes every step to ``--out``.  On
``cpu-array`` (NumPy 2 computes a float32 array's FFT in float32) it shows whether the answers
and the iterations hold; the bandwidth saved shows on a GPU (``benchmarks/gpu.py``).
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

import numpy as np

FLOAT32 = ["-petsc_contact_pc_float32"]
LOADS = list(np.logspace(-4, -1, 6))
COLUMNS = ("nominal_pressure", "iterations", "solve_time", "mean_gap", "stiffness", "converged")


def surface(n: int, hurst: float, seed: int, device: str) -> Any:
    """The surface of ``n^2`` (module docstring) on ``device``'s arrays."""
    from petsc_contact.conventions.grid import Grid
    from petsc_contact.devices.device import get_device
    from petsc_contact.devices.fft import make_fft
    from petsc_contact.physics.surface import self_affine

    grid = Grid(n, 1.0)
    return self_affine(
        grid,
        make_fft(grid, get_device(device)),
        hurst=hurst,
        rolloff_ratio=2,
        cutoff_ratio=n / 4,
        seed=seed,
        rms_slope=0.1,
    )


class Counted:
    """Counts the preconditioner's float32 round trips while in a ``with`` block."""

    def __enter__(self) -> Counted:
        from petsc_contact.backend.preconditioner import MeanModePreconditioner

        self.kind, self.calls = MeanModePreconditioner, 0
        self.original = original = MeanModePreconditioner._single_round_trip

        def counted(pre: Any, x: Any, out: Any) -> Any:
            self.calls += 1
            return original(pre, x, out)

        MeanModePreconditioner._single_round_trip = counted  # type: ignore[method-assign]
        return self

    def __exit__(self, *exc: object) -> None:
        self.kind._single_round_trip = self.original  # type: ignore[method-assign]


def steps(heights: Any, device: str, options: list[str], loads: list[float]) -> dict[str, Any]:
    """Each step's :data:`COLUMNS` of the sweep over ``loads`` with ``options``, and how many
    of the preconditioner's round trips were made in float32."""
    from petsc_contact.workflows.periodic_sweep import periodic_contact

    with Counted() as counted:
        done = periodic_contact(
            heights, length=1.0, modulus=1.0, pressures=loads, stiffness=True, device=device,
            options=options,
        )  # fmt: skip
    rows = [{k: s.scalars[k] for k in COLUMNS} for s in done]
    trips = sum(int(s.scalars["preconditioner_applications"]) for s in done)
    return {"steps": rows, "round_trips": trips, "float32_round_trips": counted.calls}


def compare(
    n: int, hurst: float, seed: int, device: str, loads: list[float] = LOADS
) -> dict[str, Any]:
    """One surface's sweep in float64 and in float32: their steps and differences."""
    h = surface(n, hurst, seed, device)
    start = time.perf_counter()
    run64 = steps(h, device, [], loads)
    middle = time.perf_counter()
    run32 = steps(h, device, FLOAT32, loads)
    end = time.perf_counter()
    double, single = run64["steps"], run32["steps"]

    def column(rows: list[dict], key: str) -> np.ndarray:
        return np.array([r[key] for r in rows], dtype=float)

    def worst(key: str) -> float:
        return float(np.abs(column(single, key) / column(double, key) - 1).max())

    its64, its32 = column(double, "iterations"), column(single, "iterations")
    return {
        "grid": n,
        "hurst": hurst,
        "seed": seed,
        "iterations_float64": int(its64.sum()),
        "iterations_float32": int(its32.sum()),
        "largest_step_difference": int(np.abs(its32 - its64).max()),
        "mean_gap_rel": worst("mean_gap"),
        "stiffness_rel": worst("stiffness"),
        "solve_float64": float(column(double, "solve_time").sum()),
        "solve_float32": float(column(single, "solve_time").sum()),
        "wall_float64": middle - start,
        "wall_float32": end - middle,
        "converged": bool(all(r["converged"] for r in double + single)),
        "round_trips": run32["round_trips"],
        "float32_round_trips": run32["float32_round_trips"],
        "float64": double,
        "float32": single,
    }


def summary(rows: list[dict[str, Any]]) -> str:
    """One line over ``rows``: iterations, the worst differences, the solves' seconds."""
    its64 = sum(r["iterations_float64"] for r in rows)
    its32 = sum(r["iterations_float32"] for r in rows)
    return (
        f"{len(rows)} surfaces: iterations {its32} (float32) / {its64} (float64) = "
        f"{its32 / max(its64, 1):.4f}, largest difference at a step "
        f"{max(r['largest_step_difference'] for r in rows)}; mean gaps to "
        f"{max(r['mean_gap_rel'] for r in rows):.1e}, stiffnesses to "
        f"{max(r['stiffness_rel'] for r in rows):.1e}; solves "
        f"{sum(r['solve_float32'] for r in rows):.1f} s / "
        f"{sum(r['solve_float64'] for r in rows):.1f} s; all converged "
        f"{all(r['converged'] for r in rows)}; the preconditioner's round trips in float32: "
        f"{sum(r['float32_round_trips'] for r in rows)} of "
        f"{sum(r['round_trips'] for r in rows)}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--device", default="cpu-array")
    ap.add_argument("--grids", default="256,512")
    ap.add_argument("--hursts", default="0.3,0.7")
    ap.add_argument("--seeds", default="1-8", help="first-last")
    ap.add_argument("--out", default="pc_float32.json")
    ap.add_argument("--loads", default="1e-4,1e-1", help="the sweep's first and last load")
    args = ap.parse_args()
    low, high = (np.log10(float(p)) for p in args.loads.split(","))
    loads = list(np.logspace(low, high, 6))
    first, last = (int(s) for s in args.seeds.split("-"))
    rows = []
    for n in (int(g) for g in args.grids.split(",")):
        for hurst in (float(h) for h in args.hursts.split(",")):
            for seed in range(first, last + 1):
                row = compare(n, hurst, seed, args.device, loads)
                rows.append(row)
                print(
                    f"{n}^2 H={hurst} seed {seed}: iterations {row['iterations_float32']} / "
                    f"{row['iterations_float64']} (step {row['largest_step_difference']}), "
                    f"mean gap {row['mean_gap_rel']:.1e}, stiffness {row['stiffness_rel']:.1e}, "
                    f"float32 round trips {row['float32_round_trips']} of {row['round_trips']}",
                    flush=True,
                )
                with open(args.out, "w") as f:
                    json.dump(rows, f, indent=1, default=float)
        print(f"{n}^2: " + summary([r for r in rows if r["grid"] == n]), flush=True)
    print("all: " + summary(rows))


if __name__ == "__main__":
    main()
