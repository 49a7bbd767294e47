"""What one solve reports, whichever solver ran it (TAO's names for its reasons), and the
package's accuracy: the measured figures every step records and the limits they are held to.

The accuracy of a step is *measured* on its answer, whatever the options asked for:

- ``kkt_residual``: the natural residual, ``rms(min(k g, p)) / p0`` (periodic) or
  ``rms(min(g, p/k)) / l`` (punch), of the hard-wall conditions ``g >= 0, p >= 0, g p = 0``,
  in the units of TAO's gradient tolerance (docs/formulation.md);
- ``force_balance``: periodic ``|mean(p) - p0| / p0`` of the projected pressure (zero out of
  contact), at most the ``kkt_residual`` when no gap is negative; punch under load control
  ``|F - F_target| / F_target`` (NaN under approach control);
- ``complementarity``: ``sum(p+ g) / (sum(p+) l)``, the force-weighted mean gap in units of
  the problem's length scale ``l`` (``h_rms``; punch: the rms recess), which for a periodic
  step is ``sum(p+ g) / (n p0 h_rms)``;
- ``stiffness_residual``: the residual of the held-set stiffness solve recomputed from its
  answer, in its preconditioner's norm
  (:func:`~petsc_contact.geometries.step.held_set_residual`).

A step is ``accurate`` when each figure is within :data:`ACCURACY_FACTOR` = 100 times the
default tolerance of the solve it measures (:class:`Accuracy`): ``1e-6`` for the first
three (or 100 times the rounding floor, where double precision resolves less than
``1e-8``), ``1e-4`` for the punch's force (Newton's ``1e-6``) and the stiffness (``KSPCG``'s
``1e-6``).  The default solver reaches the tolerance itself; on the stability scenes and the
tests' default runs every figure stayed below a tenth of its limit, ``bqnls`` at its options
file's ``1e-7`` included (docs/solvers.md), where Newton's force stopped within ``6e-6`` on
contacts of a few pixels.  The factor is still four decades below the discretisation error
of the observables: the pixel-quantised contact edges make ``K`` and ``u_bar`` uncertain by
about 1% (docs/performance.md), and a residual of ``1e-6 p0`` moves ``u_bar`` by about
``1e-6`` of itself.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

# TAO's codes of the reasons a solve ends with (petsc4py's ``PETSc.TAO.Reason``), for the
# array path, which runs without petsc4py
REASON_CODES = {
    "CONVERGED_GATOL": 3,
    "CONVERGED_GRTOL": 4,
    "CONVERGED_STEPTOL": 6,
    "DIVERGED_MAXITS": -2,
    "DIVERGED_USER": -8,
}

DEFAULT_GATOL = 1e-8  # the default gradient tolerance of both paths (module docstring)
DEFAULT_MAX_IT = 5000  # the default iteration limit of both paths
STIFFNESS_RTOL = 1e-6  # the stiffness solve's default: K to 2e-8 of a 1e-8 solve (performance.md)
ACCURACY_FACTOR = 100.0  # the accuracy: this many times the default tolerance of each solve
FORCE_ACCURACY = 1e-4  # 100 times the load control's force tolerance, 1e-6
STIFFNESS_ACCURACY = 1e-4  # 100 times the default -stiffness_ksp_rtol, 1e-6


def accuracy_limit(floor: float = 0.0) -> float:
    """The package's accuracy of a solution at a load whose rounding floor is ``floor``:
    ``ACCURACY_FACTOR max(DEFAULT_GATOL, floor)`` (module docstring)."""
    return ACCURACY_FACTOR * max(DEFAULT_GATOL, floor)


@dataclass(frozen=True)
class Accuracy:
    """The largest measured figures of an accurate step (module docstring).

    Attributes
    ----------
    residual
        Of ``kkt_residual`` and ``complementarity`` (:func:`accuracy_limit`); the step
        records it as ``accuracy_limit``.
    force
        Of ``force_balance``: ``residual`` for the periodic contact, which it bounds;
        :data:`FORCE_ACCURACY` for the punch under load control.
    stiffness
        Of ``stiffness_residual``.
    """

    residual: float
    force: float
    stiffness: float = STIFFNESS_ACCURACY

    def reasons(self, scalars: dict[str, Any]) -> list[str]:
        """Each measured figure of a step beyond its limit, in words (NaN, a figure the
        step did not measure, passes)."""
        limits = {
            "kkt_residual": self.residual,
            "force_balance": self.force,
            "complementarity": self.residual,
            "stiffness_residual": self.stiffness,
        }
        return [
            f"{name} {scalars[name]:.2e} > accuracy {limit:.0e}"
            for name, limit in limits.items()
            if scalars.get(name, np.nan) > limit
        ]

    def assess(self, scalars: dict[str, Any]) -> None:
        """Record ``accuracy_limit`` and ``accurate``; a converged step's ``verification``
        says which figures are beyond their limits (``'ok'`` if none), a step that did not
        converge keeps why.  A step assessed again (a figure added) is judged afresh."""
        reasons = self.reasons(scalars)
        scalars["accuracy_limit"] = self.residual
        scalars["accurate"] = not reasons
        if scalars["converged"]:
            scalars["verification"] = "; ".join(reasons) or "ok"


@dataclass
class SolveInfo:
    """What TAO reports for one solve (``reason`` is TAO's name, e.g. ``CONVERGED_GATOL``)."""

    tao_type: str
    reason: str
    reason_code: int
    iterations: int
    objective_gradient_evaluations: int
    hessian_applications: int
    preconditioner_applications: int
    gradient_norm: float
    solve_time: float
    tolerance: float
    relative_tolerance: float = 0.0  # TAO's grtol: gnorm <= grtol |f|
    initial_gradient_norm: float = np.inf  # TAO's gnorm at the start point
    objective: float = np.nan  # TAO's f at the end
    gradient_ratio_tolerance: float = 0.0  # TAO's gttol: gnorm <= gttol gnorm0

    @property
    def effective_tolerance(self) -> float:
        """The gradient tolerance the solve stopped against, as TAO's default test reads its
        tolerances: the largest of ``gatol``, ``grtol |f|`` and ``gttol gnorm0``."""
        bounds = [self.tolerance]
        if self.relative_tolerance > 0 and np.isfinite(self.objective):
            bounds.append(self.relative_tolerance * abs(self.objective))
        if self.gradient_ratio_tolerance > 0 and np.isfinite(self.initial_gradient_norm):
            bounds.append(self.gradient_ratio_tolerance * self.initial_gradient_norm)
        return max(bounds)

    def scalars(self, verdict: str) -> dict[str, Any]:
        """The per-step output columns of this report, with the package's verdict."""
        return {
            "iterations": self.iterations,
            "solve_time": self.solve_time,
            "converged": verdict == "ok",
            "verification": verdict,
            "tao_type": self.tao_type,
            "tao_reason": self.reason,
            "tao_reason_code": self.reason_code,
            "objective_gradient_evaluations": self.objective_gradient_evaluations,
            "hessian_applications": self.hessian_applications,
            "preconditioner_applications": self.preconditioner_applications,
            "gradient_norm": self.gradient_norm,
            "tolerance": self.tolerance,
            "effective_tolerance": self.effective_tolerance,
        }
