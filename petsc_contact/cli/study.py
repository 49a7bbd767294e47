"""``study``: the paper's datasets at the paper's parameters, in resumable pieces.

Each piece is one ``periodic`` or ``punch`` run with ``--stiffness --scalars-only``, written
to ``DATA/figN/NAME.h5``.  A piece already complete is skipped; an unfinished one continues
from its ``.partial`` file; the study stops cleanly after the step that ends past
``--minutes`` (exit status 75) and the next call goes on from there.  A piece that another
run is writing is left to that run, so several studies started on the same ``--data`` share
the pieces between them, one core each.  A piece's file (complete, or its ``.partial``)
of other parameters (another ``--shrink`` in the same ``--data``) is refused before anything
runs, never joined (:func:`~petsc_contact.paper.paper_study.run_pieces`).
"""

from __future__ import annotations

import argparse
from typing import Any

from .common import EXIT_INTERRUPTED, EXIT_NOT_CONVERGED, EXIT_PAUSED

STATUS = {  # how a study ends, as the exit status
    "complete": 0,
    "unconverged": EXIT_NOT_CONVERGED,
    "paused": EXIT_PAUSED,
    "interrupted": EXIT_INTERRUPTED,
}
PIECE_END = {code: end for end, code in STATUS.items()}  # how a piece's run ended


def run_study(args: argparse.Namespace, petsc_args: list[str]) -> int:
    """Run the pieces of the chosen figures in order within ``--minutes``."""
    from ..backend import _petsc
    from ..paper.paper_study import run_pieces, study_data, study_pieces
    from ..workflows.choice import uses_petsc
    from ..workflows.drivers import on_device

    data = study_data(args.data)
    todo = study_pieces(data, args.figure, args.shrink)
    if uses_petsc(args.device):
        _petsc.init(petsc_args)  # an array device's pieces carry the options instead

    def piece(run: Any) -> str:
        return _piece(on_device(run, args.device, petsc_args), args.quiet)

    end = run_pieces(todo, data, args.minutes, piece, _say)
    return STATUS[end]


def _piece(run: Any, quiet: bool) -> str:
    """Run one piece (its output locked by the study), printing as the run commands do; how
    it ended."""
    from .runs import execute

    shown = argparse.Namespace(command=run.geometry, quiet=quiet, plot=None)
    code = execute(run, shown, ["study", *run.arguments()], lock=False)
    return PIECE_END.get(code, "complete")


def _say(line: str) -> None:
    print(line, flush=True)


def study_plan(args: argparse.Namespace) -> str:
    """One line per piece: its state (``done``, ``todo``, or the steps an unfinished piece
    has kept, ``13/25``), its file and its command line."""
    from ..paper.paper_study import study_data, study_pieces
    from ..paper.paper_study import study_plan as plan

    data = study_data(args.data)
    return "\n".join(plan(study_pieces(data, args.figure, args.shrink), data))
