"""Cold steps of the default solver on the paper-bandwidth scenes, iterations and transforms
counted.

usage: .venv/bin/python benchmarks/cold_steps.py [--grids 1024 2048] [--pressure 1e-3]
       [--scenes 0.7/1 0.7/8 0.3/1 0.3/8] [--seeds 1] [--device cpu] [--stiffness]
       [--coarse-limit K] [-- PETSC OPTIONS]

Each scene ``H/R`` is the surface of "One load from first touch" in docs/performance.md
(Hurst exponent ``H``, ``L/lambda_r = R``, rms slope 0.1, ``L/lambda_1 = n/2``, each of
``--seeds``), solved from first touch at one nominal pressure on ``--device``
(``periodic_contact(heights, pressures=p0, device=...)``, as ``petsc-contact periodic ...
--pressures p0`` does).  Prints per step the iterations, the contact fraction, the serial
FFT backend's transforms inside the contact solve (:class:`fft_count.TransformCounter`;
"round trips" is half of them; ``nan`` on the array path, which it does not count), the coarse
spaces built and the last one's block side and aggregates, ``b (k)`` (``--coarse-limit``: at
most ``K`` aggregates instead of :func:`~petsc_contact.backend.preconditioner.coarse_limit`,
so that the blocks grow less or not at all), with ``--stiffness`` the held-set stiffness
solve's iterations (a measure of the preconditioner on a fixed contact set), and the mean
gap; then the iterations summed over the steps.  The default's sum over the eight scenes at
1024^2 and 2048^2 is 214 (docs/performance.md, "Measured and not kept").  The iterations
and transforms are deterministic; no time is measured.
"""

from __future__ import annotations

import argparse
import itertools
import sys
from pathlib import Path

import numpy as np
from mpi4py import MPI

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fft_count import TransformCounter

from petsc_contact.backend import preconditioner
from petsc_contact.backend.preconditioner import MeanModePreconditioner
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft
from petsc_contact.physics.surface import self_affine
from petsc_contact.workflows.periodic_sweep import periodic_contact

SCENES = ("0.7/1", "0.7/8", "0.3/1", "0.3/8")


class BuildCounter:
    """Count the two-level form's coarse spaces built (across loads and inverts)."""

    def __init__(self) -> None:
        self.builds = 0
        self.last = "-"  # the block side and aggregates of the last coarse space built
        build = MeanModePreconditioner._build

        def counted(pre: MeanModePreconditioner, free: np.ndarray) -> bool:
            built = build(pre, free)
            self.builds += int(built)
            if built and pre.coarse is not None:
                self.last = f"{pre.coarse.block} ({pre.coarse.size})"
            return built

        MeanModePreconditioner._build = counted  # type: ignore[method-assign,assignment]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--grids", type=int, nargs="+", default=[1024, 2048])
    parser.add_argument("--pressure", type=float, default=1e-3)
    parser.add_argument("--scenes", nargs="+", default=list(SCENES), help="H/R pairs")
    parser.add_argument("--seeds", type=int, nargs="+", default=[1], help="surfaces' seeds")
    parser.add_argument("--device", default="cpu", help="cpu (TAO) or cpu-array (the CG's driver)")
    parser.add_argument("--stiffness", action="store_true", help="and the held-set solve")
    parser.add_argument(
        "--coarse-limit", type=int, help="most aggregates (default: preconditioner.coarse_limit)"
    )
    parser.add_argument("extra", nargs="*", help="PETSc options (after --)")
    args = parser.parse_args()
    if args.coarse_limit is not None:
        limit = args.coarse_limit
        preconditioner.coarse_limit = lambda size: limit  # type: ignore[assignment]
    counter, per_solve = TransformCounter(), list[dict[str, int]]()
    counter.around_solves(per_solve)
    builds = BuildCounter()
    print(
        "| grid | H | L/lambda_r | seed | p0/E* | area | its | builds | b (k) | trips | trips/it "
        "| K its | mean gap |"
    )
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    total = trips_total = 0.0
    for n, scene, seed in itertools.product(args.grids, args.scenes, args.seeds):
        hurst, rolloff = (float(v) for v in scene.split("/"))
        grid = Grid(n, 1.0, MPI.COMM_SELF)
        heights = self_affine(
            grid,
            make_fft(grid),
            hurst=hurst,
            rolloff_ratio=rolloff,
            cutoff_ratio=n / 2,
            seed=seed,
            rms_slope=0.1,
        )
        before, builds.last = builds.builds, "-"
        (step,) = periodic_contact(
            heights,
            length=1.0,
            pressures=args.pressure,
            options=args.extra,
            stiffness=args.stiffness,
            device=args.device,
        )
        s, counts = step.scalars, per_solve.pop() if per_solve else None  # none: array path
        its = s["iterations"]
        trips = (counts["forward"] + counts["backward"]) / 2 if counts else float("nan")
        total += its
        trips_total += trips
        print(
            f"| {n} | {hurst:g} | {rolloff:g} | {seed} | {args.pressure:g} | "
            f"{s['area_fraction']:.4f} | {its} | {builds.builds - before} | {builds.last} | "
            f"{trips:g} | "
            f"{trips / max(its, 1):.2f} | "
            f"{s.get('stiffness_iterations', '-') if args.stiffness else '-'} | "
            f"{s['mean_gap']:.12e} |" + ("" if s["converged"] else " NOT CONVERGED"),
            flush=True,
        )
    print(f"total: {total:.0f} iterations, {trips_total / total:.3f} round trips per iteration")


if __name__ == "__main__":
    main()
