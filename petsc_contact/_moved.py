"""The old import paths of moved modules: each still imports, with a ``DeprecationWarning``
naming its new path, and gives the new module itself (until 0.3.0).

One table, :data:`MOVED`, and one finder on ``sys.meta_path`` (installed when the package is
imported) stand in for the moved files, so that no module's name is kept in two folders.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import warnings
from collections.abc import Sequence
from types import ModuleType

MOVED = {  # old path -> new path, below ``petsc_contact.``
    "conventions.fft": "devices.fft",  # 0.2.0
    "backend.kernels": "numerics.kernels",  # 0.2.0
    "backend.schur": "numerics.schur",  # 0.2.0
    "solver.cg": "solver.constrained_cg",  # 0.2.1
    "workflows.ensemble": "paper.fits",  # 0.2.1
    "workflows.paper_study": "paper.paper_study",  # 0.2.1
    "workflows.predictions": "paper.predictions",  # 0.2.1
    "workflows.redraw": "paper.redraw",  # 0.2.1
    "workflows.scenes": "paper.figures",  # 0.2.1
    "workflows.theory_file": "paper.theory_file",  # 0.2.1
    "workflows.theory_run": "paper.theory_run",  # 0.2.1
    "numerics.device": "devices.device",  # 0.2.1
    "numerics.fft": "devices.fft",  # 0.2.1
    "numerics.passes": "devices.passes",  # 0.2.1
    "numerics.fused": "devices.fused",  # 0.2.1
}
PACKAGE = __name__.rpartition(".")[0]


class MovedModules(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds an old path of :data:`MOVED` and loads it as its new module, with a warning."""

    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        """A spec for an old path, ``None`` for any other name."""
        old = fullname.removeprefix(f"{PACKAGE}.")
        if fullname == old or old not in MOVED:
            return None
        return importlib.machinery.ModuleSpec(fullname, self)

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        """The new module, imported, after the warning that names it."""
        new = f"{PACKAGE}.{MOVED[spec.name.removeprefix(f'{PACKAGE}.')]}"
        warnings.warn(
            f"{spec.name} is deprecated: import {new} (removed in 0.3.0)",
            DeprecationWarning,
            stacklevel=2,
        )
        return importlib.import_module(new)

    def exec_module(self, module: ModuleType) -> None:
        """Nothing: the new module ran when it was imported."""


def install() -> None:
    """Put the finder on ``sys.meta_path``, once."""
    if not any(isinstance(f, MovedModules) for f in sys.meta_path):
        sys.meta_path.append(MovedModules())
