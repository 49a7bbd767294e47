"""``compare``: every solver on one scene, error against wall time."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import Any

from .common import EXIT_NOT_CONVERGED, InputError, record_for, scene_for


def run_compare(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    """``petsc-contact compare``: every solver on one scene, error against time."""
    from ..geometries.periodic import PeriodicProblem
    from ..io.store import on_root
    from ..physics.surface import rms_of
    from ..workflows.compare import (
        DEFAULT_SOLVERS,
        check_solvers,
        commit_partial,
        compare,
        finished_solvers,
        write_compare,
    )

    if not args.time_limit >= 0 or args.stall_iterations < 0:
        raise InputError("--time-limit and --stall-iterations must not be negative")
    if "-tao_type" in petsc_args:  # it would follow, and replace, every solver's own
        raise InputError("compare takes its solvers from --solvers, not -tao_type")
    solvers = list(DEFAULT_SOLVERS) if args.solvers is None else args.solvers
    check_solvers(solvers)  # before any work
    petsc, run, scene = scene_for(args, petsc_args)
    grid, fft, heights = scene.grid, scene.fft, scene.heights
    problem = PeriodicProblem(grid, fft, heights, run.modulus_value)
    show = grid.comm.rank == 0 and not args.quiet
    if show:
        print(
            f"{'solver':>16} {'converged':>9} {'its':>6} {'time_s':>8} {'gap_err':>9} "
            f"{'p_err':>9} {'residual':>9} {'compl':>9}  reason",
            flush=True,
        )

    realised = {"rms_height": rms_of(grid, fft, heights), "pressure": args.pressure}  # collective
    attrs = record_for(run, argv, petsc, realised, scene)
    attrs["parameters"] |= {  # what the comparison is, beyond its scene
        "command": "compare",
        "pressure": args.pressure,
        "solvers": solvers,
        "time_limit": args.time_limit,
        "stall_iterations": args.stall_iterations,
    }
    done = finished_solvers(args.output, attrs["parameters"], args.resume, args.overwrite)
    finished: list[Any] = list(done)
    root = grid.comm.rank == 0
    for t in done if show else ():
        _print_trajectory(t)

    def report(trajectory: Any) -> None:  # commit each solver as it finishes
        finished.append(trajectory)
        on_root(
            grid.comm, lambda: commit_partial(args.output, reference_scalars[0], finished, attrs)
        )
        if show:
            _print_trajectory(trajectory)

    reference_scalars: list[dict[str, Any]] = []
    reference, trajectories = compare(
        problem,
        args.pressure,
        solvers,
        args.time_limit,
        petsc_args,  # after each solver's options file: the command line wins
        stall_iterations=args.stall_iterations,
        report=report,
        done=done,
        reference_ready=reference_scalars.append,
    )
    status = 0 if all(t.converged for t in trajectories) else EXIT_NOT_CONVERGED
    if not root:
        return status  # the same on every rank: the verdicts come from reduced residuals
    csv, png = write_compare(args.output, reference, trajectories, attrs)
    if show:
        print(
            f"# reference: mean gap {reference['mean_gap']:.10e}, natural residual "
            f"{reference['natural_residual']:.1e} (tolerance {reference['tolerance']:.0e})"
        )
        print(f"# wrote {args.output}, {csv} and {png}")
    return status


def _print_trajectory(trajectory: Any) -> None:
    """One row of the ``compare`` table, printed as the solver finishes."""
    from ..workflows.compare import table_rows

    ((name, reason, ok, its, t, eg, ep, r, c),) = table_rows([trajectory])
    print(
        f"{name:>16} {str(ok):>9} {its:>6d} {t:>8.3f} {eg:>9.1e} {ep:>9.1e} "
        f"{r:>9.1e} {c:>9.1e}  {reason}",
        flush=True,
    )
