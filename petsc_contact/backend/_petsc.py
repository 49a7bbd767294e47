"""Initialise PETSc once, with the user's PETSc options, and reach its C library.

petsc4py comes from the venv (``setup.sh`` compiles it against Debian's PETSc and numpy 2)
or from another distribution (conda-forge's).  :func:`init` says in one line why it cannot
be imported, naming a numpy/petsc4py mismatch as such.
"""

from __future__ import annotations

import ctypes
import os
import re
import shlex
import sys
import warnings
from collections.abc import Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager, suppress
from contextvars import ContextVar
from types import ModuleType
from typing import Any, TypeAlias

from ..conventions.warnings import UnusedOptions, user_level

INSTALL_HINT = (
    "on Debian 12 run ./setup.sh (it compiles petsc4py against Debian's PETSc); elsewhere "
    "install petsc4py from conda-forge (README, 'Installing elsewhere')"
)


def _petsc4py() -> ModuleType:
    try:
        import petsc4py
    except ImportError:
        raise ImportError(f"petsc4py is not installed: {INSTALL_HINT}") from None
    return petsc4py


@contextmanager
def _loading() -> Iterator[None]:
    """Turn a failure to load petsc4py's compiled module into one clear ImportError, naming a
    numpy/petsc4py mismatch as such."""
    try:
        yield
    except (ImportError, ValueError, AttributeError) as exc:
        import numpy as np
        import petsc4py

        text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        if "numpy" in text.lower() or "dtype size changed" in text:
            raise ImportError(
                f"petsc4py {petsc4py.__version__} was compiled against another numpy than the "
                f"installed numpy {np.__version__} ({text}): rebuild petsc4py against this "
                f"numpy ({INSTALL_HINT})"
            ) from None
        raise ImportError(f"petsc4py cannot be loaded ({text}): {INSTALL_HINT}") from None


def init(petsc_args: list[str] | None = None) -> ModuleType:
    """Initialise PETSc with command-line style options and return ``petsc4py.PETSc``.

    Parameters
    ----------
    petsc_args
        PETSc options such as ``["-tao_type", "bncg", "-tao_monitor"]``.  They are read by
        ``PetscInitialize`` if PETSc is not initialised yet; otherwise they are inserted into
        the global options database, so that later ``setFromOptions`` calls see them.
    """
    args = list(petsc_args or [])
    if "petsc4py.PETSc" not in sys.modules:
        petsc4py = _petsc4py()
        with _loading():
            petsc4py.init([sys.argv[0] if sys.argv and sys.argv[0] else "petsc-contact"] + args)
            from petsc4py import PETSc
        _python_sigpipe()
        return PETSc
    from petsc4py import PETSc

    if args:
        PETSc.Options().insertString(" ".join(args))
    return PETSc


def _python_sigpipe() -> None:
    """Give SIGPIPE back to Python (ignored: a write to a closed pipe raises
    ``BrokenPipeError``), which PETSc's signal handler takes over and turns into an abort."""
    import signal

    with suppress(ValueError):  # not the main thread: leave it
        signal.signal(signal.SIGPIPE, signal.SIG_IGN)


def library_path() -> str:
    """The ``libpetsc`` shared library petsc4py runs on (whatever its version or scalar type).

    Read from the process's own memory map after PETSc is loaded, so that ctypes calls go to
    the very library petsc4py uses.
    """
    init()
    with open("/proc/self/maps") as maps:
        for line in maps:
            path = line.split()[-1]
            if os.path.basename(path).startswith("libpetsc") and ".so" in path:
                return path
    raise ImportError("the PETSc library petsc4py uses is not mapped in this process")


def petsc() -> ModuleType:
    """Return ``petsc4py.PETSc``, initialising PETSc without options if needed."""
    return init()


def petsc_comm(comm: Any) -> Any:
    """A grid's communicator as petsc4py's ``comm=`` takes it: mpi4py's as it is, PETSc's
    ``COMM_SELF`` for the one-rank stand-in (:class:`~petsc_contact.conventions.grid.OneRank`)."""
    from ..conventions.grid import OneRank

    return petsc().COMM_SELF if isinstance(comm, OneRank) else comm


OptionsArg: TypeAlias = Sequence[str] | str | Mapping[str, Any] | None

_PREFIX: ContextVar[str] = ContextVar("options_prefix", default="")
_OPTION_NAME = re.compile(r"^-[A-Za-z_]")


def is_petsc_option(token: str) -> bool:
    """``-tao_type`` is a PETSc option's name; ``--grid``, ``-h`` and numbers such as
    ``-1e-3`` (an option's value) are not."""
    return token != "-h" and bool(_OPTION_NAME.match(token)) and not token.startswith("--")


def check_prefix(prefix: str) -> str:
    """``prefix`` if it is an options prefix PETSc takes (``a_``: letters, digits and
    underscores, not starting with a digit; ``""`` for none), else ``ValueError``."""
    if prefix and not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", prefix):
        raise ValueError(
            f"an options prefix is letters, digits and underscores, not starting with a digit "
            f"or a dash (as 'a_' for -a_tao_type): got '{prefix}'"
        )
    return prefix


def options_prefix() -> str:
    """The options prefix of the innermost :func:`scoped_options` block (``""`` outside)."""
    return _PREFIX.get()


def options(prefix: str | None = None) -> Any:
    """The options database as a solver with ``prefix`` reads it (default: the block's
    :func:`options_prefix`): ``options().getReal("stiffness_ksp_rtol", ...)`` reads
    ``-a_stiffness_ksp_rtol`` in a block with the prefix ``a_``."""
    return init().Options(options_prefix() if prefix is None else prefix)


def option_list(options: OptionsArg) -> list[str]:
    """PETSc options as a command-line list, from any of the forms the Python API takes.

    ``["-tao_type", "bncg"]``, the string ``"-tao_type bncg"`` and the mapping
    ``{"tao_type": "bncg"}`` (a value of ``None`` or ``True`` gives a bare flag) are the same.
    Raises ``TypeError`` for anything else, and ``ValueError`` for options without a dash.
    """
    if options is None:
        return []
    if isinstance(options, str):
        args = shlex.split(options)
    elif isinstance(options, Mapping):
        args = []
        for key, value in options.items():
            args.append(key if str(key).startswith("-") else f"-{key}")
            if value is not None and value is not True:
                args.append(str(value))
    elif isinstance(options, (list, tuple)) and all(isinstance(o, str) for o in options):
        args = list(options)
    else:
        raise TypeError(
            "options must be a list of strings such as ['-tao_type', 'bncg'], such a string "
            f"or a dict, not {type(options).__name__}"
        )
    if args and not args[0].startswith("-"):
        raise ValueError(f"PETSc options start with a dash: got '{args[0]}'")
    return args


def unused_options(names: Iterable[str] | None = None) -> list[str]:
    """The options in the database (or those of ``names`` in it) that nothing has read."""
    options = init().Options().getAll()
    lib = ctypes.CDLL(library_path())
    lib.PetscOptionsUsed.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.POINTER(ctypes.c_int)]
    unused = []
    for name in options if names is None else names:
        flag = ctypes.c_int(0)
        known = name in options
        if known and lib.PetscOptionsUsed(None, name.encode(), ctypes.byref(flag)) == 0:
            unused += [] if flag.value else [f"-{name}"]
    return sorted(unused)


@contextmanager
def scoped_options(args: OptionsArg, prefix: str = "") -> Iterator[ModuleType]:
    """Insert PETSc options for the duration of a ``with`` block, then restore the database.

    ``args`` are command-line style (``["-tao_type", "bncg", "-options_file", "f.opts"]``),
    or any form :func:`option_list` takes.  Options of the block that nothing read (a
    misspelt ``-tao_typo``) are reported as a warning when it ends.  The block's solvers
    read their options with ``prefix`` (``a_``: ``-a_tao_type``, ``-a_petsc_contact_*``,
    ``-a_stiffness_*``; :func:`options`).
    """
    petsc = init()
    opts = petsc.Options()
    before = opts.getAll()
    given = option_list(args)
    token = _PREFIX.set(check_prefix(prefix))
    if given:
        opts.insertString(" ".join(shlex.quote(a) for a in given))
    try:
        yield petsc
    finally:
        _PREFIX.reset(token)
        mine = [k for k, v in opts.getAll().items() if before.get(k) != v]
        unused = unused_options(mine)
        if unused:
            warnings.warn(
                f"PETSc options never used: {' '.join(unused)}",
                UnusedOptions,
                stacklevel=user_level(),
            )
        for name, value in opts.getAll().items():
            if name not in before:
                opts.delValue(name)
            elif before[name] != value:
                opts.setValue(name, before[name])
