"""The package's module paths before it was arranged in layer folders, kept importable.

``import petsc_contact.surface`` (or ``from petsc_contact.problem import PeriodicProblem``)
still works and warns once with a ``DeprecationWarning`` that names the new path.  The old
module is a stand-in that looks each name up in the new module(s); ``petsc_contact.punch``
was split into the geometry and its sweep, so its stand-in looks in both.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import types
import warnings
from collections.abc import Sequence
from typing import Any

MOVED: dict[str, tuple[str, ...]] = {
    "validation": ("conventions.validation",),
    "units": ("conventions.units",),
    "grid": ("conventions.grid",),
    "fft": ("conventions.fft",),
    "theory": ("physics.theory",),
    "greens": ("physics.greens",),
    "surface": ("physics.surface",),
    "observables": ("physics.observables",),
    "continuation": ("physics.continuation",),
    "preparation": ("physics.preparation",),
    "_petsc": ("backend._petsc",),
    "operator": ("backend.operator",),
    "schur": ("backend.schur",),
    "solve": ("backend.solve",),
    "cg": ("backend.cg",),
    "stiffness": ("backend.stiffness",),
    "kernels": ("backend.kernels",),
    "output": ("io.output",),
    "plot": ("io.plot",),
    "topography": ("io.topography",),
    "step": ("geometries.step",),
    "problem": ("geometries.periodic",),
    "punch": ("geometries.punch", "workflows.punch_sweep"),
    "periodic": ("workflows.periodic_sweep",),
    "compare": ("workflows.compare",),
    "ensemble": ("workflows.ensemble",),
    "scenes": ("workflows.scenes",),
    "predictions": ("workflows.predictions",),
    "paper_study": ("workflows.paper_study",),
}
PACKAGE = __name__.rpartition(".")[0]


def _stand_in(name: str, targets: Sequence[str]) -> types.ModuleType:
    """A module whose attributes are those of ``targets`` (looked up in order)."""
    module = types.ModuleType(name, f"Deprecated: moved to {', '.join(targets)}.")

    def __getattr__(attribute: str) -> Any:
        for target in targets:
            new = importlib.import_module(target)
            if hasattr(new, attribute):
                return getattr(new, attribute)
        raise AttributeError(f"module {name!r} has no attribute {attribute!r}")

    def __dir__() -> list[str]:
        return sorted({a for t in targets for a in dir(importlib.import_module(t))})

    module.__getattr__ = __getattr__  # type: ignore[method-assign]
    module.__dir__ = __dir__  # type: ignore[method-assign]
    return module


class _OldPaths(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds ``petsc_contact.<old>`` and loads its stand-in, with the warning."""

    def find_spec(
        self, fullname: str, path: Any = None, target: Any = None
    ) -> importlib.machinery.ModuleSpec | None:
        package, _, old = fullname.rpartition(".")
        if package != PACKAGE or old not in MOVED:
            return None
        return importlib.machinery.ModuleSpec(fullname, self)

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        targets = [f"{PACKAGE}.{t}" for t in MOVED[spec.name.rpartition(".")[2]]]
        warnings.warn(
            f"{spec.name} is deprecated: import from {' and '.join(targets)}",
            DeprecationWarning,
            stacklevel=2,
        )
        return _stand_in(spec.name, targets)

    def exec_module(self, module: types.ModuleType) -> None:
        """Nothing to run: the stand-in is complete when created."""


def old_attribute(name: str) -> types.ModuleType:
    """``petsc_contact.<old>`` as an attribute of the package (its module ``__getattr__``), as
    ``import petsc_contact; petsc_contact.grid.Grid`` worked before the folders."""
    if name not in MOVED:
        raise AttributeError(f"module {PACKAGE!r} has no attribute {name!r}")
    return importlib.import_module(f"{PACKAGE}.{name}")


def install() -> None:
    """Make the old paths importable (once per process)."""
    if not any(isinstance(f, _OldPaths) for f in sys.meta_path):
        sys.meta_path.append(_OldPaths())
