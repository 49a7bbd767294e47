"""What every command shares: exit codes, input errors, the scene and the run record."""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Sequence
from typing import Any

from ..io.paths import Named, check_input, check_outputs

EXIT_NOT_CONVERGED = 1
EXIT_BAD_INPUT = 2
EXIT_UNAVAILABLE = 69  # a package the run needs cannot be loaded (sysexits' EX_UNAVAILABLE)
EXIT_STORAGE = 74  # results cannot be written: disk full, unwritable (sysexits' EX_IOERR)
EXIT_PAUSED = 75  # --stop-after reached: the run continues with --resume
EXIT_INTERRUPTED = 130


class InputError(Exception):
    """Bad user input: reported as one line, exit status 2."""


TABLED = ("periodic", "punch", "demo", "compare")  # OUT.csv beside OUT.h5
_OPTION_LINE = re.compile(r"^\s*($|#|alias\s|-[A-Za-z_])")  # PETSc's options file lines


def options_files(petsc_args: Sequence[str]) -> list[str]:
    """The files named by ``-options_file`` among PETSc's options."""
    return [b for a, b in zip(petsc_args, petsc_args[1:], strict=False) if a == "-options_file"]


def refusal(args: argparse.Namespace, petsc_args: Sequence[str]) -> str | None:
    """Why the command line is refused before anything is read by PETSc, computed or written
    (one line), or ``None``: its PETSc options' values of a known type, its options files,
    its inputs, its outputs and their clashes."""
    from ..solver.driver import check_option_values

    try:
        check_option_values(petsc_args)
        for path in options_files(petsc_args):
            check_options_file(path)
        inputs = command_inputs(args)
        for option, given in inputs:
            if given is not None:
                check_input(given, option)
        check_outputs(command_outputs(args), inputs)
        if args.command == "theory":
            from ..paper.theory_run import check_compared

            check_compared(args.compare, args.plot)
    except (ValueError, FileNotFoundError) as exc:
        return str(exc)
    return None


def check_options_file(path: str) -> None:
    """``ValueError`` unless ``path`` is a text file of PETSc options (``-name [value]``
    lines, ``#`` comments): PETSc would otherwise print a dozen lines of errors."""
    try:
        check_input(path, "options file")
        with open(path, encoding="utf-8") as f:
            lines = f.read().splitlines()
    except UnicodeDecodeError:
        raise ValueError(f"options file '{path}' is not text (-options_file)") from None
    except (ValueError, FileNotFoundError) as exc:
        raise ValueError(f"{exc} (-options_file)") from None
    for number, line in enumerate(lines, 1):
        if "\0" in line or not _OPTION_LINE.match(line):
            raise ValueError(
                f"options file '{path}' line {number} is not a PETSc option: its lines are "
                "'-name [value]' or # comments (-options_file)"
            )


def command_inputs(args: argparse.Namespace) -> list[Named]:
    """The files the command reads, as ``(option, path)`` pairs (``None``: not given)."""
    inputs: list[Named] = [("--heights", getattr(args, "heights", None))]
    inputs += [("--compare", path) for path in getattr(args, "compare", None) or ()]
    if args.command == "plot":
        inputs.append(("the file to plot", args.file))
    if args.command == "experiment":
        inputs.append(("--table", args.table))
    return inputs


def command_outputs(args: argparse.Namespace) -> list[Named]:
    """The files the command writes, as ``(option, path)`` pairs, the names derived from
    ``--output`` (``OUT.csv``, ``compare``'s ``OUT.png``) among them."""
    from ..io.names import csv_path
    from ..io.plot import plot_file

    output, plot = getattr(args, "output", None), getattr(args, "plot", None)
    if output and args.command == "plot":
        output = plot_file(output, "--output")
    outputs: list[Named] = [("--output", output), ("--plot", plot and plot_file(plot))]
    if output and args.command in TABLED:
        outputs.append(("the table of --output", csv_path(output)))
    if output and args.command == "compare":
        outputs.append(("the plot of --output", output.removesuffix(".h5") + ".png"))
    return outputs


def describe(args: argparse.Namespace, petsc_args: Sequence[str] = ()) -> Any:
    """The :class:`~petsc_contact.workflows.description.Run` the command line describes: the
    command's options that are Run's fields (:func:`~petsc_contact.workflows.options.run_fields`).
    On the ``cpu`` device its PETSc options are in the database already (the CLI gives them to
    PETSc at start); an array device's run, which has no PETSc, carries ``petsc_args``."""
    from ..workflows.choice import uses_petsc
    from ..workflows.description import Run
    from ..workflows.options import run_fields

    given = {name: getattr(args, name) for name in run_fields(args.command)}
    run = Run(**given, geometry="punch" if args.command == "punch" else "periodic")
    return run if uses_petsc(run.device) else run.with_(options=tuple(petsc_args))


def on_array_device(args: argparse.Namespace) -> bool:
    """Whether the command line asks for an array device (``--device gpu`` or ``cpu-array``:
    no PETSc is loaded)."""
    from ..workflows.choice import uses_petsc

    return not uses_petsc(getattr(args, "device", "cpu"))


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
