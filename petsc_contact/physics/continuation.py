"""Load continuation along a sweep: where the next load step starts, and what it is held by.

A load sweep solves one contact after another.  What the converged steps already know
about the curve ``u_bar(p0)`` shortens the next solve in two ways, neither of which can
change its answer (the solver and its verification decide that):

- **The preconditioner's support.**  The open surface is held by the contact spots with
  the interfacial stiffness ``K = -dp0/du_bar``
  (:func:`~petsc_contact.physics.greens.held_compliance`).
  Its local log-slope ``u0 = -du_bar/d(ln p0) = p0/K`` changes slowly along a sweep (it is
  constant in the exponential regime, paper Eq. 3), so ``K(p0) ~ p0/u0`` with ``u0`` from
  the last step: its exact stiffness if it was computed, else the secant through the last
  two mean gaps.
- **The start.**  The gap is extrapolated linearly in ``ln p0`` through the last two
  converged gaps and projected onto ``g >= 0``: the exponential regime's ``u_bar`` is
  linear in ``ln p0``.  Only interpolation and extrapolation by at most
  :data:`MAX_EXTRAPOLATION` load intervals are used; otherwise the next step starts from
  the last converged gap, as without continuation.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

MAX_EXTRAPOLATION = 2.0  # the farthest secant start, in units of the last ln(p0) interval


@dataclass
class Held:
    """What a sweep holds between its steps beside the field it starts the next from: rows
    of numbers (a periodic sweep's :class:`LoadPath`, a punch's last Newton point) and local
    slabs in the units of that field (the older gap of the path).  A resumed sweep given it
    goes on exactly as the interrupted one would have."""

    scalars: np.ndarray = field(default_factory=lambda: np.empty((0, 3)))
    fields: tuple[np.ndarray, ...] = ()


@dataclass(frozen=True)
class ConvergedStep:
    """What continuation keeps of a converged load step.

    Attributes
    ----------
    pressure
        Nominal pressure ``p0``.
    mean_gap
        ``u_bar`` at ``p0``.
    gap
        The (local, any shape) gap field in the solver's variables.
    stiffness
        Exact ``-dp0/du_bar`` at ``p0``, or ``nan`` when it was not computed.
    """

    pressure: float
    mean_gap: float
    gap: np.ndarray
    stiffness: float = np.nan


class LoadPath:
    """The last two converged steps of a sweep, and what they predict for the next load."""

    def __init__(self, steps: Sequence[ConvergedStep] = ()) -> None:
        self._steps: list[ConvergedStep] = list(steps)[-2:]

    @property
    def steps(self) -> tuple[ConvergedStep, ...]:
        """The converged steps held, oldest first (at most two): what a resumed sweep needs
        to go on exactly as an uninterrupted one (``LoadPath(path.steps)``)."""
        return tuple(self._steps)

    def add(self, step: ConvergedStep) -> None:
        """Record a converged step (the oldest of three is forgotten)."""
        self._steps = (self._steps + [step])[-2:]

    def log_slope(self) -> float | None:
        """``u0 = -du_bar/d(ln p0)`` at the last step, or ``None`` when it is not known."""
        if not self._steps:
            return None
        last = self._steps[-1]
        if np.isfinite(last.stiffness) and last.stiffness > 0:
            return last.pressure / last.stiffness
        if len(self._steps) == 2:
            first = self._steps[0]
            span = np.log(last.pressure / first.pressure)
            if span != 0:
                u0 = -(last.mean_gap - first.mean_gap) / span
                if np.isfinite(u0) and u0 > 0:
                    return float(u0)
        return None

    def stiffness_estimate(self, p0: float) -> float | None:
        """``K(p0) ~ p0/u0`` (the log-slope of the last step), or ``None``."""
        u0 = self.log_slope()
        return None if u0 is None else p0 / u0

    def start(self, p0: float, gap: np.ndarray) -> np.ndarray:
        """The start for ``p0``: the secant in ``ln p0`` through the last two gaps, projected
        onto ``gap >= 0``, or ``gap`` itself when that would extrapolate too far."""
        if len(self._steps) < 2:
            return gap
        first, last = self._steps
        span = np.log(last.pressure / first.pressure)
        t = np.log(p0 / last.pressure) / span if span != 0 else np.nan
        if not (0 < t <= MAX_EXTRAPOLATION):
            return gap
        out = last.gap - first.gap
        out *= t
        out += last.gap
        return np.maximum(out, 0.0, out=out)
