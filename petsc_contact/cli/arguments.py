"""The command line's arguments: the package's own (two dashes) and PETSc's (one dash).

The options of the commands with a scene are made from their one description,
:data:`~petsc_contact.workflows.options.OPTIONS`; ``plot``, ``study`` and ``experiment``
add their own here.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager, suppress
from typing import Any, NoReturn

from .._version import __version__
from ..backend._petsc import is_petsc_option
from ..conventions.warnings import ReplacedOutput
from ..workflows.options import (
    DEFAULT_DATA,
    OPTIONS,
    Option,
    default_text,
    minutes,
    options_of,
    shown,
)


class DemoCutoff(float):
    """``demo``'s ``L/lambda_1`` when none is given (told apart from a given 64 by identity):
    the default scene's 64, or the Nyquist limit on a grid where 64 is past it."""

    shown = "64, or the Nyquist limit on a grid where 64 is past it"


DEMO: dict[str, Any] = {
    "grid": 512,
    "hurst": 0.7,
    "rms_slope": 0.1,
    "rolloff_ratio": 2.0,
    "cutoff_ratio": DemoCutoff(64.0),
    "seed": 1,
    "modulus": 1.0,
    "pressures": [3e-5, 1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 2e-2, 3e-2],
    "output": "demo.h5",
    "plot": "demo.png",
}
"""``demo``'s defaults: the default scene (:class:`DemoCutoff`)."""


@contextmanager
def demo_replacing_its_own(args: argparse.Namespace) -> Iterator[None]:
    """Within the block, ``demo`` replaces its own earlier ``demo.h5`` without the warning
    (:class:`~petsc_contact.conventions.warnings.ReplacedOutput`) that a run over an existing
    output gives: the README's first command runs again as it ran the first time.  Another
    ``--output``, another command, and an interrupted demo's ``.partial`` are as any run's."""
    with warnings.catch_warnings():
        own = os.path.abspath(DEMO["output"])
        if args.command == "demo" and os.path.abspath(args.output) == own:
            warnings.filterwarnings("ignore", category=ReplacedOutput)
        yield


def demo_cutoff(args: argparse.Namespace) -> None:
    """``demo``'s ``L/lambda_1`` on a grid where the default scene's 64 is past the Nyquist
    limit (:func:`~petsc_contact.physics.surface.nyquist_ratio`): that limit (``None``).  One
    given with ``--cutoff-ratio`` stays as given."""
    if type(args.cutoff_ratio) is not DemoCutoff or args.grid is None:
        return
    from ..conventions.grid import grid_for
    from ..conventions.units import parse_lengths
    from ..physics.surface import nyquist_ratio

    shape = tuple(args.grid) if isinstance(args.grid, (list, tuple)) else (args.grid,) * 2
    try:
        length = parse_lengths(args.length).pair if args.length is not None else 1.0
    except ValueError:
        return  # the run's check says why
    if args.cutoff_ratio > nyquist_ratio(grid_for(shape, length)):
        args.cutoff_ratio = None


SURFACE_GROUP = "surface (a file, or a generated self-affine surface, paper Eq. 5)"


_NUMBER = re.compile(r"^-?(\d|\.\d)")


def split_arguments(argv: Sequence[str]) -> tuple[list[str], list[str]]:
    """Split a command line into the package's arguments and PETSc's options.

    A token like ``-tao_type`` starts a PETSc option; the token after it is its value unless
    it starts with a dash (numbers such as ``-1`` are values).  ``-h`` is the package's help.
    """
    ours: list[str] = []
    petsc: list[str] = []
    tokens = list(argv)
    i = 0
    while i < len(tokens):
        tok = tokens[i]
        if is_petsc_option(tok):
            petsc.append(tok)
            if i + 1 < len(tokens) and (
                not tokens[i + 1].startswith("-") or _NUMBER.match(tokens[i + 1])
            ):
                petsc.append(tokens[i + 1])
                i += 1
        elif (
            tok.startswith("--")
            and "=" not in tok
            and i + 1 < len(tokens)
            and _NUMBER.match(tokens[i + 1])
        ):
            # joined, so that argparse reads a negative value such as -1e-3 as the value
            # (it takes only -1 and -.5 for numbers) and its check can say what is wrong
            value = tokens[i + 1]
            ours += [f"{tok}={value}"] if _negative(value) else [tok, value]
            i += 1
        else:
            ours.append(tok)
        i += 1
    return ours, petsc


def _negative(value: str) -> bool:
    """Whether ``value`` is a negative number (``-1e-3``; not ``-1.h5``)."""
    try:
        return value.startswith("-") and float(value) < 0
    except ValueError:
        return False


_SPELT = "deprecated_spellings"  # the parsed arguments' note of the deprecated ones used


class _Deprecated(argparse.Action):
    """Store the value; a spelling among ``deprecated`` is noted, for the parser to say once
    the command line is read (an error stays one line)."""

    def __init__(self, *args: Any, deprecated: tuple[str, ...], **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.deprecated = deprecated

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        if option_string in self.deprecated:
            spelt = [*getattr(namespace, _SPELT, []), (option_string, self.option_strings[0])]
            setattr(namespace, _SPELT, spelt)
        setattr(namespace, self.dest, values)


_IGNORED = "ignored_options"  # the parsed arguments' note of the retired options given


class _Ignored(argparse.Action):
    """An option the command no longer has (:attr:`Option.ignored_by`): its default value is
    noted, for the parser to say it is ignored once the command line is read; any other
    value is refused as the unknown argument it is."""

    def __init__(self, *args: Any, accepted: Any, owners: tuple[str, ...], **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.accepted, self.owners = accepted, owners

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        try:
            accepted = type(self.accepted)(values) == self.accepted
        except ValueError:
            accepted = False
        if not accepted:
            parser.error(f"unrecognized arguments: {option_string} {values}")
        owners = " and ".join(self.owners)
        setattr(namespace, _IGNORED, [*getattr(namespace, _IGNORED, []), (option_string, owners)])


def _ignored(target: Any, option: Option) -> None:
    """Add ``option`` to a command that no longer has it: read, said to be ignored, hidden
    from ``--help``."""
    kwargs: dict[str, Any] = {"dest": f"ignored_{option.name}", "default": argparse.SUPPRESS}
    kwargs.update(help=argparse.SUPPRESS, metavar=option.metavar)
    target.add_argument(
        *option.flags, action=_Ignored, accepted=option.default, owners=option.commands, **kwargs
    )


def _help(option: Option, default: Any, own: bool = False) -> str:
    """The option's ``--help`` line: its help and the default the command gives it (``own``:
    the command's own, ``demo``'s), inside the help's closing parenthesis when it has one
    (``(0 to 2^63 - 1; default 0)``)."""
    if isinstance(default, DemoCutoff):
        text: str | None = default.shown
    else:
        text = shown(default) if own else default_text(option, default)
    if text:
        text = f"default: {text}" if option.shown_default and not own else f"default {text}"
    line = option.help
    if text:
        line = line[:-1] + f"; {text})" if line.endswith(")") else f"{line} ({text})"
    return line.replace("%", "%%")


def _argument(target: Any, option: Option, defaults: dict[str, Any]) -> None:
    """Add ``option`` to a parser, a group or an exclusive group; ``defaults``: the
    command's own (``demo``), which also make a required option optional."""
    default = defaults.get(option.name, option.default)
    kwargs: dict[str, Any] = {"dest": option.name, "default": default}
    kwargs["help"] = _help(option, default, own=option.name in defaults)
    if option.switch:
        kwargs["action"] = "store_true"
    else:
        kwargs.update(metavar=option.metavar, type=option.parse, choices=option.choices)
        kwargs.update(nargs=option.nargs)
    if option.deprecated:
        kwargs.update(action=_Deprecated, deprecated=option.deprecated)
    if option.required and not option.exclusive:
        kwargs["required"] = option.name not in defaults
    target.add_argument(*option.flags, **kwargs)


def _options(
    p: argparse.ArgumentParser, command: str, defaults: dict[str, Any] | None = None
) -> None:
    """The options of ``command`` (:data:`~petsc_contact.workflows.options.OPTIONS`): the
    surface's in their group, exclusive ones (the loads) in theirs."""
    d = defaults or {}
    options = options_of(command)
    groups: dict[str, Any] = {}
    for option in options:
        if option.section == "surface" and "surface" not in groups:
            groups["surface"] = p.add_argument_group(SURFACE_GROUP)
        if option.exclusive and option.exclusive not in groups:
            members = [o for o in options if o.exclusive == option.exclusive]
            required = all(o.required and o.name not in d for o in members)
            groups[option.exclusive] = p.add_mutually_exclusive_group(required=required)
        target = groups.get(option.exclusive or option.section, p)
        _argument(target, option, d)
    for option in OPTIONS:
        if command in option.ignored_by:
            _ignored(p, option)


COMMANDS = {  # name: (one-line help, description)
    "plot": (
        "draw a map of a stored field (pressure, gap, contact, heights)",
        "A map of one load step's field over the cell, with physical axes and a colour bar.",
    ),
    "study": (
        "the paper's datasets at the paper's parameters, in resumable pieces",
        "Runs the pieces of the paper's figures and of the datasets beyond them (periodic "
        "sweeps and punches, with the exact stiffness, scalars only) into DATA/FIGURE/ "
        "(fig1, ..., hertz, seeds, punch), skipping complete pieces and "
        "stopping cleanly after --minutes; run it again to go on. Pieces another run is "
        "writing are left to it: start one study per core on the same DATA to share them.",
    ),
    "schema": (
        "print the HDF5 output schema (docs/output-schema.md)",
        "Every dataset the commands write, with its units and description.",
    ),
    "periodic": (
        "periodic, load-controlled contact of a rough surface",
        "Hard-wall contact of a rigid rough surface on a periodic "
        "elastic half-space, one TAO solve per nominal pressure.",
    ),
    "punch": (
        "rigid rough square punch on a free half-space",
        "A rigid punch with a rough face pressed into a "
        "non-periodic elastic half-space (Hockney padding), "
        "displacement (--approaches) or load (--forces) "
        "controlled.",
    ),
    "ensemble": (
        "periodic sweeps over many seeds, with statistics",
        "The periodic scene for each seed (one resumable file "
        "OUT_seedK.h5 per seed), then mean, std and standard "
        "error over seeds of every per-step quantity in OUT.h5. Every seed gets the "
        "same pressures: --sweep N takes its default range from the first seed's surface.",
    ),
    "compare": (
        "error against wall time for several solvers",
        "One periodic scene solved by each solver from first "
        "touch; errors against a tightly converged reference "
        "at every iteration; a table (stdout and OUT.csv), "
        "OUT.h5 and a plot OUT.png.",
    ),
    "experiment": (
        "K(p) from a measured p(s) table (paper Eq. C3)",
        "Interfacial stiffness from a squeeze test of an elastic "
        "block of thickness d and effective modulus E' (paper "
        "Appendix C): K* = dp/ds, K = K*/(1 - K* d/E').",
    ),
    "theory": (
        "Persson's theory and the finite-size p_c from a map's spectrum",
        "What theory predicts for a height map (measured, or generated): the radially "
        "averaged spectrum, Persson's mean gap u(p) and stiffness K(p), the exponential "
        "law's u0 and beta, and the finite-size crossover p_c (paper Eq. 13) with a Hurst "
        "exponent fitted to the spectrum.",
    ),
    "demo": (
        "the default scene (periodic 512^2, H=0.7, slope 0.1)",
        "The default scene: periodic 512 x 512 self-affine "
        "surface, H = 0.7, rms slope 0.1, L/lambda_r = 2, "
        "L/lambda_1 = 64, loads from first contact to ~50% area.",
    ),
}


def _command(sub: Any, name: str) -> argparse.ArgumentParser:
    """The subcommand ``name`` with its help and description from :data:`COMMANDS`."""
    summary, description = COMMANDS[name]
    parser: argparse.ArgumentParser = sub.add_parser(name, help=summary, description=description)
    return parser


class _Parser(argparse.ArgumentParser):
    """Argument errors in one line (what is wrong, where the help is), exit status 2."""

    def error(self, message: str) -> NoReturn:
        """The error in one line, printed by the first rank of an MPI launch only (every
        rank parses the same command line), and exit status 2 on every rank once it is
        printed: the launcher stops every rank when one leaves with an error, which could
        otherwise come before the first rank has said why."""
        from ..conventions.grid import MPIUnavailable, launched, world

        text = f"petsc-contact: error: {message} (see {self.prog} --help)\n"
        if launched("size") == 1:
            self.exit(2, text)
        if launched("rank") == 0:
            sys.stderr.write(text)
            sys.stderr.flush()
        with suppress(MPIUnavailable):  # without mpi4py the ranks cannot wait for each other
            world().Barrier()
        self.exit(2)

    def parse_args(self, args: Any = None, namespace: Any = None) -> Any:
        """The parsed arguments; a deprecated spelling among them is a warning on standard
        error."""
        from .common import say

        parsed = super().parse_args(args, namespace)
        for old, new in vars(parsed).pop(_SPELT, ()):
            say(f"{old} is deprecated: use {new}", "warning")
        for flag, owners in vars(parsed).pop(_IGNORED, ()):
            say(f"{flag} is for {owners} runs; ignored", "warning")
        return parsed


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="petsc-contact",
        description="Non-adhesive contact of rough elastic solids with PETSc/TAO. "
        "Options with one dash (-tao_type bncg, -tao_monitor, -options_file F, "
        "-log_view, ...) are passed to PETSc. The package's own PETSc options: "
        "-petsc_contact_no_j0 (no Fourier initial Hessian for the BQNK types), "
        "-petsc_contact_no_ksp_pc (no Fourier KSP preconditioner for tron, bnls, "
        "bntr, bntl); the default solver's two-level preconditioner: "
        "-petsc_contact_two_level 0 (off), -petsc_contact_two_level_block B (aggregate "
        "block side, pixels; default 16), -petsc_contact_two_level_max_fraction F (largest "
        "contact fraction it is used at; default 0.1); on --device gpu and cpu-array, "
        "-petsc_contact_pc_float32 (the periodic preconditioner's Fourier round trips in "
        "float32, the residual float64; default off).",
        epilog="Exit status: 0 converged, 1 a step did not converge or is not accurate, 2 bad "
        "input or an output "
        "in use, 69 a package cannot be loaded, 74 results cannot be written (disk full, "
        "unwritable), 75 paused, 130 interrupted.",
    )
    parser.add_argument("--version", action="version", version=f"petsc-contact {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in ("periodic", "punch", "ensemble", "compare"):
        _options(_command(sub, name), name)
    _experiment_parser(sub)
    _options(_command(sub, "demo"), "demo", DEMO)
    _plot_parser(sub)
    _study_parser(sub)
    _options(_command(sub, "theory"), "theory")
    _command(sub, "schema")
    return parser


def _study_parser(sub: Any) -> None:
    p = _command(sub, "study")
    p.add_argument(
        "--figure",
        choices=("1", "2", "3", "hertz", "seeds", "punch", "cells", "all"),
        default="all",
        help="the paper's Figs. 1-3, or the datasets beyond them: the Hertz regime, the "
        "distribution over 64 seeds, the punch's periodic and cut faces, the punch's periodic "
        "faces as periodic cells (default all)",
    )
    p.add_argument("--minutes", type=minutes, default=45.0, help="time budget (default 45)")
    p.add_argument(
        "--data",
        help=f"the pieces' folder, made if it is new (default {DEFAULT_DATA}, which must "
        "exist: the repository's root)",
    )
    p.add_argument("--shrink", type=int, default=1, help="divide every grid (a quick look)")
    p.add_argument(
        "--list",
        action="store_true",
        help="print every piece: done, todo or steps kept (13/25), and stop",
    )
    p.add_argument("--quiet", action="store_true", help="no tables")
    for option in options_of("study"):
        _argument(p, option, {})


def _plot_parser(sub: Any) -> None:
    p = _command(sub, "plot")
    p.add_argument(
        "file", metavar="OUT.h5", help="a periodic, punch, ensemble or theory output file"
    )
    p.add_argument(
        "--step",
        type=int,
        default=-1,
        metavar="K",
        help="load step, counted from 1 as the run's table counts (-1, the default: the last)",
    )
    p.add_argument(
        "--field",
        choices=("pressure", "gap", "contact", "heights", "filled", "plastic_displacement"),
        default="pressure",
        help="the map to draw (default pressure; fields need a run with --fields; filled: the "
        "points --fill-undefined filled)",
    )
    p.add_argument(
        "--scale",
        choices=("auto", "linear", "log"),
        default="auto",
        help="colour scale (auto: log for a pressure spanning more than two decades)",
    )
    p.add_argument("--vmin", type=float, metavar="V", help="lower end of the colour scale")
    p.add_argument("--vmax", type=float, metavar="V", help="upper end of the colour scale")
    p.add_argument(
        "--sweep",
        action="store_true",
        help="draw the run's load plot again (what --plot drew; a theory or ensemble file "
        "always gets its plot) instead of a map",
    )
    p.add_argument(
        "--output",
        metavar="PNG",
        help="default: OUT_FIELD_stepK.png for a map, OUT_redrawn.png for a load plot",
    )


def _experiment_parser(sub: Any) -> None:
    exp = _command(sub, "experiment")
    exp.add_argument(
        "--table",
        required=True,
        metavar="FILE",
        help="two columns, comma- or whitespace-separated: nominal pressure p, displacement "
        "s of the block's top (# comments and one header line are skipped)",
    )
    exp.add_argument(
        "--modulus",
        type=float,
        required=True,
        metavar="EPRIME",
        help="effective Young's modulus E' of the block (pressure units)",
    )
    exp.add_argument(
        "--thickness",
        type=float,
        required=True,
        metavar="D",
        help="block thickness d (length units of s)",
    )
    exp.add_argument("--output", required=True, metavar="OUT.h5", help="the table, K* and K (HDF5)")
    exp.add_argument("--plot", metavar="PNG", help="K and K* against p")
    _options(exp, "experiment")
