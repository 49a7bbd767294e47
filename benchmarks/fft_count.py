"""FFT transforms counted per iteration of the default solver over a load sweep.

usage: .venv/bin/python benchmarks/fft_count.py [--grid 512] [--hurst 0.7] [--rolloff-ratio 1]
       [--sweep 12,1e-7,1e-1] [--stiffness] [-- PETSC OPTIONS]

Runs ``periodic_contact`` on the paper-bandwidth surface (rms slope 0.1,
``L/lambda_1 = n/2``, seed 1) along the sweep, and counts, inside each step's contact solve
only (``BoundSolver.solve``), the serial FFT backend's forward and backward transforms, with
the solver's own counts of objective/gradient evaluations, Hessian and preconditioner
applications.  ``--stiffness`` adds the exact stiffness to every step, as the command line's
``--stiffness`` does (its held-set solves are not counted; it sets the next step's
preconditioner).  Prints one row per step and the sweep's totals; "round trips" is half the
transforms.
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np
from mpi4py import MPI

from petsc_contact.backend.solve import BoundSolver
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import SerialFFT, make_fft
from petsc_contact.physics.surface import self_affine
from petsc_contact.workflows.periodic_sweep import periodic_contact

COUNTED = ("forward", "backward", "forward_from", "backward_into")
FORWARD = ("forward", "forward_from")


class TransformCounter:
    """Count the serial backend's transforms, forward and backward, while :attr:`on`."""

    def __init__(self) -> None:
        self.counts = {"forward": 0, "backward": 0}
        self.on = False
        for name in COUNTED:
            method = getattr(SerialFFT, name)
            kind = "forward" if name in FORWARD else "backward"

            def counted(*args: Any, _method: Any = method, _kind: str = kind, **kw: Any) -> Any:
                if self.on:
                    self.counts[_kind] += 1
                return _method(*args, **kw)

            setattr(SerialFFT, name, counted)

    def around_solves(self, per_solve: list[dict[str, int]]) -> None:
        """Count inside ``BoundSolver.solve`` only; append each solve's counts."""
        solve = BoundSolver.solve

        def counted_solve(solver: BoundSolver, *args: Any, **kw: Any) -> Any:
            before = dict(self.counts)
            self.on = True
            try:
                return solve(solver, *args, **kw)
            finally:
                self.on = False
                per_solve.append({k: self.counts[k] - before[k] for k in self.counts})

        BoundSolver.solve = counted_solve  # type: ignore[method-assign]


def sweep_loads(text: str) -> np.ndarray:
    """``N,first,last``: N loads log-spaced from first to last."""
    n, first, last = text.split(",")
    return np.geomspace(float(first), float(last), int(n))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--grid", type=int, default=512)
    parser.add_argument("--hurst", type=float, default=0.7)
    parser.add_argument("--rolloff-ratio", type=float, default=1.0)
    parser.add_argument("--sweep", default="12,1e-7,1e-1")
    parser.add_argument("--stiffness", action="store_true")
    parser.add_argument("extra", nargs="*", help="PETSc options (after --)")
    args = parser.parse_args()
    grid = Grid(args.grid, 1.0, MPI.COMM_SELF)
    heights = self_affine(
        grid,
        make_fft(grid),
        hurst=args.hurst,
        rolloff_ratio=args.rolloff_ratio,
        cutoff_ratio=args.grid / 2,
        seed=1,
        rms_slope=0.1,
    )
    counter, per_solve = TransformCounter(), []
    counter.around_solves(per_solve)
    steps = periodic_contact(
        heights,
        length=1.0,
        pressures=list(sweep_loads(args.sweep)),
        options=args.extra,
        stiffness=args.stiffness,
    )
    print(
        "| step | p0/E* | area | its | evals | H | M | forward | backward | trips/it | mean gap |"
    )
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    total = np.zeros(4)
    for i, (step, counts) in enumerate(zip(steps, per_solve, strict=True), 1):
        s = step.scalars
        its, fwd, bwd = s["iterations"], counts["forward"], counts["backward"]
        total += (its, fwd, bwd, s["objective_gradient_evaluations"])
        print(
            f"| {i} | {s['nominal_pressure']:.2g} | {s['area_fraction']:.4f} | {its} | "
            f"{s['objective_gradient_evaluations']} | {s['hessian_applications']} | "
            f"{s['preconditioner_applications']} | {fwd} | {bwd} | "
            f"{(fwd + bwd) / 2 / max(its, 1):.2f} | {s['mean_gap']:.12e} |"
        )
    its, fwd, bwd, evals = total
    print(
        f"sweep: {its:.0f} iterations, {evals:.0f} evaluations, {fwd:.0f} forward and "
        f"{bwd:.0f} backward transforms, {(fwd + bwd) / 2 / its:.3f} round trips per iteration"
    )


if __name__ == "__main__":
    main()
