"""``compare``: every solver on one scene, error against wall time."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import Any

from .common import EXIT_NOT_CONVERGED, describe, record_for, scene_for

HEADER = (
    f"{'solver':>16} {'converged':>9} {'its':>6} {'time_s':>8} {'gap_err':>9} "
    f"{'p_err':>9} {'residual':>9} {'compl':>9}  reason"
)


def run_compare(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    """``petsc-contact compare``: every solver on one scene, error against time."""
    from ..conventions.units import pressure_value
    from ..conventions.validation import positive
    from ..workflows.compare import check_comparison, compare_into, shared_options
    from ..workflows.drivers import adhesive_law

    solvers = check_comparison(args.solvers, args.time_limit, args.stall_iterations, petsc_args)
    unit = describe(args).pressure_unit  # --modulus's
    pressure = positive("--pressures", pressure_value(args.pressure, unit, "--pressures"))
    # a solver's own options (-bncg_...) reach it alone, inside the comparison
    petsc, run, scene = scene_for(args, shared_options(petsc_args, solvers))
    show = scene.grid.comm.rank == 0 and not args.quiet
    if show:
        print(HEADER, flush=True)
    result = compare_into(
        args.output,
        scene,
        run.modulus_value,
        pressure,
        lambda realised: record_for(run, argv, petsc, realised, scene),
        solvers,
        args.time_limit,
        args.stall_iterations,
        petsc_args,
        args.resume,
        args.overwrite,
        report=_print_trajectory if show else None,
        interaction=adhesive_law(run, scene) if run.adhesion else run.interaction,
    )
    if show:
        reference = result.reference
        print(
            f"# reference: mean gap {reference['mean_gap']:.10e}, natural residual "
            f"{reference['natural_residual']:.1e} (tolerance {reference['tolerance']:.0e})"
        )
        print(f"# wrote {args.output}, {result.csv} and {result.png}")
    return 0 if result.converged else EXIT_NOT_CONVERGED


def _print_trajectory(trajectory: Any) -> None:
    """One row of the ``compare`` table, printed as the solver finishes."""
    from ..workflows.compare import table_rows

    ((name, reason, ok, its, t, eg, ep, r, c),) = table_rows([trajectory])
    print(
        f"{name:>16} {str(ok):>9} {its:>6d} {t:>8.3f} {eg:>9.1e} {ep:>9.1e} "
        f"{r:>9.1e} {c:>9.1e}  {reason}",
        flush=True,
    )
