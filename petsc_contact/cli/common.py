"""What every command shares: exit codes, input errors, the scene and the run record."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any

EXIT_NOT_CONVERGED = 1
EXIT_BAD_INPUT = 2
EXIT_UNAVAILABLE = 69  # a package the run needs cannot be loaded (sysexits' EX_UNAVAILABLE)
EXIT_STORAGE = 74  # results cannot be written: disk full, unwritable (sysexits' EX_IOERR)
EXIT_PAUSED = 75  # --stop-after reached: the run continues with --resume
EXIT_INTERRUPTED = 130


class InputError(Exception):
    """Bad user input: reported as one line, exit status 2."""


def describe(args: argparse.Namespace) -> Any:
    """The :class:`~petsc_contact.workflows.description.Run` the command line describes (its
    PETSc options are in the database already: the CLI gives them to PETSc at start)."""
    from dataclasses import fields

    from ..workflows.description import Run

    given = {f.name: getattr(args, f.name) for f in fields(Run) if hasattr(args, f.name)}
    return Run(**given, geometry="punch" if args.command == "punch" else "periodic")


def scene_for(args: argparse.Namespace, petsc_args: list[str]) -> tuple[Any, Any, Any]:
    """PETSc, the run the command line describes and its scene (``compare``, ``theory``)."""
    from ..backend import _petsc
    from ..workflows.scene import prepare_scene

    run = describe(args)
    petsc = _petsc.init(petsc_args)
    return petsc, run, prepare_scene(run, default_solver=False)


def record_for(
    run: Any, argv: Sequence[str], petsc: Any, realised: dict[str, Any], scene: Any
) -> dict[str, Any]:
    """The run record of a command that solves no sweep (``compare``, ``theory``)."""
    from ..workflows.runner import run_record

    line = " ".join(["petsc-contact", *argv])
    return run_record(run, line, petsc, realised, {**scene.resolved, **scene.record})


def say(message: str, kind: str = "error") -> None:
    """``petsc-contact: KIND: MESSAGE`` on standard error, from rank 0 only."""
    from ..conventions.grid import world_rank

    if world_rank() == 0:
        print(f"petsc-contact: {kind}: {message}", file=sys.stderr)
