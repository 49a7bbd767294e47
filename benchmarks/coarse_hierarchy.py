"""Cold steps with a coarse space of fixed blocks and no cap, its system solved iteratively
through a third level: a measurement of the hierarchy's iterations, not a solver kept.

usage: .venv/bin/python benchmarks/coarse_hierarchy.py [--block 8] [--inner 3] [--tol 0]
       [--inflation 0] [--flexible] [COLD_STEPS ARGUMENTS] [-- PETSC OPTIONS]

Runs :mod:`cold_steps` (its arguments, table and counts) with the two-level form's coarse
space replaced, at each build, by :class:`Hierarchy`: the reactions piecewise constant on the
contact pixels of ``b x b`` blocks (``--block``, never grown), the bordered coarse system
``[[E, w], [w^T, 0]]`` solved as ``a = y - c x`` with ``E y = f`` by ``--inner`` conjugate
gradient steps (or fewer, where the residual falls below ``--tol`` relative) and
``x = E^-1 w`` to ``1e-12`` once per build.  ``E = W^T G_BB W``, its diagonal raised by
``--inflation`` (relative, as the capped form's by its ``DIAGONAL_INFLATION``), is applied
exactly, by one FFT round trip on the grid per inner step (counted in the table's "trips");
a lattice form would apply it on the ``(n/b)^2`` block lattice.  The inner steps are
preconditioned additively by ``E``'s diagonal (exact, pixel pair sums) and a third level:
the coarse space of the capped form (:class:`~petsc_contact.backend.coarse.CoarseSpace`, its
dense factor) on blocks of side a multiple of ``b``, the smallest that keeps at most
``coarse_limit`` of them, so that its aggregates are unions of the second level's.  A fixed
count of inner steps makes the preconditioner a (slightly) different operator at each
application: the outer CG's beta is the solver's own, or with ``--flexible``
Polak-Ribiere's (:func:`flexible`).  One rank, the ``cpu`` device.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import cold_steps

from petsc_contact.backend import preconditioner
from petsc_contact.backend.coarse import CoarseSpace, block_of, near_corner, whole_aggregates
from petsc_contact.backend.operator import FourierOperator
from petsc_contact.numerics.aggregates import pair_sums_direct
from petsc_contact.solver.constrained_cg import ConstrainedCG

INNER = {"steps": 0, "solves": 0}  # inner CG steps and coarse solves, over the run


class Hierarchy(CoarseSpace):
    """The coarse space of fixed ``block`` aggregates of the bound set of ``free``, solved by
    ``inner = (steps, tol)``: at most ``steps`` preconditioned CG steps, fewer where the
    residual falls below ``tol`` relative (module docstring)."""

    def __init__(
        self,
        pre: preconditioner.MeanModePreconditioner,
        free: np.ndarray,
        block: int,
        inner: tuple[int, float],
        inflation: float,
    ) -> None:
        self.grid, self.device, self.pre, self.inner = pre.grid, pre.device, pre, inner
        quarter = np.ascontiguousarray(pre._exact_compliance(), dtype=float)
        bound = (~free).reshape(self.grid.local_shape)
        self.local = np.flatnonzero(bound.ravel())
        rows, cols = np.divmod(self.local, self.grid.shape[1])
        parts, self.labels = whole_aggregates(rows, cols, self.grid.shape, block, 2**62)
        self.block, self.size, self.weights = block, len(parts.ids), parts.sizes
        near = near_corner(quarter, self.grid, 2 * block)
        pairs = np.repeat(np.arange(self.size, dtype=np.int64)[:, None], 2, axis=1)
        self.raised = inflation  # E's diagonal raised by this (relative), as the capped form's
        self.diagonal = pair_sums_direct(
            parts.rows, parts.cols, parts.starts, pairs, near, *self.grid.shape
        )
        limit, side = preconditioner.coarse_limit(self.grid.size), block
        while np.unique(block_of(rows, cols, self.grid.shape[1], side)).size > limit:
            side += block
        self.third = CoarseSpace(self.grid, quarter, bound, side, limit, self.device)
        self.up = np.empty(self.size, dtype=np.int64)
        self.up[self.labels] = self.third.labels  # each aggregate's third-level aggregate
        self.factorised = self.third.factorised
        self.e_w = self.cg(self.weights, 10**4, 1e-12)

    def apply_e(self, a: np.ndarray) -> np.ndarray:
        """``E a = W^T G_BB W a``, its diagonal raised: one FFT round trip on the grid."""
        spread, response = self.pre.work_fields()
        spread[self.local] = a[self.labels]
        shape = self.grid.local_shape
        FourierOperator.apply_array(self.pre, spread.reshape(shape), response.reshape(shape))
        spread[self.local] = 0.0
        e_a = np.bincount(self.labels, weights=response[self.local], minlength=self.size)
        return e_a + self.raised * self.diagonal * a

    def smooth(self, v: np.ndarray) -> np.ndarray:
        """The inner preconditioner: ``D^-1 v + P E_3^-1 P^T v``."""
        v3 = np.bincount(self.up, weights=v, minlength=self.third.size)
        assert self.third.system.factor is not None
        y3 = self.device.cho_solve(self.third.system.factor, v3)
        return v / ((1.0 + self.raised) * self.diagonal) + y3[self.up]

    def cg(self, f: np.ndarray, steps: int, tol: float) -> np.ndarray:
        """At most ``steps`` preconditioned CG steps on ``E y = f`` from zero."""
        y, r = np.zeros_like(f), f.copy()
        z = self.smooth(r)
        d, rz, norm = z.copy(), float(r @ z), float(np.sqrt(f @ f))
        for _ in range(steps):
            q = self.apply_e(d)
            alpha = rz / float(d @ q)
            y += alpha * d
            r -= alpha * q
            INNER["steps"] += 1
            if np.sqrt(r @ r) <= tol * norm:
                break
            z = self.smooth(r)
            rz, rz_old = float(r @ z), rz
            d = z + (rz / rz_old) * d
        return y

    def solve(self, g_r: np.ndarray, r_sum: float) -> tuple[np.ndarray, float]:
        f = np.bincount(self.labels, weights=-g_r.reshape(-1)[self.local], minlength=self.size)
        y = self.cg(f, *self.inner)
        INNER["solves"] += 1
        c = (float(self.weights @ y) + r_sum) / float(self.weights @ self.e_w)
        return (y - c * self.e_w)[self.labels], c


def flexible() -> None:
    """Make the CG's beta Polak-Ribiere, ``z.(r - r_old)/(z_old.r_old)`` (floored at zero),
    while a :class:`Hierarchy` is in use: ``rz_old`` is scaled so that the solver's own
    ``rz/rz_old`` is that beta, and each direction's residual kept."""
    direction = ConstrainedCG._direction

    def flexible_direction(cg: ConstrainedCG, rr: float, bound_count: int) -> int:
        apply, last = cg.preconditioner, getattr(cg, "r_old", None)
        assert apply is not None

        def polak_ribiere(r: np.ndarray, z: np.ndarray) -> None:
            residual = r.copy()  # the CG preconditions in place (z is r)
            cg.r_old = residual  # type: ignore[attr-defined]
            apply(r, z)
            if not isinstance(getattr(cg.contact, "correction", None), Hierarchy):
                return
            if last is not None and cg.rz_old > 0:
                rz, z_last = cg.allsum(
                    cg.passes.restrict_dot(z, cg.free, residual), float(np.dot(z, last))
                )
                cg.rz_old *= rz / (rz - z_last) if rz > z_last else np.inf

        cg.preconditioner = polak_ribiere
        try:
            return direction(cg, rr, bound_count)
        finally:
            cg.preconditioner = apply

    ConstrainedCG._direction = flexible_direction  # type: ignore[method-assign]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, add_help=False)
    parser.add_argument("--block", type=int, default=8)
    parser.add_argument("--inner", type=int, default=3)
    parser.add_argument("--tol", type=float, default=0.0)
    parser.add_argument("--flexible", action="store_true", help="a Polak-Ribiere beta")
    parser.add_argument("--inflation", type=float, default=0.0, help="E's diagonal raised")
    args, rest = parser.parse_known_args()
    if args.flexible:
        flexible()

    def build(pre: preconditioner.MeanModePreconditioner, free: np.ndarray) -> bool:
        hierarchy = Hierarchy(pre, free, args.block, (args.inner, args.tol), args.inflation)
        if not hierarchy.factorised:
            return False
        pre.correction, pre._built_free = hierarchy, free.copy()
        pre.builds += 1
        return True

    preconditioner.MeanModePreconditioner._build = build  # type: ignore[method-assign]
    sys.argv = [sys.argv[0], *rest]
    cold_steps.main()
    print(f"inner steps: {INNER['steps']} over {INNER['solves']} coarse solves")


if __name__ == "__main__":
    main()
