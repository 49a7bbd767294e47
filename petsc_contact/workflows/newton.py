"""Safeguarded Newton iterations on a load's control variable, written once for both
geometries: the punch reaches a force by Newton on its approach
(:mod:`~petsc_contact.workflows.punch_steps`), the periodic cell a mean gap by Newton on
``-ln p0`` (:mod:`~petsc_contact.workflows.periodic_steps`).

Each looks for ``x`` with ``value(x) = target`` for an increasing ``value``, whose exact
derivative every solve gives (the stiffness with the contact set held fixed).  A
:class:`Bracket` keeps the interval the root lies in and turns Newton's step into a
bisection when it leaves it; :func:`newton` runs the solves.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..geometries.step import Step

MAX_NEWTON = 60


@dataclass
class Bracket:
    """Where the root of ``value(x) = target`` (``value`` increasing) lies: above ``lo``,
    where the value is below the target, and at or below ``hi``.

    Attributes
    ----------
    target
        The value sought.
    lo, hi
        The bracket (``hi`` infinite while no ``x`` above the root is known).
    beyond
        The next ``x`` from ``lo`` while ``hi`` is infinite and Newton's step fails.
    ceiling
        The largest ``x`` that may be tried (a root above it is out of reach).
    """

    target: float
    lo: float
    hi: float
    beyond: Callable[[float], float]
    ceiling: float = np.inf

    def start(self, default: float, last: tuple[float, float, float] | None) -> float:
        """The first ``x``, at most :attr:`ceiling`: the tangent at ``last`` (``x``, value,
        slope of a converged solve), which narrows the bracket, else ``default``."""
        if last is None:
            return min(default, self.ceiling)
        x0, v0, k0 = last
        if v0 < self.target:
            self.lo = x0
        else:
            self.hi = x0
        return min(x0 + (self.target - v0) / k0 if k0 > 0 else default, self.ceiling)

    def next(self, x: float, value: float, slope: float) -> float | None:
        """Newton's next ``x`` from ``x`` (its ``value`` and ``slope``), bisected in the
        bracket (or :attr:`beyond` ``lo`` while no ``x`` above the root is known) when Newton
        leaves it, at most :attr:`ceiling`; ``None`` when the root lies above the ceiling."""
        if value < self.target:
            self.lo = x
            if x >= self.ceiling:
                return None
        else:
            self.hi = x
        guess = x + (self.target - value) / slope if slope > 0 else np.inf
        if not self.lo < guess < self.hi:
            guess = self.beyond(self.lo) if not np.isfinite(self.hi) else 0.5 * (self.lo + self.hi)
        return min(guess, self.ceiling)


@dataclass
class NewtonEnd:
    """How :func:`newton` ended: the last step, the Newton steps taken and the solver's
    iterations and solve time summed over them all."""

    step: Step
    count: int
    iterations: int
    solve_time: float


def newton(
    bracket: Bracket,
    x: float,
    solve: Callable[[float], Step],
    point: Callable[[dict[str, Any]], tuple[float, float]],
    rtol: float,
    what: str,
    out_of_reach: str = "",
    scale: float | None = None,
) -> NewtonEnd:
    """Safeguarded Newton's steps from ``x`` toward ``bracket.target``: ``solve(x)`` a step,
    ``point(scalars)`` its value and exact slope.

    It stops on the target (``|value - target| <= rtol scale``, ``scale`` by default
    ``|target|``), at a step that did not converge, or when a solve accepts its warm start at
    a new ``x`` without an iteration (it cannot tell the two apart: the value is as close as
    the solve resolves) unless the value lies above the target with no slope (a hardness cap
    with every pixel at it: the same answer at every ``x`` there, bisected down).  A step
    that stops for another reason is made not converged, saying why: ``what`` not reached in
    :data:`MAX_NEWTON` steps, or the root above the bracket's ceiling (``out_of_reach``)."""
    tolerance = rtol * (abs(bracket.target) if scale is None else scale)
    iterations, solve_time = 0, 0.0
    for count in range(1, MAX_NEWTON + 1):
        step = solve(x)
        s = step.scalars
        iterations += s["iterations"]
        solve_time += s["solve_time"]
        if not step.converged:
            break
        value, slope = point(s)
        if abs(value - bracket.target) <= tolerance:
            break
        if count > 1 and s["iterations"] == 0 and not (slope == 0 and value > bracket.target):
            break  # as close as the solve resolves (not: past a flat top, every pixel capped)
        following = bracket.next(x, value, slope)
        if following is None:
            s["converged"] = False
            s["verification"] = f"{what} {bracket.target:.6g} out of reach: {out_of_reach}"
            break
        x = following
    else:
        s["converged"] = False
        s["verification"] = f"{what} not reached in {MAX_NEWTON} Newton steps"
    return NewtonEnd(step, count, iterations, solve_time)


def check_reached(
    scalars: dict[str, Any], value: float, target: float, within: float, why: str
) -> None:
    """A converged step whose ``value`` is further than ``within`` from its ``target`` made
    not converged, saying why (``why``)."""
    if scalars["converged"] and abs(value - target) > within:
        scalars["converged"] = False
        scalars["verification"] = why
