"""The held-set linear solve on arrays: ``A_MM y = 1_M`` by preconditioned conjugate gradients.

The exact stiffness (Barber 2003, :mod:`petsc_contact.backend.stiffness`) is one linear solve
with the contact set held fixed.  On the PETSc path PETSc's ``KSPCG`` solves it; on the array
path (``--device gpu`` and its CPU stand-in) :func:`held_set_solve` does, with the same
operators, the same zero start and the same test as ``KSPCG``'s default: the 2-norm of the
preconditioned residual against ``rtol`` times its first value.
"""

from __future__ import annotations

import warnings
from typing import Any, Protocol, runtime_checkable

import numpy as np

from ..conventions.grid import Grid
from ..conventions.warnings import PetscContactWarning, user_level
from ..devices.device import Device


@runtime_checkable
class ReadsInputFirst(Protocol):
    """An operator with a field of its own that its application may take as its input: it
    overwrites that field only once the input is read (the FFT operators' input buffer), so
    a :class:`Restricted` form of it makes its masked copy of the input there."""

    @property
    def input_field(self) -> Any: ...


class StiffnessNotConverged(PetscContactWarning):
    """The held-set solve of an exact stiffness stopped short of its tolerance."""


def unconverged(y: Any, reason: str) -> Any:
    """``y`` set to NaN, with a warning naming ``reason``: a stiffness from a solve that did
    not converge would be wrong, not approximate, and the run goes on without it."""
    warnings.warn(
        f"the exact stiffness's held-set solve did not converge ({reason}; "
        "-stiffness_ksp_max_it and -stiffness_ksp_rtol set its limits): that stiffness is NaN",
        StiffnessNotConverged,
        stacklevel=user_level(),
    )
    y[...] = float("nan")
    return y


class Restricted:
    """``P A P + (I - P)`` for a 0/1 mask ``P`` and an operator ``A`` with ``apply_array``.

    Parameters
    ----------
    op
        The operator (``apply_array(x, out)``, ``diagonal()``, ``grid``).
    mask
        ``P`` as a boolean array of ``op``'s fields.
    device
        Where the fields live (its element-wise passes).
    scratch
        A field of the device that every application overwrites (``P x``); give one
        :class:`Restricted`'s :attr:`scratch` to another applied in turn with it (the
        operator and the preconditioner of one solve) to share it; default: the operator's
        :attr:`~ReadsInputFirst.input_field` where it has one (no field more), else a new one.
    """

    def __init__(self, op: Any, mask: Any, device: Device, scratch: Any = None) -> None:
        self.op = op
        self.grid = op.grid
        self.mask = mask.reshape(-1)
        self.passes = device.passes
        if scratch is None:
            own = isinstance(op, ReadsInputFirst)
            scratch = op.input_field if own else device.xp.empty(self.mask.shape)
        self.scratch = scratch
        self.applications = 0

    def apply_array(self, x: Any, out: Any) -> Any:
        self.applications += 1
        out = out.reshape(-1)
        flat = x.reshape(-1)
        self.passes.restrict(self.scratch, flat, self.mask)
        self.op.apply_array(self.scratch, out)
        self.passes.fill_outside(out, flat, self.mask)
        return out

    def diagonal(self) -> float:
        return float(self.op.diagonal())


def held_set_solve(
    grid: Grid, op: Any, pc: Any, mask: Any, rtol: float, device: Device, max_it: int = 0
) -> tuple[Any, int]:
    """Solve ``A_MM y = 1_M`` on the pixels of ``mask`` by preconditioned CG, its dot
    products summed over ``grid``'s ranks (each holds its slab of the fields).

    Parameters
    ----------
    op, pc
        ``A`` and its preconditioner (``apply_array``), restricted here to the mask.
    mask
        The held set, a boolean array of the device (or a host one, copied there).
    rtol
        Stop when ``||M r|| <= rtol ||M b||`` (``KSPCG``'s default test).
    max_it
        The most iterations (default: ten times the grid's points, as on the PETSc path).

    Returns
    -------
    y, iterations
        ``y`` (zero off the mask) as a field of the device, and the CG iterations; NaN if
        CG did not converge (:func:`unconverged`).
    """
    xp = device.xp
    mask = device.asarray(mask).reshape(-1)
    a = Restricted(op, mask, device)
    m = Restricted(pc, mask, device, a.scratch)
    limit = max_it or 10 * grid.size
    b = mask.astype(float)
    y, r = xp.zeros_like(b), b.copy()
    z, q = xp.empty_like(b), xp.empty_like(b)
    m.apply_array(r, z)
    zz, rz = grid.sum(xp.dot(z, z), xp.dot(r, z)).tolist()
    first = float(np.sqrt(zz))  # ||z||, as xp.linalg.norm computes it
    if not first > 0:
        return y.reshape(grid.local_shape), 0
    p = z.copy()
    reason = "DIVERGED_ITS"
    for its in range(1, limit + 1):
        a.apply_array(p, q)
        (pq,) = grid.sum(xp.dot(p, q)).tolist()
        if not pq > 0:  # a Hessian that is not positive definite on the set
            reason = "DIVERGED_INDEFINITE_MAT"
            break
        alpha = rz / pq
        y += alpha * p
        r -= alpha * q
        m.apply_array(r, z)
        zz, rz_new = grid.sum(xp.dot(z, z), xp.dot(r, z)).tolist()
        if float(np.sqrt(zz)) <= rtol * first:
            return y.reshape(grid.local_shape), its
        p *= rz_new / rz
        p += z
        rz = rz_new
    return unconverged(y, reason).reshape(grid.local_shape), its
