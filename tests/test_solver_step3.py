"""Fewer FFTs per step: the exact Schur form's Hessian image and the compliance column kept
between loads (docs/performance.md, "Counted FFT round trips")."""

import numpy as np
import pytest

from petsc_contact.backend.preconditioner import MeanModePreconditioner
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft
from petsc_contact.geometries.periodic import PeriodicProblem
from petsc_contact.numerics.schur import response_quarter
from petsc_contact.physics.surface import self_affine
from petsc_contact.solver.constrained_cg import ONE_RANK, growth_fraction
from petsc_contact.workflows.periodic_sweep import periodic_contact


def heights(n: int = 48) -> tuple[Grid, np.ndarray]:
    grid = Grid(n, 1.3)
    h = self_affine(
        grid, make_fft(grid), hurst=0.7, rolloff_ratio=2, cutoff_ratio=8, seed=5, rms_slope=0.2
    )
    return grid, h


def schur_problem() -> tuple[Grid, PeriodicProblem, np.ndarray, np.ndarray]:
    """A problem whose preconditioner is in the Schur form on a scattered bound set, and a
    residual restricted to the free set."""
    grid, h = heights()
    pb = PeriodicProblem(grid, make_fft(grid), h, 2.0)
    pb.set_pressure(1e-3)
    rng = np.random.default_rng(0)
    bound = np.zeros(grid.size, dtype=bool)
    bound[rng.choice(grid.size, 60, replace=False)] = True
    assert pb.preconditioner.adapt(int(bound.sum()), ~bound)
    return grid, pb, ~bound, rng.standard_normal(grid.size) * ~bound


def test_schur_image_is_the_hessian_of_the_restricted_output(petsc):
    """``hessian_image`` gives ``beta out + H z`` for ``z = P_F M r`` without a transform,
    from the unrestricted gradient ``g`` (``r = P_F g``: the CG keeps no ``r``)."""
    grid, pb, free, r = schur_problem()
    pre = pb.preconditioner
    rng = np.random.default_rng(1)
    g = r + rng.standard_normal(grid.size) * ~free  # anything on the bound pixels
    z = pre.apply_array(r, np.empty_like(r)) * free
    hz = pb.hessian.apply_array(z, np.empty_like(z))
    old = rng.standard_normal(grid.size)
    out = old.copy()
    assert pre.hessian_image(g, out, 0.5)
    assert np.abs(out - 0.5 * old - hz).max() <= 1e-9 * np.abs(hz).max()
    assert pre.hessian_image(g, out, 0.0)
    assert np.abs(out - hz).max() <= 1e-9 * np.abs(hz).max()


@pytest.mark.parametrize("bound_count", [0, 60, 200])
def test_preconditioner_applies_in_place(petsc, bound_count):
    """The constrained CG preconditions in place (``z`` is ``r``): the Fourier form (no
    bound pixel), the exact Schur form (60) and the two-level form (200 of 2304) give, in
    place, the numbers they give into another array."""
    grid, pb, free, r = schur_problem()
    pre = pb.preconditioner
    free[:] = True
    free[np.random.default_rng(2).choice(grid.size, bound_count, replace=False)] = False
    pre.schur_max = 100
    for _ in range(2):  # the two-level form is built once the count has settled
        pre.adapt(bound_count, free)
    assert (pre.schur is not None) == (bound_count == 60)
    assert (pre.coarse is not None) == (bound_count == 200)
    x = r * free
    expected = pre.apply_array(x, np.empty_like(x))
    assert np.abs(expected).max() > 0
    assert np.array_equal(pre.apply_array(x, x), expected)


def test_other_forms_give_no_image(petsc):
    """Beyond the Schur form the output is restricted after the preconditioner, and its
    image is not known: ``out`` stays as it was."""
    grid, pb, free, r = schur_problem()
    pre = pb.preconditioner
    free[: pre.schur_max + 1] = False
    pre.adapt(int((~free).sum()), free)
    pre.apply_array(r * free, np.empty_like(r))
    out = np.ones(grid.size)
    assert not pre.hessian_image(r, out, 1.0)
    assert (out == 1.0).all()


def test_compliance_column_rescaled_between_loads(petsc):
    """The column of ``1/K`` kept from one load is the one computed afresh at the next."""
    grid, h = heights()
    pb = PeriodicProblem(grid, make_fft(grid), h, 2.0)
    pre = pb.preconditioner
    pb.set_pressure(1e-4)
    pre._exact_compliance()
    pb.set_pressure(3e-2)
    kept = pre._exact_compliance().copy()
    fresh = response_quarter(grid, pre.apply_array, pre.work_fields(), pre.device)
    assert np.abs(kept - fresh).max() <= 1e-13 * np.abs(fresh).max()


def test_schur_steps_take_no_hessian_transform(petsc, monkeypatch):
    """Loads on a few contact pixels are solved in the Schur form without any transform of
    the Hessian, in the iterations and to the answer of the solver that transforms it."""
    grid, h = heights()
    loads = [1e-5, 1e-4, 1e-3]
    steps = periodic_contact(h, length=1.3, modulus=2.0, pressures=loads)
    monkeypatch.setattr(MeanModePreconditioner, "hessian_image", lambda *args: False)
    transformed = periodic_contact(h, length=1.3, modulus=2.0, pressures=loads)
    for step, other in zip(steps, transformed, strict=True):
        s, t = step.scalars, other.scalars
        assert s["converged"] and t["converged"]
        assert s["hessian_applications"] == 0 < t["hessian_applications"]
        assert s["iterations"] == t["iterations"]
        assert abs(s["mean_gap"] - t["mean_gap"]) <= 1e-9 * abs(t["mean_gap"])


def reference_fraction(x, d, alpha, lower, limit):
    """The growth limit's fraction from the fractions gathered (one rank)."""
    below = x < lower
    lo = lower if isinstance(lower, float) else lower[below]
    reach = 1.0 - (x[below] - lo) / (alpha * d[below])
    reach = np.sort(reach[reach > 1e-9])[:limit]
    low, high = 0.0, 1.0
    for _ in range(40):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if np.count_nonzero(reach <= mid) < limit else (low, mid)
    return high


def test_growth_fraction_in_work_arrays():
    """The fraction computed in the CG's work arrays is the one of the gathered fractions,
    bit for bit, with a bound array or a number, starts on the bound and zero directions."""
    rng = np.random.default_rng(3)
    n = 5000
    x0 = np.abs(rng.standard_normal(n))
    x0[:300] = 0.0  # on the bound
    d = rng.standard_normal(n)
    d[300:400] = 0.0
    for lower, limit in ((0.0, 64), (0.0, 1000), (0.0, 10000), (rng.random(n) * 0.1, 200)):
        alpha = 0.8
        x = x0 - alpha * d
        work = (np.empty(n), np.empty(n))
        got = growth_fraction(x, d, alpha, lower, limit, ONE_RANK.sum, work)
        assert got == reference_fraction(x, d, alpha, lower, limit)


@pytest.mark.parametrize("device", ["cpu", "cpu-array"])
def test_leaving_the_schur_form_keeps_the_recurrence(petsc, monkeypatch, device):
    """A cold step that leaves the Schur form for the Fourier one (the growth limit takes
    the contact past ``m_S``): the recurrence goes on across the change, in fewer
    iterations than a restart there, to the same answer.  Measured at 128^2 (``H = 0.3``,
    ``p0 = 1e-2``, seed 5): 22 iterations going on, 25 restarting; over 64 cold 512^2
    steps 1684 against 1749, over 64 at 1024^2 1996 against 2102 (docs/performance.md,
    "The lost iterations").  TAO's path and
    the array path run the same CG."""
    n = 128
    grid = Grid(n, 1.0)
    h = self_affine(
        grid, make_fft(grid), hurst=0.3, rolloff_ratio=1, cutoff_ratio=n / 2, seed=5, rms_slope=0.1
    )
    left = []
    adapt = MeanModePreconditioner.adapt

    def watched(pre: MeanModePreconditioner, bound_count: int, free: np.ndarray) -> bool:
        schur = pre.schur is not None
        changed = adapt(pre, bound_count, free)
        left.append(schur and pre.correction is None)
        return changed

    monkeypatch.setattr(MeanModePreconditioner, "adapt", watched)
    (step,) = periodic_contact(h, length=1.0, pressures=1e-2, progress=False, device=device)
    assert any(left)  # the solve did leave the Schur form

    def restarting(pre: MeanModePreconditioner, bound_count: int, free: np.ndarray) -> bool:
        schur = pre.schur is not None
        return adapt(pre, bound_count, free) or (schur and pre.correction is None)

    monkeypatch.setattr(MeanModePreconditioner, "adapt", restarting)
    (restarted,) = periodic_contact(h, length=1.0, pressures=1e-2, progress=False, device=device)
    s, t = step.scalars, restarted.scalars
    assert s["converged"] and t["converged"]
    assert s["iterations"] <= 22 < t["iterations"]
    # both stop at the same gradient tolerance: the mean gaps agree to well below it
    assert abs(s["mean_gap"] - t["mean_gap"]) <= 1e-8 * abs(t["mean_gap"])


def test_a_multiplier_kept_once_says_once_is_deprecated():
    """``FourierOperator(..., once=)`` still works, warns, and keeps the one layout: one float
    per complex entry of the spectrum, the same operator either way."""
    from petsc_contact.backend.operator import FourierOperator

    grid, h = heights()
    fft = make_fft(grid)
    kernel = np.abs(np.fft.rfftfreq(grid.shape[1]))[None, :] + np.zeros(fft.spectrum.shape)
    plain = FourierOperator(grid, fft, kernel)
    with pytest.warns(DeprecationWarning, match="once= is deprecated"):
        old = FourierOperator(grid, fft, kernel, once=False)
    assert plain.multiplier.shape == old.multiplier.shape == fft.spectrum.shape
    x = h.reshape(-1)
    a, b = plain.apply_array(x, np.empty_like(x)), old.apply_array(x, np.empty_like(x))
    assert np.array_equal(a, b) and np.abs(a).max() > 0


def test_a_pc_of_petsc_s_own_preconditions_in_place(petsc):
    """The constrained CG preconditions in place (``z`` is ``r``); a ``PC`` that is not the
    package's Python one is applied on a copy (PETSc refuses aliased vectors): Jacobi on a
    diagonal matrix gives ``r / diag`` into ``r``'s own array."""
    from petsc_contact.backend.cg import _context, _in_place, _VecArrays

    diag = petsc.Vec().createSeq(5)
    diag.setArray(np.arange(1.0, 6.0))
    mat = petsc.Mat().createAIJ((5, 5), nnz=1)
    mat.setUp()
    mat.setDiagonal(diag)
    mat.assemble()
    pc = petsc.PC().create()
    pc.setType("jacobi")
    pc.setOperators(mat)
    pc.setUp()
    arrays = _VecArrays()
    x = diag.duplicate()
    arrays.begin(x)
    r = arrays.new()
    r[...] = 6.0
    _in_place(pc, _context(pc), arrays)(r, r)
    assert np.allclose(r, 6.0 / np.arange(1.0, 6.0))
    arrays.close()
    for obj in (pc, mat, diag, x):
        obj.destroy()
