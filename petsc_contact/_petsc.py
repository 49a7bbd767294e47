"""Find Debian's petsc4py and initialise PETSc once, with the user's PETSc options.

Debian installs petsc4py below ``$PETSC_DIR/lib/python3/dist-packages`` and only puts it on
``sys.path`` when ``PETSC_DIR`` is set before the interpreter starts.  This module adds the
path itself, so users never set ``PETSC_DIR``.
"""

from __future__ import annotations

import glob
import os
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from types import ModuleType

DEBIAN_PETSC_DIRS = ("/usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real",)


def _petsc_dirs() -> list[str]:
    dirs = [os.environ.get("PETSC_DIR", "")]
    dirs += list(DEBIAN_PETSC_DIRS)
    dirs += sorted(glob.glob("/usr/lib/petscdir/petsc3.*/x86_64-linux-gnu-real"), reverse=True)
    return [d for d in dirs if d]


def _make_importable() -> None:
    try:
        import petsc4py  # noqa: F401

        return
    except ImportError:
        pass
    for d in _petsc_dirs():
        site = os.path.join(d, "lib", "python3", "dist-packages")
        if os.path.isdir(os.path.join(site, "petsc4py")):
            sys.path.append(site)
            os.environ.setdefault("PETSC_DIR", d)
            return
    raise ImportError(
        "petsc4py not found: install Debian's python3-petsc4py (see README, set-up command)"
    )


def init(petsc_args: list[str] | None = None) -> ModuleType:
    """Initialise PETSc with command-line style options and return ``petsc4py.PETSc``.

    Parameters
    ----------
    petsc_args
        PETSc options such as ``["-tao_type", "bncg", "-tao_monitor"]``.  They are read by
        ``PetscInitialize`` if PETSc is not initialised yet; otherwise they are inserted into
        the global options database, so that later ``setFromOptions`` calls see them.
    """
    _make_importable()
    import petsc4py

    args = list(petsc_args or [])
    if "petsc4py.PETSc" not in sys.modules:
        petsc4py.init([sys.argv[0] if sys.argv and sys.argv[0] else "petsc-contact"] + args)
        from petsc4py import PETSc

        return PETSc
    from petsc4py import PETSc

    if args:
        PETSc.Options().insertString(" ".join(args))
    return PETSc


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


@contextmanager
def scoped_options(args: Sequence[str] | None) -> Iterator[ModuleType]:
    """Insert PETSc options for the duration of a ``with`` block, then restore the database.

    ``args`` are command-line style (``["-tao_type", "bncg", "-options_file", "f.opts"]``).
    """
    petsc = init()
    opts = petsc.Options()
    before = opts.getAll()
    if args:
        opts.insertString(" ".join(args))
    try:
        yield petsc
    finally:
        for name, value in opts.getAll().items():
            if name not in before:
                opts.delValue(name)
            elif before[name] != value:
                opts.setValue(name, before[name])
