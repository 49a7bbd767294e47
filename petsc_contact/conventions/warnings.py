"""The package's warnings: one class for all, one per kind, and a run's record of them.

Every warning the package gives about an input or a result is a
:class:`PetscContactWarning` (a ``UserWarning``; deprecations of the API are
``DeprecationWarning``, of the command line's behaviour also ``FutureWarning``), so that
``warnings.simplefilter("error", PetscContactWarning)`` turns them all into errors and the
command line prints each as one line.  A run
(:func:`~petsc_contact.workflows.runner.run_contact`) keeps the texts of those about its
result in its result and its file (:func:`recorded`).

A warning is attributed to the first line outside the package (:func:`user_level`): a
script's or notebook's call, not the package's own source; and it names an option as the door
in use spells it (:func:`option`): ``detrend="slope"`` from Python, ``--detrend slope`` from
the command line (within :func:`command_line`).
"""

from __future__ import annotations

import contextlib
import os
import sys
import warnings
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import PurePath
from typing import Any, ClassVar, TextIO

PACKAGE = __name__.split(".")[0]
_FOLDER = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + os.sep
_OURS = (_FOLDER, contextlib.__file__)  # the package, and the exits of its with blocks
_ON_COMMAND_LINE: ContextVar[bool] = ContextVar("on_command_line", default=False)


@contextmanager
def command_line() -> Iterator[None]:
    """Within the block, :func:`option` names options as the command line's flags."""
    token = _ON_COMMAND_LINE.set(True)
    try:
        yield
    finally:
        _ON_COMMAND_LINE.reset(token)


def option(name: str, value: Any = None) -> str:
    """The option ``name`` (a :class:`~petsc_contact.workflows.description.Run` field) set to
    ``value`` (``None``: the option alone), as the door in use spells it: from Python the
    keyword (``detrend="slope"``, ``length``), on the command line (:func:`command_line`) the
    flag (``--detrend slope``, ``--length``, ``--overwrite`` for ``True``; the geometry is
    its command, ``petsc-contact punch``)."""
    if not _ON_COMMAND_LINE.get():
        if value is None:
            return name
        return f'{name}="{value}"' if isinstance(value, str) else f"{name}={value!r}"
    if name == "geometry":
        return f"petsc-contact {value}"
    flag = "--" + name.replace("_", "-")
    return flag if value is None or value is True else f"{flag} {value}"


def user_level() -> int:
    """The ``stacklevel`` that attributes a warning given by the caller of this function to
    the first frame outside the package (and ``contextlib``, through which the package's
    ``with`` blocks end): the line of the script or notebook that called it
    (``warnings.warn(text, Kind, stacklevel=user_level())``; Python 3.11 has no
    ``skip_file_prefixes``)."""
    frame, level = sys._getframe(1), 1
    while frame.f_back is not None and frame.f_code.co_filename.startswith(_OURS):
        frame, level = frame.f_back, level + 1
    return level


class PetscContactWarning(UserWarning):
    """A result the package computed, or an input it took, with a reservation."""

    of_the_result: ClassVar[bool] = True
    """Whether a run records it (:func:`recorded`): not a warning about another file."""


class DoubtfulMap(PetscContactWarning):
    """A measured map that may not be what its user thinks (units, edges, filled heights)."""


class FilledLoad(PetscContactWarning):
    """Much of the load rests on heights that were undefined and filled."""


class ResumeWarning(PetscContactWarning):
    """A resumed run computes again what its files could not give."""


class DoubtfulTable(PetscContactWarning):
    """A measured ``p(s)`` table whose stiffness is undefined at some of its rows."""


class Unconverged(PetscContactWarning):
    """Load steps that did not converge, or whose measured accuracy is beyond the package's:
    they are in the results, flagged ``converged`` or ``accurate`` ``False``."""


def flagged_steps(table: Sequence[Mapping[str, Any]], output: str | None = None) -> list[str]:
    """The :class:`Unconverged` texts of a run's step ``table`` (each step's scalars): one for
    the steps that did not converge, one for those converged but not accurate; none for a
    run whose steps are all good.  ``output`` is named as the file that flags them."""
    failed = [(i, s) for i, s in enumerate(table, 1) if not s["converged"]]
    inaccurate = [
        (i, s) for i, s in enumerate(table, 1) if s["converged"] and not s.get("accurate", True)
    ]
    where = f" in {output}" if output else ""
    texts = []
    for steps, what, flag in (
        (failed, "did NOT converge", "converged"),
        (inaccurate, "are NOT accurate", "accurate"),
    ):
        if steps:
            first, scalars = steps[0]
            texts.append(
                f"{len(steps)} of {len(table)} load steps {what} (first: step {first}, "
                f"{scalars['verification']}); they are flagged {flag} = False{where}"
            )
    return texts


class FullContact(PetscContactWarning):
    """Load steps at or beyond full contact: every pixel in contact, the mean gap 0 whatever
    the load, the interfacial stiffness unbounded (NaN); they are in the results, flagged
    ``full_contact`` ``True``."""


def full_contact_steps(table: Sequence[Mapping[str, Any]], output: str | None = None) -> list[str]:
    """The :class:`FullContact` text of a run's step ``table``: one for its steps at full
    contact, none if it has none.  ``output`` is named as the file that flags them."""
    full = [i for i, s in enumerate(table, 1) if s.get("full_contact", False)]
    if not full:
        return []
    where = f" in {output}" if output else ""
    return [
        f"{len(full)} of {len(table)} load steps are at or beyond full contact (first: step "
        f"{full[0]}, area fraction 1): a larger load changes no contact, and their "
        f"interfacial stiffness is unbounded, NaN; they are flagged full_contact = True{where}"
    ]


def step_warnings(
    table: Sequence[Mapping[str, Any]], output: str | None = None
) -> list[tuple[str, type[PetscContactWarning]]]:
    """What a run says of its flagged steps: the texts of :func:`flagged_steps` and
    :func:`full_contact_steps`, each with its warning's class."""
    return [
        *((text, Unconverged) for text in flagged_steps(table, output)),
        *((text, FullContact) for text in full_contact_steps(table, output)),
    ]


class ReplacedOutput(PetscContactWarning, FutureWarning):
    """A new run's output that replaces an existing file without ``overwrite``: deprecated
    (refused from 0.3.0, as an interrupted run's finished steps already are)."""

    of_the_result = False


class ConvertedLoads(PetscContactWarning):
    """Loads that meant one quantity in the run they came from, given as the equivalent ones
    of another geometry (a periodic sweep's nominal pressures as a punch's ``pressures``)."""


class IdleRanks(PetscContactWarning):
    """A run on more MPI ranks than help: its grid's slabs too thin, or more ranks on a node
    than cores (:func:`~petsc_contact.conventions.resources.rank_excess`); the result is
    the same, only slower."""

    of_the_result = False


class IgnoredOption(PetscContactWarning):
    """An option given to a command that does not use it."""


class UnusedOptions(PetscContactWarning):
    """PETSc options that nothing read (a misspelt name)."""


@contextmanager
def recorded(texts: list[str]) -> Iterator[list[str]]:
    """Within the block, add the text of every package warning to ``texts`` (once each, in
    order), whatever the filters; each is then shown, ignored or raised as the filters in
    force outside the block say (its module the dotted name of the file that warned).

    Parameters
    ----------
    texts
        The list to add to (kept across blocks: a run records its preparation's warnings and
        its steps').

    Yields
    ------
    list of str
        ``texts``.
    """
    outer, shown = list(warnings.filters), warnings.showwarning
    registry: dict[Any, Any] = {}  # "default" and "module" show a text once per block

    def show(
        message: Warning | str,
        category: type[Warning],
        filename: str,
        lineno: int,
        file: TextIO | None = None,
        line: str | None = None,
    ) -> None:
        if not issubclass(category, PetscContactWarning):
            shown(message, category, filename, lineno, file, line)
            return
        if category.of_the_result and str(message) not in texts:
            texts.append(str(message))
        inner = warnings.filters, warnings.showwarning
        warnings.filters, warnings.showwarning = outer, shown  # as if the block were not there
        try:
            warnings.warn_explicit(message, category, filename, lineno, _module(filename), registry)
        finally:
            warnings.filters, warnings.showwarning = inner

    with warnings.catch_warnings():  # restores the filters and showwarning
        warnings.simplefilter("always", PetscContactWarning)
        warnings.showwarning = show
        yield texts


def _module(filename: str) -> str:
    """The dotted name of the package's module ``filename``, as ``warnings.warn`` gives it to
    the filters (another file: its path without ``.py``, as ``warn_explicit`` makes it)."""
    parts = PurePath(filename).with_suffix("").parts
    if PACKAGE not in parts:
        return str(PurePath(*parts))
    return ".".join(parts[len(parts) - 1 - parts[::-1].index(PACKAGE) :])
