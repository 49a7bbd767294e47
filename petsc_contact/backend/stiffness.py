"""Exact incremental stiffness at a converged contact state (Barber 2003).

With the contact set held fixed, a small load change is a *linear* problem: one conjugate
gradient solve restricted to a set of pixels, with no finite-difference noise.

- Periodic, load controlled: open pixels ``F`` carry no pressure, so ``K_FF dg = -dp0 1``
  and ``K = -dp0/du_bar = 1 / mean(y)`` with ``K_FF y = 1_F`` (``K`` the periodic
  stiffness; per apparent area, pressure over length).
- Punch, displacement controlled: contact pixels ``C`` keep zero gap, so ``G_CC dp = dδ 1``
  and ``dF/dδ = a^2 sum(y)`` with ``G_CC y = 1_C`` (``G`` the padded compliance).

The restricted operator ``P A P + (I - P)`` and preconditioner ``P M P + (I - P)`` are
Python ``Mat``/``PC`` objects solved by PETSc's ``KSPCG`` (:func:`restricted_solve`).  On the
array devices (``gpu``, ``cpu-array``) the geometries hand :func:`periodic_stiffness_exact`
and :func:`punch_stiffness_exact` the array path's held-set CG instead
(:func:`~petsc_contact.solver.linear.held_set_solve`): the same operators, start and test.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..conventions.grid import Grid
from ..devices.device import CPU
from ..solver.linear import Restricted, unconverged
from ..solver.report import STIFFNESS_RTOL
from . import _petsc
from .operator import ShellInterface, shell_matrix


class _Shell(Restricted, ShellInterface):
    """:class:`~petsc_contact.solver.linear.Restricted` as a shell ``Mat``/``PC`` context."""


def iteration_cap(points: int, int_type: Any) -> int:
    """The held-set solve's iteration limit on ``points`` unknowns: ten per unknown, no more
    than PETSc's integer (``int_type``, ``PETSc.IntType``) holds: 32 bits in Debian's PETSc,
    which ten per unknown overflows above 214.7 million points (14654^2; a 15360^2 run
    failed with ``OverflowError`` after its contact solve)."""
    return int(min(10 * points, np.iinfo(int_type).max))


def restricted_solve(
    grid: Grid,
    op: ShellInterface,
    pc: ShellInterface,
    mask: np.ndarray,
    rtol: float = STIFFNESS_RTOL,
    prefix: str | None = None,
) -> tuple[np.ndarray, int]:
    """Solve ``A_MM y = 1_M`` on the pixels of ``mask`` (local slab) by preconditioned CG,
    ``KSPCG`` reading ``-stiffness_ksp_*`` with ``prefix`` before ``stiffness_`` (default:
    the options block's).

    Returns
    -------
    y, iterations
        The local slab of ``y`` (zero off the mask) and the CG iterations; NaN if CG did not
        converge (:func:`~petsc_contact.solver.linear.unconverged`).
    """
    a_ctx = _Shell(op, mask, CPU)
    m_ctx = _Shell(pc, mask, CPU, a_ctx.scratch)
    petsc = _petsc.petsc()
    mat = shell_matrix(petsc, a_ctx)
    # a PC of its own: one taken from ksp.getPC() keeps its Python context alive after
    # ksp.destroy() (petsc4py 3.18), two field-sized arrays leaked per solve
    comm = _petsc.petsc_comm(grid.comm)
    pcobj = petsc.PC().createPython(m_ctx, comm=comm)
    ksp = petsc.KSP().create(comm=comm)
    try:
        ksp.setType("cg")
        ksp.setPC(pcobj)  # before the operators, which the KSP hands on to its PC
        ksp.setOperators(mat)
        ksp.setTolerances(rtol=rtol, atol=0.0, max_it=iteration_cap(grid.size, petsc.IntType))
        given = _petsc.options_prefix() if prefix is None else prefix
        ksp.setOptionsPrefix(given + "stiffness_")
        ksp.setFromOptions()
        b, y = mat.createVecs()
        with b as barr:
            barr[...] = mask.reshape(-1)
        y.set(0.0)
        ksp.solve(b, y)
        reason = ksp.getConvergedReason()
        its = ksp.getIterationNumber()
    finally:
        ksp.destroy()  # its work Vecs freed before y is copied out
        pcobj.destroy()
        mat.destroy()
    b.destroy()
    out = y.array_r.copy().reshape(grid.local_shape)
    y.destroy()
    if reason <= 0:
        names = {v: k for k, v in vars(petsc.KSP.ConvergedReason).items() if isinstance(v, int)}
        out = unconverged(out, f"KSP {names.get(reason, reason)}")
    return out, int(its)


def periodic_stiffness_exact(
    grid: Grid,
    stiffness: ShellInterface,
    compliance: ShellInterface,
    contact: np.ndarray,
    solve: Any = restricted_solve,
) -> tuple[float, int]:
    """``K = -dp0/du_bar`` with the contact set held fixed (per apparent area).

    ``inf`` at full contact (no open pixel), 0 without contact (the surfaces separate freely).
    ``solve(grid, op, pc, mask)`` is the held-set solve: PETSc's ``KSPCG``
    (:func:`restricted_solve`) or the array path's
    (:func:`~petsc_contact.solver.linear.held_set_solve`).
    """
    free = ~contact
    n_free, n_contact = grid.sum(np.count_nonzero(free), np.count_nonzero(contact))
    if n_free == 0:
        return np.inf, 0
    if n_contact == 0:
        return 0.0, 0
    y, its = solve(grid, stiffness, compliance, free)
    return grid.size / float(grid.sum(y.sum())[0]), its


def punch_stiffness_exact(
    grid: Grid,
    compliance: ShellInterface,
    inverse: ShellInterface,
    contact: np.ndarray,
    solve: Any = restricted_solve,
) -> tuple[float, int]:
    """Total stiffness ``dF/dδ`` of a punch with the contact set held fixed (0 if none);
    ``solve`` as for :func:`periodic_stiffness_exact`.  ``contact`` is this rank's host
    mask; ``y`` may be an array of any device (its sum comes to the host)."""
    if grid.sum(np.count_nonzero(contact))[0] == 0:
        return 0.0, 0
    y, its = solve(grid, compliance, inverse, contact)
    return grid.pixel_area * float(grid.sum(y.sum())[0]), its


def sweep_stiffness(pressure: np.ndarray, mean_gap: np.ndarray) -> np.ndarray:
    """``K = -dp0/du_bar`` from a load sweep, by finite differences.

    Scheme: ``K = -p0 d(ln p0)/du_bar`` with second-order central differences on the
    non-uniform ``u_bar`` table (``numpy.gradient``, second-order one-sided at both ends).
    Differentiating ``ln p0`` is exact for the exponential regime ``p0 ~ exp(-u_bar/u0)``
    and keeps log-spaced sweeps accurate.  The error is ``O(du^2)`` where the contact set
    changes smoothly; steps must be strictly ordered in ``u_bar``.
    """
    p = np.asarray(pressure, dtype=float)
    u = np.asarray(mean_gap, dtype=float)
    if p.ndim != 1 or p.shape != u.shape or p.size < 3:
        raise ValueError("need at least three load steps")
    if np.any(np.diff(u) == 0):
        raise ValueError("mean gaps must differ between steps")
    return -p * np.gradient(np.log(p), u, edge_order=2)
