"""The entry point: parse, dispatch, report unused PETSc options, exit status."""

from __future__ import annotations

import argparse
import os
import signal
import sys
import warnings
from collections.abc import Sequence
from typing import Any

from ..conventions.warnings import FullContact, PetscContactWarning, Unconverged, command_line
from ..devices.device import DeviceUnavailable
from ..io.schema import schema_markdown
from ..io.store import StorageError, check_interrupt, check_writable, forget_interrupts, interrupt
from .arguments import (
    build_parser,
    demo_cutoff,
    demo_replacing_its_own,
    is_petsc_option,
    split_arguments,
)
from .common import (
    EXIT_BAD_INPUT,
    EXIT_INTERRUPTED,
    EXIT_STORAGE,
    EXIT_UNAVAILABLE,
    InputError,
    command_outputs,
    describe,
    on_array_device,
    refusal,
    say,
)


def _unraisable(info: Any) -> None:
    """Python's report of an exception it had to drop (in a finaliser), less the interrupts:
    those are remembered and end the run with its one note (:func:`check_interrupt`)."""
    if not issubclass(info.exc_type, KeyboardInterrupt):
        sys.__unraisablehook__(info)


def _show_warning(message: Warning | str, category: type[Warning], *args: Any, **kw: Any) -> None:
    """The package's warnings (a doubtful map, load on filled heights, unused PETSc options:
    :class:`~petsc_contact.conventions.warnings.PetscContactWarning`) as one line each."""
    if issubclass(category, PetscContactWarning):
        say(str(message), "warning")
    else:
        print(warnings.formatwarning(message, category, *args[:2]), end="", file=sys.stderr)


class QuietPipe:
    """Standard output that falls silent when its reader goes away (``... | head``): the run
    goes on and writes its files; only the table is no longer printed."""

    def __init__(self, stream: Any) -> None:
        self.stream = stream
        self.closed_by_reader = False

    def write(self, text: str) -> int:
        if not self.closed_by_reader:
            try:
                return int(self.stream.write(text))
            except BrokenPipeError:
                self._silence()
        return len(text)

    def flush(self) -> None:
        if not self.closed_by_reader:
            try:
                self.stream.flush()
            except BrokenPipeError:
                self._silence()

    def _silence(self) -> None:
        self.closed_by_reader = True
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, self.stream.fileno())  # nothing is left to flush at exit
        os.close(devnull)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.stream, name)


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``petsc-contact`` with ``argv`` (default: the process's); return the exit status."""
    argv = list(sys.argv[1:] if argv is None else argv)
    ours, petsc_args = split_arguments(argv)
    args = build_parser().parse_args(ours)
    problem = refusal(args, petsc_args)
    if problem:  # before PETSc reads an options file, before anything is computed or written
        say(problem)
        return EXIT_BAD_INPUT
    for signum in (signal.SIGTERM, signal.SIGINT):  # remembered: never lost in a finaliser
        signal.signal(signum, interrupt)
    sys.stdout = QuietPipe(sys.stdout)
    sys.unraisablehook = _unraisable
    warnings.showwarning = _show_warning
    for flagged in (Unconverged, FullContact):  # flagged results are said, whatever the filters
        warnings.simplefilter("always", flagged)
    try:
        for option, path in command_outputs(args):  # a figure's folder, as the output's
            if option == "--plot" and path:
                check_writable(path, "--plot's")
        with demo_replacing_its_own(args), command_line():  # warnings name its flags
            status = _dispatch(args, argv, petsc_args)
        _report_unused(petsc_args)
        if status != EXIT_INTERRUPTED:  # said so already
            check_interrupt()  # a signal whose exception a finaliser dropped
        return status
    except (ImportError, DeviceUnavailable) as exc:  # the installation, not the input
        say(str(exc))
        return EXIT_UNAVAILABLE
    except StorageError as exc:
        say(exc.strerror or str(exc))
        return EXIT_STORAGE
    except (InputError, ValueError, OSError, MemoryError, PetscContactWarning) as exc:
        say(str(exc) or type(exc).__name__)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt as exc:  # a run's says what it kept
        say(str(exc) or "interrupted", "note")
        return EXIT_INTERRUPTED
    except Exception as exc:
        if type(exc).__name__ == "Error" and "petsc4py" in type(exc).__module__:
            say(f"PETSc error: {petsc_message(exc)}")
            return EXIT_BAD_INPUT
        raise
    finally:
        _release_petsc()
        forget_interrupts()


def _release_petsc() -> None:
    """Destroy the PETSc objects Python no longer holds while Python still runs: PETSc
    destroys what is left at its finalisation, after Python's, and a preconditioner with a
    Python context (the default solver's) then crashes the process on its way out."""
    if "petsc4py.PETSc" in sys.modules:
        import gc

        gc.collect()
        sys.modules["petsc4py.PETSc"].garbage_cleanup()


def petsc_message(exc: Exception) -> str:
    """A PETSc error in one line: its messages and the routine where it arose.

    petsc4py's text is ``error code N`` then PETSc's stack (``[0] Routine() at file:line``)
    and the messages (``[0] Argument out of range``)."""
    lines = [line.removeprefix("[0]").strip() for line in str(exc).splitlines()[1:]]
    stack = [line.split("()")[0] for line in lines if "() at " in line]
    said = [line for line in lines if line and "() at " not in line]
    where = f" (in {stack[-1]})" if stack else ""
    return ": ".join(said) + where if said else str(exc).splitlines()[0]


LOCKED = ("ensemble", "experiment", "compare", "theory")  # periodic, punch: their run locks


def _dispatch(args: argparse.Namespace, argv: Sequence[str], petsc_args: list[str]) -> int:
    """Run the command (each module imported when used, so that ``--help`` starts fast)."""
    from ..workflows.runner import locked
    from .comparison import run_compare
    from .ensemble_command import run_ensemble
    from .runs import execute, run
    from .study import run_study, study_plan
    from .theory_command import run_theory
    from .tools import run_experiment, run_plot

    if args.command == "schema":
        sys.stdout.write(schema_markdown())
        return 0
    if args.command == "plot":
        return run_plot(args)
    if args.command == "study" and args.list:
        print(study_plan(args))
        return 0
    if args.command == "study":
        return run_study(args, petsc_args)  # each piece locked: studies may share a folder
    if args.command == "demo":
        demo_cutoff(args)
    if args.command not in LOCKED and on_array_device(args):  # no PETSc is loaded
        return execute(describe(args, petsc_args), args, argv)
    if args.command not in LOCKED:
        return run(args, argv, petsc_args)
    with locked(args.output):
        if args.command == "ensemble":
            return run_ensemble(args, argv, petsc_args)
        if args.command == "experiment":
            return run_experiment(args)
        if args.command == "compare":
            return run_compare(args, argv, petsc_args)
        return run_theory(args, argv, petsc_args)


def _report_unused(petsc_args: list[str]) -> None:
    """Warn about the user's PETSc options that nothing read (a misspelt ``-tao_typo``)."""
    if not petsc_args or "petsc4py.PETSc" not in sys.modules:
        return
    from ..backend import _petsc

    names = [a[1:] for a in petsc_args if is_petsc_option(a)]
    unused = _petsc.unused_options(names)
    if unused:
        say(f"PETSc options never used: {' '.join(unused)}", "warning")
