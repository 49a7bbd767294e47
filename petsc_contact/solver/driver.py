"""The array path's solver: the package's constrained CG on a device, without PETSc.

:class:`ArraySolver` is what :class:`~petsc_contact.backend.solve.BoundSolver` is on the PETSc
path: ``solve(objective_gradient, start, ...)`` runs one load step and returns the solution
with a :class:`~petsc_contact.solver.report.SolveInfo`.  It runs
:class:`~petsc_contact.solver.constrained_cg.ConstrainedCG` with the problem's Hessian and
preconditioner on the arrays of a :class:`~petsc_contact.devices.device.Device` (``gpu``, or its
CPU stand-in ``cpu-array``), its sums and minima over the grid's ranks.

Its options are PETSc's names for what it reads (:class:`SolveSettings`), so a command line
keeps its meaning on every device; any other option is refused in one line rather than
ignored.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ..conventions.grid import Grid
from ..devices.device import Device
from .constrained_cg import (
    MONITOR,
    ONE_RANK,
    USER,
    ConstrainedCG,
    ContactPreconditioner,
    Reductions,
    ToleranceTest,
)
from .report import DEFAULT_GATOL, DEFAULT_MAX_IT, REASON_CODES, STIFFNESS_RTOL, SolveInfo

TYPE_NAME = "cg"  # the algorithm, as the PETSc path records it (backend.solve.PACKAGE_SOLVERS)


def _flag(value: str | None) -> bool:
    if value is None or value.lower() in ("1", "true", "yes", "on"):
        return True
    if value.lower() in ("0", "false", "no", "off"):
        return False
    raise ValueError(f"not a true/false value: {value}")


@dataclass(frozen=True)
class SolveSettings:
    """One solve's settings, parsed once from the run's options (PETSc's names, PETSc's
    defaults): all of them on the array path (:meth:`from_options`); on the PETSc path the
    package's own (the two-level form's, the stiffness solve's tolerance), read at PETSc's
    edge (:class:`~petsc_contact.backend.tao.PetscBackend`), TAO reading its own.

    Attributes
    ----------
    gatol, grtol, max_it
        ``-tao_gatol``, ``-tao_grtol``, ``-tao_max_it``, tested as TAO tests them
        (:class:`~petsc_contact.solver.constrained_cg.ToleranceTest`).
    monitor
        ``-tao_monitor``: a line per iteration.
    two_level, block, max_fraction
        ``-petsc_contact_two_level``, ``-petsc_contact_two_level_block`` and
        ``-petsc_contact_two_level_max_fraction`` (the preconditioner's two-level form).
    stiffness_rtol, stiffness_max_it
        ``-stiffness_ksp_rtol``, ``-stiffness_ksp_max_it`` (the held-set stiffness solve).
    pc_float32
        ``-petsc_contact_pc_float32``: the periodic contact's preconditioner makes its
        Fourier round trips in ``float32``, the residual staying ``float64`` (the array path
        on one rank; :class:`~petsc_contact.backend.preconditioner.MeanModePreconditioner`).
        Off by default.
    """

    gatol: float = DEFAULT_GATOL
    grtol: float = 0.0
    max_it: int = DEFAULT_MAX_IT
    monitor: bool = False
    two_level: bool = True
    block: int | None = None
    max_fraction: float | None = None
    stiffness_rtol: float = STIFFNESS_RTOL
    stiffness_max_it: int = 0
    pc_float32: bool = False

    READS: ClassVar[dict[str, tuple[str, Callable[[Any], Any]]]] = {
        "tao_gatol": ("gatol", float),
        "tao_grtol": ("grtol", float),
        "tao_max_it": ("max_it", int),
        "tao_monitor": ("monitor", _flag),
        "petsc_contact_two_level": ("two_level", _flag),
        "petsc_contact_two_level_block": ("block", int),
        "petsc_contact_two_level_max_fraction": ("max_fraction", float),
        "stiffness_ksp_rtol": ("stiffness_rtol", float),
        "stiffness_ksp_max_it": ("stiffness_max_it", int),
        "petsc_contact_pc_float32": ("pc_float32", _flag),
    }

    @classmethod
    def from_options(cls, options: Sequence[str], device: str, prefix: str = "") -> SolveSettings:
        """Parse ``["-tao_gatol", "1e-10", "-tao_monitor", ...]``; ``ValueError`` in one line
        for an option the array path does not read (``-tao_type`` among them).  With a
        ``prefix`` (``a_``) only the options that carry it are read (``-a_tao_gatol``), as
        PETSc's solvers with that prefix read theirs; the others are not the run's."""
        values: dict[str, Any] = {}
        items = _prefixed(list(options), prefix) if prefix else list(options)
        i = 0
        while i < len(items):
            name = items[i]
            if not name.startswith("-") or len(name) < 2:
                raise ValueError(f"--device {device}: expected a PETSc option, not '{name}'")
            key = name.lstrip("-")
            value = None
            if i + 1 < len(items) and not _is_option(items[i + 1]):
                value = items[i + 1]
                i += 1
            i += 1
            if key == "tao_type" or key.startswith("tao_python"):
                raise ValueError(
                    f"--device {device} runs the package's own solver: {name} needs --device cpu"
                )
            if key not in cls.READS:
                known = ", ".join(f"-{k}" for k in cls.READS)
                raise ValueError(f"--device {device} does not read {name} (it reads {known})")
            field, kind = cls.READS[key]
            try:
                values[field] = kind(value) if value is not None or kind is _flag else None
            except ValueError:
                raise ValueError(f"{name}: cannot read '{value}'") from None
            if values[field] is None:
                raise ValueError(f"{name} needs a value")
        settings = cls(**values)
        if settings.block is not None and settings.block < 1:
            block = settings.block
            raise ValueError(f"-petsc_contact_two_level_block must be positive, not {block}")
        return settings


def __getattr__(name: str) -> Any:
    """``ArraySettings``, deprecated (a ``DeprecationWarning``): :class:`SolveSettings`."""
    if name == "ArraySettings":
        warnings.warn(
            "solver.driver.ArraySettings is deprecated; use solver.driver.SolveSettings",
            DeprecationWarning,
            stacklevel=2,
        )
        return SolveSettings
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


PETSC_WORDS = ("default", "petsc_default", "decide", "petsc_decide", "determine",
               "petsc_determine", "unlimited", "petsc_unlimited")  # fmt: skip
"""Words PETSc takes for a number option's value, whatever its case."""


def check_option_values(options: Sequence[str]) -> None:
    """``ValueError`` in one line where an option whose type the package knows (a number of
    :attr:`SolveSettings.READS`, with any prefix: ``-a_tao_max_it``, ``-bncg_tao_gatol``) has
    a value that is not one (``-tao_max_it abc``): said before PETSc reads it mid-run."""
    numbers = {key: kind for key, (_, kind) in SolveSettings.READS.items() if kind is not _flag}
    for i, name in enumerate(options):
        value = options[i + 1] if i + 1 < len(options) else None
        key = name.lstrip("-") if _is_option(name) else ""
        known = next((k for k in numbers if key == k or key.endswith("_" + k)), None)
        if known is None or value is None or _is_option(value):
            continue
        if value.lower() not in PETSC_WORDS and not _reads_as(value, numbers[known]):
            what = "a whole number" if numbers[known] is int else "a number"
            raise ValueError(f"{name} takes {what}, not '{value}'")


def _reads_as(value: str, kind: Callable[[Any], Any]) -> bool:
    """Whether ``value`` is a number of ``kind`` (``int``: digits alone, as PETSc reads it)."""
    try:
        kind(value)
    except ValueError:
        return False
    return True


def _prefixed(items: list[str], prefix: str) -> list[str]:
    """The options of ``items`` that carry ``prefix`` (with their values), the prefix taken
    off: ``-a_tao_gatol 1e-9`` is ``-tao_gatol 1e-9`` for the prefix ``a_``."""
    out: list[str] = []
    mine = False
    for item in items:
        if _is_option(item):
            mine = item.lstrip("-").startswith(prefix)
            if mine:
                out.append("-" + item.lstrip("-").removeprefix(prefix))
        elif mine:
            out.append(item)
    return out


def _is_option(text: str) -> bool:
    """Whether ``text`` names an option (``-x``), not a value (``-1e-3``)."""
    if not text.startswith("-"):
        return False
    try:
        float(text)
    except ValueError:
        return True
    return False


class ArraySolver:
    """One load step after another with the constrained CG on a device (module docstring).

    Parameters
    ----------
    hessian
        The scaled Hessian (a :class:`~petsc_contact.solver.constrained_cg.SplitHessian` with
        ``applications``).
    preconditioner
        Its approximate inverse (``apply_array``; a
        :class:`~petsc_contact.solver.constrained_cg.ContactPreconditioner` follows the free set).
    device
        Where the arrays live.
    settings
        Tolerances and the monitor.
    grid
        The grid whose communicator the CG's sums and minima go over (its ranks each hold a
        slab of the unknowns); ``None``: one rank.
    """

    def __init__(
        self,
        hessian: Any,
        preconditioner: Any,
        device: Device,
        settings: SolveSettings,
        grid: Grid | None = None,
    ) -> None:
        self.hessian, self.preconditioner = hessian, preconditioner
        self.device, self.settings = device, settings
        self.reduce = ONE_RANK if grid is None else Reductions.over(grid)

    def __enter__(self) -> ArraySolver:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Nothing to destroy (the arrays go with their owners); as ``BoundSolver.close``."""

    def solve(
        self,
        objgrad: Callable[[Any, Any], float],
        x0: Any,
        lower: float = 0.0,
        monitor: Callable[[int, float, float], object] | None = None,
        upper: Any = None,
        gatol_floor: float = 0.0,
    ) -> tuple[Any, SolveInfo]:
        """Run the CG from ``x0``; the solution (an array of the device) and its report.

        The arguments mean what they mean for
        :meth:`~petsc_contact.backend.solve.BoundSolver.solve`.
        """
        device, settings = self.device, self.settings
        x = device.asarray(x0, dtype=float).reshape(-1).copy()
        gatol = max(settings.gatol, gatol_floor)
        watch = _Watch(objgrad, monitor, settings.monitor)
        pre = self.preconditioner
        before = (self.hessian.applications, pre.applications)
        device.synchronize()
        start = time.perf_counter()
        cg = ConstrainedCG(
            x,
            lower,
            np.inf if upper is None else device.asarray(upper).reshape(-1),
            watch.gradient,
            self.hessian,
            pre.apply_array,
            pre if isinstance(pre, ContactPreconditioner) else None,
            ToleranceTest(gatol, settings.grtol, settings.max_it, watch),
            device.passes,
            lambda: device.xp.empty_like(x),
            self.reduce,
            int(self.reduce.sum(x.size)[0]),
        )
        outcome = cg.run()
        device.synchronize()
        elapsed = time.perf_counter() - start
        return x, self._report(cg, outcome, watch, elapsed, gatol, before)

    def _report(
        self,
        cg: ConstrainedCG,
        outcome: Any,
        watch: _Watch,
        elapsed: float,
        gatol: float,
        before: tuple[int, int],
    ) -> SolveInfo:
        """What a solve reports, as ``BoundSolver`` reports it: ``before`` are the Hessian's
        and the preconditioner's applications at its start."""
        reason = USER if outcome.reason == MONITOR else outcome.reason
        return SolveInfo(
            tao_type=TYPE_NAME,
            reason=reason,
            reason_code=REASON_CODES[reason],
            iterations=outcome.iterations,
            objective_gradient_evaluations=watch.evaluations,
            hessian_applications=self.hessian.applications - before[0],
            preconditioner_applications=self.preconditioner.applications - before[1],
            gradient_norm=outcome.residual,
            solve_time=elapsed,
            tolerance=float(gatol),
            relative_tolerance=float(self.settings.grtol),
            initial_gradient_norm=np.inf if watch.first is None else watch.first,
            objective=float(watch.last),
        )


class _Watch:
    """What a solve counts as it goes: the objective-gradient evaluations, the first
    iteration's residual norm and the last objective; each iteration goes on to the caller's
    ``monitor`` (and is printed when ``show``, as ``-tao_monitor`` prints TAO's)."""

    def __init__(
        self,
        objgrad: Callable[[Any, Any], float],
        monitor: Callable[[int, float, float], object] | None,
        show: bool,
    ) -> None:
        self.objgrad, self.monitor, self.show = objgrad, monitor, show
        self.evaluations = 0
        self.first: float | None = None
        self.last = np.nan

    def gradient(self, x: Any, g: Any) -> float:
        """The objective at ``x``, its gradient into ``g``, counted."""
        self.evaluations += 1
        return self.objgrad(x, g)

    def __call__(self, it: int, f: float, rnorm: float) -> bool:
        if self.first is None:
            self.first = rnorm
        self.last = f
        if self.show:
            print(f"{it:4d} TAO,  Function value: {f:g},  Residual: {rnorm:g}", flush=True)
        return bool(self.monitor is not None and self.monitor(it, f, rnorm))
