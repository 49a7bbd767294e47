"""The constrained CG as a TAO type on a Hessian that is not the package's (a plain AIJ Mat)."""

import numpy as np
import pytest


def bound_qp(petsc, tao_type, python_type="PreconditionedCG"):
    """``min 1/2 x.Ax - b.x``, ``0 <= x <= 0.3``, on a 1-D Laplacian (n = 200): a TAO of
    ``tao_type`` (the package's ``python_type`` when ``python``) and the objects to
    destroy."""
    n = 200
    a = petsc.Mat().createAIJ((n, n), nnz=3, comm=petsc.COMM_SELF)
    for i in range(n):
        a.setValue(i, i, 2.01)
        for j in (i - 1, i + 1):
            if 0 <= j < n:
                a.setValue(i, j, -1.0)
    a.assemble()
    b = petsc.Vec().createWithArray(np.sin(np.linspace(0, 6 * np.pi, n)) * 0.05)
    lower, upper, x = (petsc.Vec().createSeq(n) for _ in range(3))
    lower.set(0.0)
    upper.set(0.3)
    x.set(0.0)

    def objgrad(tao, xv, gv):
        a.mult(xv, gv)
        gv.axpy(-1.0, b)
        return 0.5 * xv.dot(gv) - 0.5 * xv.dot(b)

    tao = petsc.TAO().create(comm=petsc.COMM_SELF)
    tao.setType(tao_type)
    if tao_type == "python":
        tao.setPythonType(f"petsc_contact.backend.cg.{python_type}")
    tao.setObjectiveGradient(objgrad, None)
    tao.setHessian(lambda *args: None, a, a)
    tao.setVariableBounds(lower, upper)
    tao.setTolerances(gatol=1e-10, grtol=0.0, gttol=0.0)
    return tao, x, [tao, a, b, lower, upper, x]


@pytest.mark.parametrize("python_type", ["PolonskyKeer", "PreconditionedCG"])
def test_bound_qp_with_aij_hessian(petsc, python_type):
    """``min 1/2 x.Ax - b.x`` with ``0 <= x <= 0.3`` on a 1-D Laplacian (n = 200): the KKT
    conditions hold to the tolerance, and the active set is that of a dense projected-gradient
    reference (the problem is strictly convex, so the solution is unique)."""
    n = 200
    tao, x, objects = bound_qp(petsc, "python", python_type)
    b = objects[2].array.copy()
    tao.setMaximumIterations(2000)
    tao.solve(x)
    assert tao.getConvergedReason() > 0
    xs = x.array.copy()
    dense = np.diag(np.full(n, 2.01)) - np.eye(n, k=1) - np.eye(n, k=-1)
    g = dense @ xs - b
    assert xs.min() >= 0 and xs.max() <= 0.3
    assert np.abs(g[(xs > 1e-12) & (xs < 0.3 - 1e-12)]).max() < 1e-9
    assert g[xs <= 1e-12].min() > -1e-9 and g[xs >= 0.3 - 1e-12].max() < 1e-9
    ref = np.zeros(n)
    for _ in range(20000):  # projected gradient with step 1/L, L <= 4.01
        ref = np.clip(ref - (dense @ ref - b) / 4.01, 0.0, 0.3)
    assert np.abs(xs - ref).max() < 1e-7
    assert np.count_nonzero(xs >= 0.3 - 1e-12) > 0 and np.count_nonzero(xs <= 1e-12) > 0
    for obj in objects:
        obj.destroy()


def test_stops_at_the_rounding_floor(monkeypatch):
    """Asked for a residual double precision cannot reach (the package's floor switched
    off), the default CG stops at the floor with CONVERGED_STEPTOL within a few confirmations,
    instead of running to its iteration limit; the verification then flags the step."""
    from petsc_contact import periodic_contact
    from petsc_contact.conventions.grid import Grid
    from petsc_contact.devices.fft import make_fft
    from petsc_contact.geometries import periodic as problem
    from petsc_contact.physics.surface import self_affine

    grid = Grid(128, 1.0)
    h = self_affine(
        grid, make_fft(grid), hurst=0.7, rolloff_ratio=1, cutoff_ratio=64, seed=1, rms_slope=0.1
    )
    p0 = 1e-9  # the exact residual stops near 70 eps rms(K h)/p0 ~ 1e-6 here
    (fine,) = periodic_contact(
        h, length=1.0, modulus=1.0, pressures=[p0]
    )  # with the floor: converged
    assert fine.converged and fine.scalars["tao_reason"] == "CONVERGED_GATOL"
    assert fine.scalars["tolerance"] > 1e-8  # raised to the floor
    monkeypatch.setattr(problem.PeriodicProblem, "tolerance_floor", lambda self: 0.0)
    (stuck,) = periodic_contact(
        h, length=1.0, modulus=1.0, pressures=[p0], options=["-tao_max_it", "2000"]
    )
    assert stuck.scalars["tao_reason"] == "CONVERGED_STEPTOL"
    assert stuck.scalars["iterations"] < 200
    assert not stuck.converged and "residual" in stuck.scalars["verification"]
    assert stuck.scalars["mean_gap"] == pytest.approx(fine.scalars["mean_gap"], rel=1e-12)
