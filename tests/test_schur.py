"""The Schur form of the preconditioner: the exact inverse of the Hessian on a free set."""

import numpy as np
import pytest

from petsc_contact.backend.coarse import CoarseSpace
from petsc_contact.backend.preconditioner import schur_limit
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft
from petsc_contact.geometries.periodic import PeriodicProblem
from petsc_contact.physics.surface import self_affine


def problem(n=48, p0=1e-3):
    grid = Grid(n, 1.3)
    h = self_affine(
        grid, make_fft(grid), hurst=0.7, rolloff_ratio=2, cutoff_ratio=8, seed=5, rms_slope=0.2
    )
    pb = PeriodicProblem(grid, make_fft(grid), h, 2.0)
    pb.set_pressure(p0)
    return grid, pb


@pytest.mark.parametrize("form", ["schur", "pixel aggregates"])
def test_schur_inverts_the_free_block(petsc, form):
    """``z = M r`` solves ``H_FF z_F = r_F`` with ``z_B = 0`` for a scattered bound set (a
    clustered patch and isolated pixels), to the rounding of a dense solve and two FFTs:
    the Schur form, and the two-level form with single-pixel aggregates (``b = 1``)."""
    grid, pb = problem()
    rng = np.random.default_rng(0)
    bound = np.zeros(grid.local_shape, dtype=bool)
    bound[10:16, 20:27] = True
    bound.flat[rng.choice(grid.size, 40, replace=False)] = True
    free = ~bound.reshape(-1)
    pre = pb.preconditioner
    if form == "schur":
        assert pre.adapt(int(bound.sum()), free)
    else:
        pre.correction = CoarseSpace(grid, pre._exact_compliance(), bound, 1, grid.size)
    r = rng.standard_normal(grid.size) * free
    z = pre.apply_array(r, np.empty_like(r))
    hz = pb.hessian.apply_array(z, np.empty_like(z))
    scale = np.abs(r).max()
    assert np.abs(z[~free]).max() <= 1e-11 * np.abs(z).max()
    assert np.abs((hz - r)[free]).max() <= 1e-9 * scale
    # the reactions on B balance the free residual (H annihilates constants)
    assert abs(hz.sum()) <= 1e-10 * scale * grid.size


def test_large_bound_sets_keep_the_fourier_form():
    """Beyond the Schur limit only the ``q = 0`` entry follows the contact count."""
    grid, pb = problem()
    pre = pb.preconditioner
    free = np.ones(grid.size, dtype=bool)
    free[: pre.schur_max + 1] = False
    assert not pre.adapt(pre.schur_max + 1, free)
    assert pre.schur is None and pre.mean_mode >= pre.base_mean_mode > 0
    assert schur_limit(512**2) < schur_limit(2048**2) <= 4096


def test_a_schur_form_that_cannot_be_factorised_is_not_used(petsc):
    """Where ``G_BB`` is not positive definite (here ``G``'s column negated: rounding could
    do it only for a bound set close to the whole grid) the form is dropped, not applied:
    the preconditioner keeps the Fourier form, whose ``q = 0`` entry follows the count."""
    grid, pb = problem()
    pre = pb.preconditioner
    pre._exact_compliance()
    pre._quarter *= -1.0
    free = np.ones(grid.size, dtype=bool)
    free[::97] = False
    count = int((~free).sum())
    assert 0 < count <= pre.schur_max
    assert not pre.adapt(count, free)
    assert pre.schur is None and pre.mean_mode >= pre.base_mean_mode > 0
    r = np.random.default_rng(1).standard_normal(grid.size) * free
    z = pre.apply_array(r, np.empty_like(r))
    assert np.all(np.isfinite(z)) and float(r @ z) > 0
