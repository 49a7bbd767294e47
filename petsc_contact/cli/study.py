"""``study``: the paper's datasets at the paper's parameters, in resumable pieces.

Each piece is one ``periodic`` or ``punch`` run with ``--stiffness --scalars-only``, written
to ``DATA/figN/NAME.h5``.  A piece already complete is skipped; an unfinished one continues
from its ``.partial`` file; the study stops cleanly after the step that ends past
``--minutes`` (exit status 75) and the next call goes on from there.  A piece that another
run is writing is left to that run, so several studies started on the same ``--data`` share
the pieces between them, one core each.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Sequence

from ..io.store import OutputBusy, tidy
from ..workflows.paper_study import Piece, complete, finished_steps, pieces
from .common import EXIT_INTERRUPTED, EXIT_PAUSED


def chosen(args: argparse.Namespace) -> list[Piece]:
    """The pieces of ``--figure`` (all of them for ``all``), the smaller grids first."""
    figure = f"fig{args.figure}" if args.figure.isdigit() else args.figure
    todo = [
        p for p in pieces(args.shrink) if args.figure == "all" or figure in (p.figure, *p.used_by)
    ]
    return sorted(todo, key=lambda p: p.grid)


def run_study(args: argparse.Namespace, petsc_args: list[str]) -> int:
    """Run the pieces of the chosen figures in order within ``--minutes``."""
    from ..backend import _petsc
    from ..workflows.runner import locked
    from .runs import execute

    _petsc.init(petsc_args)
    todo = chosen(args)
    began = time.perf_counter()
    elsewhere = []  # pieces other runs are writing
    for number, piece in enumerate(todo, 1):
        path = piece.path(args.data)
        if complete(path):
            tidy(path)  # what a writer killed after its last rename left
            continue
        left = args.minutes - (time.perf_counter() - began) / 60
        if left <= 0:
            return _paused(todo, number - 1)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        try:
            with locked(path):  # free now, and still unfinished once we hold it (every rank)
                if complete(path):
                    continue
        except OutputBusy:
            _elsewhere(number, len(todo), path)
            elsewhere.append(path)
            continue
        run = piece.to_run(args.data, round(left, 3))
        _say(f"# study {number}/{len(todo)}: {path}")
        shown = argparse.Namespace(command=run.geometry, quiet=args.quiet, plot=None)
        try:
            code = execute(run, shown, ["study", *run.arguments()])
        except OutputBusy:  # another study took it between our look and our start
            _elsewhere(number, len(todo), path)
            elsewhere.append(path)
            continue
        if code in (EXIT_PAUSED, EXIT_INTERRUPTED):
            return code
    if elsewhere:
        _say(
            f"# study: {len(elsewhere)} of {len(todo)} pieces are being written by other runs; "
            "run the study again once they end to check that every piece is complete"
        )
        return EXIT_PAUSED
    _say(f"# study: all {len(todo)} pieces complete in {args.data}")
    return 0


def _say(line: str) -> None:
    """A line of the study's progress, from rank 0 only."""
    from mpi4py import MPI

    if MPI.COMM_WORLD.rank == 0:
        print(line, flush=True)


def _elsewhere(number: int, total: int, path: str) -> None:
    _say(f"# study {number}/{total}: {path} is being written by another run; left to it")


def _paused(todo: Sequence[Piece], done: int) -> int:
    _say(f"# study: time is up after {done} of {len(todo)} pieces; run it again to go on")
    return EXIT_PAUSED


def study_plan(args: argparse.Namespace) -> str:
    """One line per piece: its state (``done``, ``todo``, or the steps an unfinished piece
    has kept, ``13/25``), its file and its command line."""
    lines = []
    for piece in chosen(args):
        path = piece.path(args.data)
        if complete(path):
            state = "done"
        else:
            kept = finished_steps(path)
            state = "todo" if kept is None else f"{kept}/{piece.steps}"
        lines.append(f"{state:>5}  {path}  petsc-contact {' '.join(piece.run.arguments())}")
    return "\n".join(lines)
