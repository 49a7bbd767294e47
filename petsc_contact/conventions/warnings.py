"""The package's warnings: one class for all, one per kind, and a run's record of them.

Every warning the package gives about an input or a result is a
:class:`PetscContactWarning` (a ``UserWarning``; deprecations of the API are
``DeprecationWarning``, of the command line's behaviour also ``FutureWarning``), so that
``warnings.simplefilter("error", PetscContactWarning)`` turns them all into errors and the
command line prints each as one line.  A run
(:func:`~petsc_contact.workflows.runner.run_contact`) keeps the texts of those about its
result in its result and its file (:func:`recorded`).
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import PurePath
from typing import Any, ClassVar, TextIO

PACKAGE = __name__.split(".")[0]


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


class ReplacedOutput(PetscContactWarning, FutureWarning):
    """A new run's output that replaces an existing file without ``overwrite``: deprecated
    (refused from 0.3.0, as an interrupted run's finished steps already are)."""

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
