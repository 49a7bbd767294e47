"""``ensemble``: one periodic run per seed, then statistics over seeds."""

from __future__ import annotations

import argparse
import warnings
from collections.abc import Sequence

from .common import EXIT_INTERRUPTED, EXIT_PAUSED, describe, on_array_device


def run_ensemble(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    """One periodic run per seed (each resumable), then statistics over seeds in OUT.h5; what
    an earlier ensemble left is continued, cleared or refused (``--resume``, ``--overwrite``,
    neither: :func:`~petsc_contact.workflows.seeds.seeds_to_run`)."""
    from ..backend import _petsc
    from ..conventions.grid import world
    from ..conventions.warnings import IgnoredOption
    from ..workflows.seeds import (
        ensemble_record,
        seed_runs,
        seed_scales,
        seeds_to_run,
        summarise,
        write_summary,
    )
    from .runs import execute

    if any(a == "--seed" or a.startswith("--seed=") for a in argv):
        warnings.warn(
            "--seed is ignored: an ensemble's surfaces are its --seeds", IgnoredOption, stacklevel=2
        )
    base = describe(args, petsc_args)
    if not on_array_device(args):
        _petsc.init(petsc_args)
    runs = seed_runs(base, args.seeds)
    status = 0
    for run in seeds_to_run(base, runs):  # a seed finished earlier is not recomputed
        seed_args = argparse.Namespace(command="periodic", quiet=args.quiet, plot=None)
        code = execute(run, seed_args, argv)
        if code in (EXIT_INTERRUPTED, EXIT_PAUSED):
            return code  # the next --resume continues with this seed
        status = max(status, code)
    files = [str(r.output) for r in runs]
    pressures = [float(p) for p in runs[0].pressures or []]
    record = ensemble_record(base, args.seeds, pressures, " ".join(["petsc-contact", *argv]))
    if world().rank == 0:
        summary = summarise(args.seeds, files)
        write_summary(args.output, summary, files, record)
        if args.plot:
            from ..io.plot import plot_ensemble

            plot_ensemble(args.plot, summary, base.modulus_value, *seed_scales(files))
        if not args.quiet:
            plotted = f" and {args.plot}" if args.plot else ""
            print(f"# wrote {args.output}{plotted} ({len(files)} seeds)")
    return status
