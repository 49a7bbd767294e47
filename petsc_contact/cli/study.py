"""``study``: the paper's datasets at the paper's parameters, in resumable pieces.

Each piece is one ``periodic`` or ``punch`` run with ``--stiffness --scalars-only``, written
to ``DATA/figN/NAME.h5``.  A piece already complete is skipped; an unfinished one continues
from its ``.partial`` file; the study stops cleanly after the step that ends past
``--minutes`` (exit status 75) and the next call goes on from there.  A piece that another
run is writing is left to that run, so several studies started on the same ``--data`` share
the pieces between them, one core each.  A piece's file (complete, or its ``.partial``)
of other parameters (another ``--shrink`` in the same ``--data``) is refused before anything
runs, never joined.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

from ..io.store import OutputBusy, partial_path, storage, tidy
from ..workflows.paper_study import Piece, check_piece, complete, converged, finished_steps, pieces
from .common import EXIT_INTERRUPTED, EXIT_NOT_CONVERGED, EXIT_PAUSED


def chosen(args: argparse.Namespace) -> list[Piece]:
    """The pieces of ``--figure`` (all of them for ``all``), the smaller grids first
    (``ValueError`` for an empty ``--data``, one not a folder, a bad ``--shrink``)."""
    if not args.data:
        raise ValueError("give a data folder (--data is empty)")
    if os.path.exists(args.data) and not os.path.isdir(args.data):
        raise ValueError(f"--data '{args.data}' is not a folder")
    figure = f"fig{args.figure}" if args.figure.isdigit() else args.figure
    todo = [
        p for p in pieces(args.shrink) if args.figure == "all" or figure in (p.figure, *p.used_by)
    ]
    return sorted(todo, key=lambda p: p.grid)


def run_study(args: argparse.Namespace, petsc_args: list[str]) -> int:
    """Run the pieces of the chosen figures in order within ``--minutes``.

    Every decision (a piece complete, the time left) is rank 0's, shared with the other
    ranks.  A piece is run inside its lock, taken once: a piece another run holds is left to
    it, one that became complete before the lock was ours is skipped."""
    from ..backend import _petsc
    from ..conventions.grid import world
    from ..workflows.runner import locked
    from .runs import execute

    todo = chosen(args)
    with storage(args.data):
        os.makedirs(args.data, exist_ok=True)
    _petsc.init(petsc_args)
    comm = world()
    foreign = _agreed(comm, _foreign, args.data, todo)
    if foreign:  # before anything is computed
        raise ValueError(foreign)
    began = time.perf_counter()
    elsewhere, unconverged = [], []  # pieces other runs are writing; complete with failures
    for number, piece in enumerate(todo, 1):
        path = piece.path(args.data)
        if _agreed(comm, complete, path):
            tidy(path)  # what a writer killed after its last rename left
            if not _agreed(comm, converged, path):
                unconverged.append(path)
            continue
        left = _agreed(comm, lambda: args.minutes - (time.perf_counter() - began) / 60)
        if left <= 0:
            return _paused(comm, todo, number - 1)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        run = piece.to_run(args.data, round(left, 3))
        shown = argparse.Namespace(command=run.geometry, quiet=args.quiet, plot=None)
        try:
            with locked(path):
                if _agreed(comm, complete, path):  # finished by another run meanwhile
                    continue
                _say(comm, f"# study {number}/{len(todo)}: {path}")
                code = execute(run, shown, ["study", *run.arguments()], lock=False)
        except OutputBusy as busy:
            _say(
                comm,
                f"# study {number}/{len(todo)}: {path} is being written by another run "
                f"({busy.holder}); left to it",
            )
            elsewhere.append(path)
            continue
        if code in (EXIT_PAUSED, EXIT_INTERRUPTED):
            return code
        if code == EXIT_NOT_CONVERGED:
            unconverged.append(path)
    if elsewhere:
        _say(
            comm,
            f"# study: {len(elsewhere)} of {len(todo)} pieces are being written by other runs; "
            "run the study again once they end to check that every piece is complete",
        )
    if unconverged:
        _say(
            comm,
            f"# study: {len(unconverged)} of {len(todo)} pieces have steps that did not "
            f"converge (flagged converged = False): {', '.join(unconverged)}",
        )
        return EXIT_NOT_CONVERGED
    if elsewhere:
        return EXIT_PAUSED
    _say(comm, f"# study: all {len(todo)} pieces complete in {args.data}")
    return 0


def _foreign(data: str, todo: Sequence[Piece]) -> str:
    """Why a file of the pieces ``todo`` in ``data`` (complete, or a ``.partial``) is not the
    study's (:func:`check_piece`), or ``""``."""
    for piece in todo:
        path = piece.path(data)
        for kept in (path, partial_path(path)):
            try:
                if os.path.exists(kept):
                    check_piece(kept, piece.to_run(data))
            except ValueError as exc:
                return str(exc)
    return ""


T = TypeVar("T")


def _agreed(comm: Any, decide: Callable[..., T], *args: Any) -> T:
    """Rank 0's ``decide(*args)``, the same on every rank of ``comm``."""
    if comm.size == 1:
        return decide(*args)
    agreed: T = comm.bcast(decide(*args) if comm.rank == 0 else None, root=0)
    return agreed


def _say(comm: Any, line: str) -> None:
    """A line of the study's progress, from rank 0 only."""
    if comm.rank == 0:
        print(line, flush=True)


def _paused(comm: Any, todo: Sequence[Piece], done: int) -> int:
    _say(comm, f"# study: time is up after {done} of {len(todo)} pieces; run it again to go on")
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
