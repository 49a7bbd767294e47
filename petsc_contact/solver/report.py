"""What one solve reports, whichever solver ran it (TAO's names for its reasons)."""

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
    relative_tolerance: float = 0.0  # TAO's grtol
    initial_gradient_norm: float = np.inf  # TAO's gnorm at the start point

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
        }
