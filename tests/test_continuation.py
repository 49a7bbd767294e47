"""Load continuation (start and preconditioner support) and the held compliance.

Continuation may change the solver's path, never its answer: a sweep is checked against
cold solves of the same loads, and a preconditioner held by a stiffness a thousand times
off must still converge to the same contact.
"""

import numpy as np
import pytest
from mpi4py import MPI

from petsc_contact import periodic_contact
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft, wavevector_magnitude
from petsc_contact.geometries.periodic import PeriodicProblem
from petsc_contact.physics.continuation import MAX_EXTRAPOLATION, ConvergedStep, LoadPath
from petsc_contact.physics.greens import held_compliance, periodic_compliance
from petsc_contact.physics.surface import self_affine
from petsc_contact.workflows.periodic_sweep import sweep

U0 = 0.3  # log-slope of the synthetic exponential curve p = exp(-u/U0)


def exponential_step(p0: float, gap: np.ndarray, stiffness: float = np.nan) -> ConvergedStep:
    return ConvergedStep(p0, -U0 * np.log(p0), gap, stiffness)


def test_log_slope_from_exact_stiffness_and_from_two_mean_gaps():
    path = LoadPath()
    assert path.log_slope() is None and path.stiffness_estimate(1.0) is None
    path.add(exponential_step(1e-3, np.zeros(4)))
    assert path.log_slope() is None  # one step and no stiffness: nothing is known
    path.add(exponential_step(1e-2, np.zeros(4)))
    assert path.log_slope() == pytest.approx(U0, rel=1e-12)  # the secant of u(ln p)
    assert path.stiffness_estimate(0.05) == pytest.approx(0.05 / U0, rel=1e-12)
    path.add(exponential_step(2e-2, np.zeros(4), stiffness=0.2))
    assert path.log_slope() == pytest.approx(2e-2 / 0.2)  # the exact stiffness wins


def test_log_slope_ignores_unloading_and_equal_gaps():
    path = LoadPath()
    path.add(ConvergedStep(1e-3, 1.0, np.zeros(4)))
    path.add(ConvergedStep(1e-2, 1.0, np.zeros(4)))  # u_bar unchanged: no positive slope
    assert path.log_slope() is None
    path.add(ConvergedStep(1e-2, 0.5, np.zeros(4), stiffness=np.inf))  # full contact
    assert path.log_slope() is None


def test_start_is_the_secant_in_log_pressure_projected_on_the_bound():
    """Fields linear in ln p are extrapolated exactly; negative predictions are clipped;
    steps beyond MAX_EXTRAPOLATION intervals, unloading and a repeated load start from the
    last gap itself."""
    slope = np.array([-1.0, -0.1, 0.0, 0.5])
    offset = np.array([1.0, 1.0, 2.0, 0.0])

    def gap(p0: float) -> np.ndarray:
        return offset + slope * np.log(p0 / 1e-3)

    path = LoadPath()
    last = gap(1e-3)
    assert path.start(1e-2, last) is last
    path.add(ConvergedStep(1e-3, 0.0, gap(1e-3)))
    path.add(ConvergedStep(1e-2, 0.0, gap(1e-2)))
    last = gap(1e-2)
    np.testing.assert_allclose(path.start(3e-2, last), np.maximum(gap(3e-2), 0), atol=1e-14)
    assert path.start(3e-2, last)[0] == 0.0  # 1 - ln 30 < 0: clipped
    beyond = 1e-2 * 10 ** (MAX_EXTRAPOLATION + 0.1)
    for p0 in (beyond, 5e-3, 1e-2):
        assert path.start(p0, last) is last


def test_held_compliance_limits():
    q = np.array([0.0, 1e-3, 1e3])
    held = held_compliance(q, 2.0, 0.5)
    assert held[0] == pytest.approx(1 / 0.5)  # the mean mode: 1/K
    free = periodic_compliance(q[1:], 2.0, 1.0)
    assert held[2] == pytest.approx(free[1], rel=1e-3)  # short waves: the free compliance
    assert held[1] == pytest.approx(1 / (1e-3 + 0.5))
    for bad in (0.0, -1.0, np.inf, np.nan):
        with pytest.raises(ValueError):
            held_compliance(q, 2.0, bad)


def test_held_operators_are_the_held_compliance():
    """The stiffness solve's operator and the CG's preconditioner (scaled like the Hessian)
    carry ``1/(E*|q|/2 + K)``; in the Schur form the preconditioner is the exact ``1/K``."""
    grid = Grid(32, 2.0, MPI.COMM_SELF)
    fft = make_fft(grid)
    heights = self_affine(
        grid, fft, hurst=0.7, rolloff_ratio=1, cutoff_ratio=16, seed=1, rms_slope=0.1
    )
    problem = PeriodicProblem(grid, fft, heights, 3.0)
    q = wavevector_magnitude(grid, fft)
    expected = held_compliance(q, 3.0, 0.7) / grid.size
    np.testing.assert_allclose(problem.held_compliance(0.7).spectrum, expected, rtol=1e-12)
    problem.set_pressure(1e-2, 0.7)
    c = problem.hessian.spectrum[0, 1] / problem.stiffness.spectrum[0, 1]  # the Hessian's scale
    pre = problem.preconditioner
    np.testing.assert_allclose(pre.spectrum * c, expected, rtol=1e-12)
    assert pre.adapt(1, np.arange(grid.size) > 0)  # one pixel at the bound: the Schur form
    free = periodic_compliance(q, 3.0, 1.0) / grid.size
    np.testing.assert_allclose((pre.spectrum * c)[q > 0], free[q > 0], rtol=1e-12)
    # leaving the Schur form for the Fourier one keeps the CG's recurrence (no restart: over
    # eight seeds a restart there cost iterations, docs/performance.md "The lost iterations")
    assert not pre.adapt(pre.schur_max + 1, np.arange(grid.size) > pre.schur_max)
    assert pre.schur is None
    np.testing.assert_allclose((pre.spectrum * c)[q > 0], expected[q > 0], rtol=1e-12)


@pytest.fixture(scope="module")
def paper_band():
    """A 128^2 surface with roughness down to two pixels (L/lambda_1 = n/2)."""
    grid = Grid(128, 1.0, MPI.COMM_SELF)
    return self_affine(
        grid, make_fft(grid), hurst=0.7, rolloff_ratio=1, cutoff_ratio=64, seed=3, rms_slope=0.1
    )


def test_sweep_agrees_with_cold_solves(paper_band):
    """Warm-started, extrapolated steps land where cold solves of each load land: the mean
    gaps agree to 1e-7 (the gatol 1e-8 pressure tolerance moves u_bar by ~1e-9 relative
    here), the areas to the pixel, the stiffness to 1e-8 (its CG tolerance gives 2e-10)."""
    pressures = list(np.geomspace(1e-4, 3e-2, 6))
    warm = periodic_contact(
        paper_band, length=1.0, modulus=1.0, pressures=pressures, stiffness=True
    )
    for p0, step in zip(pressures, warm, strict=True):
        (cold,) = periodic_contact(
            paper_band, length=1.0, modulus=1.0, pressures=[p0], stiffness=True
        )
        assert step.converged and cold.converged
        w, c = step.scalars, cold.scalars
        assert w["mean_gap"] == pytest.approx(c["mean_gap"], rel=1e-7)
        assert w["area_fraction"] == c["area_fraction"]
        assert w["stiffness"] == pytest.approx(c["stiffness"], rel=1e-8)
        assert w["preconditioner_stiffness"] > 0


@pytest.mark.parametrize("factor", [0.0, 1e-3, 1e3])
def test_wrong_support_changes_the_path_not_the_answer(petsc, paper_band, factor):
    """A preconditioner held by a stiffness 1000 times too soft or too stiff, or not held at
    all (the free compliance), still converges to the contact of Persson's estimate."""
    grid = Grid(128, 1.0, MPI.COMM_SELF)
    problem = PeriodicProblem(grid, make_fft(grid), paper_band, 1.0)
    p0 = 3e-3
    (reference,) = sweep(problem, [p0])
    problem.set_pressure(p0, factor * problem.stiffness_estimate(p0))
    assert problem.interfacial_stiffness == pytest.approx(factor * problem.stiffness_estimate(p0))
    x0 = problem.initial_gap().reshape(-1) / problem.scale_length
    problem.start(x0)
    from petsc_contact.backend.solve import BoundSolver

    with BoundSolver(grid, problem.hessian, problem.preconditioner) as solver:
        x, info = solver.solve(problem.objective_gradient, problem.start_point)
    assert info.reason_code > 0
    gap = x.reshape(grid.local_shape) * problem.scale_length
    assert gap.mean() == pytest.approx(reference.scalars["mean_gap"], rel=1e-7)
