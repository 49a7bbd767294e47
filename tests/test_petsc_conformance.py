"""The default solver as a TAO type like PETSc's own: TAO's tolerances, convergence tests,
monitors and views hold for it as for ``bncg``; a sweep keeps one TAO; an options prefix
gives each solver its own options."""

import warnings

import pytest
from test_cg import bound_qp

SURFACE = {"hurst": 0.7, "rms_slope": 0.1, "seed": 1}
BNCG = ["-tao_type", "bncg"]


@pytest.fixture(scope="module")
def heights():
    from petsc_contact.conventions.grid import Grid
    from petsc_contact.devices.fft import make_fft
    from petsc_contact.physics.surface import self_affine

    grid = Grid(64, 1.0)
    return self_affine(grid, make_fft(grid), rolloff_ratio=1, cutoff_ratio=16, **SURFACE)


def solve(heights, options, pressures=(1e-2,)):
    """The steps of ``periodic_contact`` with ``options``, and the warnings it gave."""
    from petsc_contact import periodic_contact

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        steps = periodic_contact(
            heights, length=1.0, modulus=1.0, pressures=list(pressures), options=options
        )
    return steps, [str(w.message) for w in caught]


@pytest.fixture(scope="module")
def full(heights):
    """The default solver's and bncg's steps at their default tolerances."""
    return {name: solve(heights, t)[0][0].scalars for name, t in (("cg", []), ("bncg", BNCG))}


@pytest.mark.parametrize(
    "options, reason",
    [
        (["-tao_gttol", "1e-2"], "CONVERGED_GTTOL"),
        (["-tao_max_funcs", "5"], "DIVERGED_MAXFCN"),
        (["-tao_max_it", "3"], "DIVERGED_MAXITS"),
        (["-tao_grtol", "0.5"], "CONVERGED_GRTOL"),
    ],
    ids=["gttol", "max_funcs", "max_it", "grtol"],
)
def test_tao_tolerances_stop_the_default_solver_as_bncg(heights, full, options, reason):
    """Each TAO tolerance stops the default solver with the reason it stops ``bncg`` with,
    before the full solve; ``-tao_max_funcs 5`` after at most 6 objective evaluations."""
    for name, solver in (("cg", []), ("bncg", BNCG)):
        (step,), _ = solve(heights, solver + options)
        s = step.scalars
        assert s["tao_reason"] == reason, name
        assert s["iterations"] < full[name]["iterations"]
        assert s["gradient_norm"] > full[name]["gradient_norm"]
        if "-tao_max_funcs" in options:
            assert s["objective_gradient_evaluations"] <= 6
        if "-tao_max_it" in options:
            assert s["iterations"] == 3


def test_fatol_is_not_read_by_tao(heights, full):
    """PETSc 3.18's TAO has no ``-tao_fatol``: neither solver reads it, both converge as
    without it and the option is reported unused."""
    for name, solver in (("cg", []), ("bncg", BNCG)):
        (step,), messages = solve(heights, [*solver, "-tao_fatol", "1e-1"])
        assert step.scalars["iterations"] == full[name]["iterations"]
        assert step.scalars["tao_reason"] == "CONVERGED_GATOL"
        assert any("never used: -tao_fatol" in m for m in messages)


@pytest.mark.parametrize("tao_type", ["python", "bncg"])
def test_users_convergence_test_is_honoured(petsc, tao_type):
    """A convergence test given with ``tao.setConvergenceTest`` stops the solve where it says
    (``True``: ``CONVERGED_USER`` at iteration 4), as it stops ``bncg``; TAO's monitor sees
    every iteration up to there."""
    tao, x, objects = bound_qp(petsc, tao_type)
    seen = []
    tao.setConvergenceTest(lambda t: True if t.getIterationNumber() >= 4 else None)
    tao.setMonitor(lambda t: seen.append(t.getIterationNumber()))
    tao.solve(x)
    assert tao.getConvergedReason() == petsc.TAO.Reason.CONVERGED_USER
    assert tao.getIterationNumber() == 4 and set(seen) == {0, 1, 2, 3, 4}
    for obj in objects:
        obj.destroy()


def test_tao_view_describes_the_solver(heights, capfd):
    """``-tao_view`` prints the default solver's name, its preconditioner and tolerances;
    ``-tao_monitor`` a line per iteration, as for TAO's own types."""
    (step,), _ = solve(heights, ["-tao_view", "-tao_monitor"])
    out = capfd.readouterr().out
    assert "PreconditionedCG: the package's active-set conjugate gradient" in out
    assert "preconditioner: MeanModePreconditioner, restricted to the free set" in out
    assert "gatol=1e-08, grtol=0, gttol=0, max_it=5000" in out
    assert out.count("TAO,  Function value:") >= step.scalars["iterations"]


def test_prefix_gives_two_solvers_their_options(heights):
    """Two solvers side by side, prefixes ``a_`` and ``b_``: each reads its own options
    (``-a_tao_type bncg``, ``-b_tao_max_it 2``), step after step; the unprefixed
    ``-tao_type blmvm`` is neither's."""
    from petsc_contact.backend import _petsc
    from petsc_contact.backend.solve import BoundSolver
    from petsc_contact.conventions.grid import Grid
    from petsc_contact.devices.fft import make_fft
    from petsc_contact.geometries.periodic import PeriodicProblem
    from petsc_contact.geometries.step import solve_step

    options = ["-a_tao_type", "bncg", "-b_tao_max_it", "2", "-tao_type", "blmvm"]
    unused = pytest.warns(UserWarning, match="never used: -tao_type")
    with unused, _petsc.scoped_options(options):
        grid = Grid(64, 1.0)
        problem = PeriodicProblem(grid, make_fft(grid), heights, 1.0)
        problem.set_pressure(1e-2)
        problem.start(problem.initial_gap())
        ops = (grid, problem.hessian, problem.preconditioner)
        with BoundSolver(*ops, options_prefix="a_") as a, BoundSolver(*ops, "b_") as b:
            for _ in range(2):
                first, _ = solve_step(a, problem, problem.start_point)
                second, _ = solve_step(b, problem, problem.start_point)
                assert first.scalars["tao_type"] == "bncg" and first.converged
                assert second.scalars["tao_type"] == "cg"
                assert second.scalars["tao_reason"] == "DIVERGED_MAXITS"
                assert second.scalars["iterations"] == 2


def test_run_and_cli_take_a_prefix(tmp_path):
    """``Run(options_prefix="a_")`` reads ``-a_tao_type`` and ``-a_stiffness_ksp_rtol``
    (the package's own options too), not ``-tao_type``; ``--options-prefix`` makes such a
    run, and a prefix PETSc cannot take is refused."""
    from petsc_contact import Run, run_contact
    from petsc_contact.cli.arguments import build_parser
    from petsc_contact.cli.common import describe

    options = ("-a_tao_type", "bncg", "-a_stiffness_ksp_rtol", "1e-7", "-tao_type", "blmvm")
    run = Run(grid=32, **SURFACE, pressures=(1e-2,), stiffness=True, options=options)
    with pytest.warns(UserWarning, match="never used: -tao_type"):
        (row,) = run_contact(run.with_(options_prefix="a_")).table
    assert row["tao_type"] == "bncg" and row["stiffness_tolerance"] == 1e-7
    (plain,) = run_contact(run.with_(options=("-tao_type", "bncg"))).table
    assert plain["tao_type"] == "bncg" and plain["stiffness_tolerance"] == 1e-6
    line = ["periodic", "--grid", "32", "--pressures", "1e-2", "--output", str(tmp_path / "o.h5")]
    args = build_parser().parse_args([*line, "--options-prefix", "a_"])
    assert describe(args).options_prefix == "a_"
    with pytest.raises(ValueError, match="options prefix"):
        run_contact(run.with_(options_prefix="-a"))


def test_sweep_keeps_one_tao(heights, monkeypatch):
    """A 4-step sweep makes its TAO once (a probe counts the TAOs the package creates)."""
    from petsc4py import PETSc

    made = []

    class CountedTAO(PETSc.TAO):
        def create(self, *args, **kwargs):
            made.append(self)
            return super().create(*args, **kwargs)

    monkeypatch.setattr(PETSc, "TAO", CountedTAO)
    steps, _ = solve(heights, [], pressures=(1e-3, 3e-3, 1e-2, 3e-2))
    assert len(steps) == 4 and all(s.converged for s in steps)
    assert len(made) == 1


def test_bqpip_shifts_the_diagonal_and_reaches_the_default(heights):
    """TAO's interior-point ``bqpip`` adds its barrier's diagonal to the Hessian's shell
    ``Mat`` and restores it (``MatDiagonalSet``, add then insert): with its options file it
    reaches the default solver's mean gap to 1e-6 at 3e-4 and 1e-2 E* (it raised a PETSc
    error before the shell took a diagonal)."""
    from conftest import ROOT

    opts = ["-options_file", str(ROOT / "options" / "bqpip.opts")]
    loads = (3e-4, 1e-2)
    (cg, _), (bq, _) = (solve(heights, o, loads) for o in ([], opts))
    for a, b in zip(cg, bq, strict=True):
        assert b.converged and b.scalars["tao_type"] == "bqpip", b.scalars["verification"]
        assert b.scalars["mean_gap"] == pytest.approx(a.scalars["mean_gap"], rel=1e-6)


def test_a_shifted_shell_adds_and_restores_its_diagonal():
    """``DiagonalShift``: ``(H + D) x`` after ``MatDiagonalSet(ADD_VALUES)``, ``H x`` again
    after the diagonal is inserted back, and the shifted diagonal read in between."""
    import numpy as np

    from petsc_contact.backend import _petsc
    from petsc_contact.backend.operator import DiagonalShift, FourierOperator, shell_matrix
    from petsc_contact.conventions.grid import Grid
    from petsc_contact.devices.fft import make_fft

    petsc = _petsc.init([])
    grid = Grid(16, 1.0)
    kernel = 1.0 + np.arange(grid.shape[0])[:, None] + np.zeros((1, grid.half))
    op = FourierOperator(grid, make_fft(grid), kernel)
    mat = shell_matrix(petsc, DiagonalShift(op))
    x, y, d = mat.createVecRight(), mat.createVecLeft(), mat.createVecRight()
    x.setArray(np.random.default_rng(1).standard_normal(grid.size))
    plain = op.apply_array(x.array_r, np.empty(grid.size)).copy()
    shift = np.linspace(0.5, 2.0, grid.size)
    d.setArray(shift)
    mat.setDiagonal(d, addv=petsc.InsertMode.ADD_VALUES)
    mat.mult(x, y)
    np.testing.assert_allclose(y.array_r, plain + shift * x.array_r, rtol=1e-13)
    diagonal = mat.getDiagonal()
    np.testing.assert_allclose(diagonal.array_r, op.diagonal() + shift, rtol=1e-14)
    d.set(op.diagonal())
    mat.setDiagonal(d, addv=petsc.InsertMode.INSERT_VALUES)
    mat.mult(x, y)
    np.testing.assert_array_equal(y.array_r, plain)
