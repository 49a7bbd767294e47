"""Adhesion on the periodic cell: the laws, the objective's gradient, the weak-adhesion limit
(the hard wall), a sphere's pull-off between Maugis' JKR and DMT limits, the load cycle's
records, and the refusals."""

import h5py
import numpy as np
import pytest
from conftest import cli

from petsc_contact import Run
from petsc_contact.backend._petsc import scoped_options
from petsc_contact.backend.tao import PetscBackend
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft
from petsc_contact.geometries.adhesive_periodic import AdhesivePeriodicProblem
from petsc_contact.geometries.periodic import PeriodicProblem
from petsc_contact.interactions.adhesion import MAUGIS_SMOOTHING, Adhesion
from petsc_contact.physics.surface import self_affine
from petsc_contact.workflows.adhesive_steps import (
    BranchJump,
    adhesive_mean_gap_sweep,
    adhesive_sweep,
    note_jump,
    predicted_pressure,
    pull_off_pressure,
)
from petsc_contact.workflows.periodic_steps import sweep

RHO = 0.01  # the sphere's interaction range (1.28 pixels at 128^2)


@pytest.fixture(scope="module")
def rough():
    grid = Grid(64, 1.0)
    h = self_affine(
        grid, make_fft(grid), hurst=0.8, rolloff_ratio=1, cutoff_ratio=32, seed=3, rms_slope=0.1
    )
    return grid, h


@pytest.mark.parametrize("law", ["exponential", "maugis"])
def test_the_laws_energy_is_the_integral_of_their_attraction(law):
    """``phi(0) = -w``, ``phi`` vanishes beyond the range (Maugis': beyond the smoothed step;
    the exponential: as ``exp(-g/rho)``), and ``phi'`` is its derivative (central differences
    of step 1e-7 rho: rounding 1e-9 w/rho; at the ends of Maugis' ramp, where the curvature
    jumps by ``(w/rho)/(2 eps rho)``, half the step times that, 5e-7 w/rho)."""
    a = Adhesion(law, 2e-3, 0.5)
    assert a.energy(np.zeros(1))[0] == pytest.approx(-2e-3, rel=1e-15)
    far = np.array([0.5 * (1 + 2 * MAUGIS_SMOOTHING), 20.0])
    expected = 0.0 if law == "maugis" else -2e-3 * np.exp(-far / 0.5)
    assert np.all(a.energy(far) == expected)
    g = np.linspace(0.0, 1.0, 2001)[1:-1]
    step = 1e-7 * a.range
    numeric = (a.energy(g + step) - a.energy(g - step)) / (2 * step)
    assert np.abs(numeric - a.derivative(g)).max() < 1e-6 * a.strength


def test_the_objective_and_its_gradient_agree(rough):
    """The scaled objective's directional derivative is its gradient's (central differences
    of 1e-6 of the rms height: 1e-9 of the slope)."""
    grid, h = rough
    problem = AdhesivePeriodicProblem(
        grid, make_fft(grid), h, 1.0, Adhesion("exponential", 1e-4, 5e-3)
    )
    problem.set_pressure(-1e-3)
    x0 = problem.initial_gap().reshape(-1) / problem.scale_length
    problem.start(x0)
    d = np.random.default_rng(1).standard_normal(x0.size)
    grad = np.empty_like(x0)
    problem.objective_gradient(x0, grad)
    t = 1e-6
    up = problem.objective_gradient(x0 + t * d, np.empty_like(x0))
    down = problem.objective_gradient(x0 - t * d, np.empty_like(x0))
    assert (up - down) / (2 * t) == pytest.approx(np.dot(grad, d), rel=1e-6)


@pytest.mark.parametrize("tao_type", ["blmvm", "bncg"])
def test_weak_adhesion_is_the_hard_wall(rough, tao_type):
    """An attraction ``w/rho`` far below the load moves the mean gap by at most its share of
    the load (``du/u ~ (w/rho)/p0`` in the exponential regime, where ``u0 = p0/K`` is below
    the mean gap) and keeps the contact area; a strong one moves both (the check can fail)."""
    grid, h = rough
    loads = [5e-3, 1e-2]
    with scoped_options(["-tao_type", tao_type]):
        wall = list(sweep(PeriodicProblem(grid, make_fft(grid), h, 1.0, PetscBackend()), loads))
        results = {}
        for w in (1e-9, 1e-5):
            law = Adhesion("exponential", w, 5e-3)
            problem = AdhesivePeriodicProblem(grid, make_fft(grid), h, 1.0, law, PetscBackend())
            results[w] = list(adhesive_sweep(problem, loads))
    for p0, ref, weak, strong in zip(loads, wall, results[1e-9], results[1e-5], strict=True):
        assert weak.converged and strong.converged, weak.scalars["verification"]
        u = ref.scalars["mean_gap"]
        assert abs(weak.scalars["mean_gap"] - u) / u < 2 * (1e-9 / 5e-3) / p0 + 1e-6
        assert weak.scalars["area_fraction"] == ref.scalars["area_fraction"]
        assert abs(strong.scalars["mean_gap"] - u) / u > 1e-2
        assert strong.scalars["area_fraction"] > ref.scalars["area_fraction"]


def sphere_cycle(law, tabor, tao_type, fractions):
    """A sphere ``R = 1`` in a unit cell (128^2) with ``rho = 0.01`` and ``w`` from the Tabor
    parameter ``mu = (R w^2 / (E*^2 rho^3))^(1/3)``, unloaded from half the DMT pull-off
    ``2 pi R w`` to ``-fraction`` of it: the steps' scalars and ``2 pi R w``."""
    n = 128
    grid = Grid(n, 1.0)
    x = (np.arange(n) + 0.5) / n - 0.5
    h = -(x[:, None] ** 2 + x[None, :] ** 2) / 2
    w = np.sqrt(tabor**3 * RHO**3)
    dmt = 2 * np.pi * w
    loads = [0.5 * dmt] + [-f * dmt for f in fractions]
    with scoped_options(["-tao_type", tao_type]):
        law_ = Adhesion(law, w, RHO)
        problem = AdhesivePeriodicProblem(grid, make_fft(grid), h, 1.0, law_, PetscBackend())
        return [s.scalars for s in adhesive_sweep(problem, loads)], dmt


@pytest.mark.parametrize(
    ("law", "tabor", "tao_type", "low", "high"),
    [
        ("exponential", 0.1, "blmvm", 0.95, 1.0),
        ("maugis", 0.1, "bncg", 0.9, 1.0),
        ("exponential", 2.0, "blmvm", 0.75, 0.9),
    ],
)
def test_a_spheres_pull_off_lies_between_jkr_and_dmt(law, tabor, tao_type, low, high):
    """The pull-off of a sphere (Maugis 1992): ``2 pi R w`` (DMT) at a small Tabor parameter,
    toward ``1.5 pi R w`` (JKR) at a large one.  At ``mu = 0.1`` the rigid sphere's
    Derjaguin force is reached within the load step (2%, 5% for the smoothed Maugis law on
    coarser steps); at ``mu = 2`` it lies strictly between the limits (0.75 and 1 of DMT's).
    The steps beyond it are not converged and say ``pulled off``; it is bracketed."""
    fractions = (0.0, 0.5, 0.7, 0.75, 0.8, 0.85, 0.9, 0.95, 0.98, 1.0, 1.02)
    steps, dmt = sphere_cycle(law, tabor, tao_type, fractions)
    p_off, bracketed = pull_off_pressure(steps)
    assert bracketed and low <= -p_off / dmt < high
    assert steps[-1]["pull_off_pressure"] == p_off
    beyond = [s for s in steps if s["nominal_pressure"] < p_off]
    assert beyond and all(s["verification"].startswith("pulled off") for s in beyond)
    held = [s for s in steps if s["converged"]]
    for s in held:  # force balance: the wall's mean reaction less the mean attraction is p0
        assert s["force_balance"] < 1e-6 and s["min_gap"] >= 0


def test_displacement_control_reaches_the_load_controlled_pull_off():
    """At ``mu = 2`` the sphere held by the loading machine at prescribed mean gaps, down and
    back up past the load-controlled pull-off, stays in contact (the machine holds the branch
    that load control leaves): every mean gap within 1e-6, the most tensile pressure within
    the load-controlled bracket (0.80 held, 0.85 pulled off, of ``2 pi R w``) and the
    path reversible (the same pressure down and up, to the tolerance's 1e-6 of ``P``)."""
    n = 128
    grid = Grid(n, 1.0)
    x = (np.arange(n) + 0.5) / n - 0.5
    h = -(x[:, None] ** 2 + x[None, :] ** 2) / 2
    w = np.sqrt(2.0**3 * RHO**3)
    gaps = [0.08, 0.07, 0.075, 0.08, 0.0825, 0.085, 0.09]
    with scoped_options(["-tao_type", "blmvm"]):
        problem = AdhesivePeriodicProblem(
            grid, make_fft(grid), h, 1.0, Adhesion("exponential", w, RHO), PetscBackend()
        )
        steps = [s.scalars for s in adhesive_mean_gap_sweep(problem, gaps)]
    assert all(s["converged"] and s["mean_gap_mismatch"] <= 1e-6 for s in steps)
    assert all(s["area_fraction"] > 0 for s in steps)
    assert 0.80 < -pull_off_pressure(steps)[0] / (2 * np.pi * w) < 0.85
    assert steps[3]["nominal_pressure"] == pytest.approx(steps[0]["nominal_pressure"], rel=1e-5)


def test_a_mean_gaps_counts_cover_all_its_solves(rough):
    """Every solve of a prescribed mean gap (the loading machine's corrections) is counted:
    BLMVM evaluates the objective at least once an iteration (its line search), so the sums
    keep ``iterations <= evaluations <= 3 iterations`` (More-Thuente's 1.4-2.2 measured; a
    line search that backtracks on every step, as Armijo's does here, takes 5-7), and
    applies its ``H0`` once an iteration (and at a reset): one FFT pair of the preconditioner,
    two in its Schur and two-level forms, so at most two pairs an iteration (1.0-1.83
    measured)."""
    grid, h = rough
    rms = float(np.sqrt(np.mean(h**2)))
    with scoped_options(["-tao_type", "blmvm"]):
        problem = AdhesivePeriodicProblem(
            grid, make_fft(grid), h, 1.0, Adhesion("exponential", 1e-4, 5e-3), PetscBackend()
        )
        steps = [s.scalars for s in adhesive_mean_gap_sweep(problem, [1.2 * rms, 0.6 * rms])]
    for s in steps:
        assert s["converged"], s["verification"]
        its = s["iterations"]
        assert its <= s["objective_gradient_evaluations"] <= 3 * its
        assert s["preconditioner_applications"] <= 2 * its


def test_the_anchor_follows_the_branchs_tangent():
    """The first anchor's pressure: none before a step, the last one after one, then the
    tangent through the last two (exact on a straight branch)."""

    def steps(*branch):
        return [{"target_mean_gap": g, "nominal_pressure": p, "converged": True} for g, p in branch]

    assert predicted_pressure([], 1.0) == 0.0
    assert predicted_pressure(steps((2.0, -1.0)), 1.0) == -1.0
    assert predicted_pressure(steps((3.0, -2.0), (2.0, -1.0)), 0.5) == pytest.approx(0.5, rel=1e-15)
    unconverged = [*steps((3.0, -2.0), (2.0, -1.0)), {**steps((1.0, 9.0))[0], "converged": False}]
    assert predicted_pressure(unconverged, 0.5) == pytest.approx(0.5, rel=1e-15)


def test_a_jump_of_the_contact_area_is_flagged():
    """A converged step whose area misses its branch's tangent through the last two steps by
    more than half the larger area is a branch jump, warned about; one on the tangent, one
    whose area is the last one's (still out of contact after a jump out of it), one that did
    not converge, or the first, is not."""
    scalars = {"area_fraction": 0.1, "converged": True, "nominal_pressure": -1e-3}
    with pytest.warns(BranchJump, match="jumped from 0.3 to 0.1"):
        note_jump(scalars, [(1e-3, 0.3)])
    assert scalars["branch_jump"]
    note_jump(scalars, [(3e-3, 0.5), (1e-3, 0.3)])  # on the tangent: 0.1 at -1e-3
    assert not scalars["branch_jump"]
    apart = {"area_fraction": 0.0, "converged": True, "nominal_pressure": -2e-3}
    note_jump(apart, [(0.0, 0.004), (-1e-3, 0.0)])  # off the tangent's -0.004, but still 0
    assert not apart["branch_jump"]
    note_jump(scalars, [])
    assert not scalars["branch_jump"]
    scalars["converged"] = False
    note_jump(scalars, [(1e-3, 0.9)])
    assert not scalars["branch_jump"]


COMMON = ("periodic", "--grid", "32", "--hurst", "0.8", "--rms-slope", "0.1")
ADHESIVE = ("--adhesion", "exponential", "--work-of-adhesion", "1e-4", "--interaction-range")


def test_a_load_cycle_on_the_command_line(tmp_path):
    """Loading then unloading into tension with ``-tao_type blmvm``: the file records the
    steps, the pull-off as it stands, and the steps that pulled off as not converged (the
    run's exit status 1 says some did not, as for any run)."""
    out = tmp_path / "cycle.h5"
    loads = "2e-2,1.5e-2,1e-2,5e-3,0,-1e-3,-5e-3"
    done = cli(*COMMON, "--pressures", loads, *ADHESIVE, "0.005", "-tao_type", "blmvm",
               "--output", str(out))  # fmt: skip
    assert done.returncode == 1 and "BranchJump" not in done.stderr, done.stderr
    assert "pulled off" in done.stdout
    with h5py.File(out) as f:
        p0 = f["nominal_pressure"][()]
        converged = f["converged"][()]
        pull_off = f["pull_off_pressure"][()]
    assert list(p0) == [2e-2, 1.5e-2, 1e-2, 5e-3, 0, -1e-3, -5e-3]
    assert converged[:5].all() and not converged[-1]
    assert pull_off[-1] == min(p0[converged]) < 0  # in contact at every converged step


def test_adhesion_with_the_packages_cg_is_refused(tmp_path):
    """The package's CG (the default solver) solves a QP: refused in one line naming blmvm."""
    done = cli(*COMMON, "--pressures", "1e-2", *ADHESIVE, "0.005",
               "--output", str(tmp_path / "x.h5"))  # fmt: skip
    assert done.returncode != 0 and "-tao_type blmvm" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize(
    ("fields", "words"),
    [
        ({"pressures": [-1e-3]}, "--pressures"),
        ({"pressures": [1e-3], "adhesion": "exponential"}, "--work-of-adhesion W"),
        ({"pressures": [1e-3], "work_of_adhesion": 1e-4}, "need --adhesion"),
        (
            {"pressures": [1e-3], "adhesion": "maugis", "work_of_adhesion": 1e-4,
             "interaction_range": 1e-3, "thickness": 0.1},
            "--thickness",
        ),
        (
            {"pressures": [1e-3], "adhesion": "maugis", "work_of_adhesion": -1e-4,
             "interaction_range": 1e-3},
            "--work-of-adhesion",
        ),
    ],
)  # fmt: skip
def test_what_adhesion_does_not_take_is_refused(fields, words):
    """Tension without an adhesive law, a law without its work and range (or those without
    it), a layer and a work that is not positive: one line naming the option."""
    with pytest.raises(ValueError, match=words):
        Run(grid=32, hurst=0.8, rms_slope=0.1, **fields)


def test_compare_on_an_adhesive_scene(tmp_path):
    """``compare --adhesion`` measures every solver against a tight ``blmvm`` reference: the
    bound solvers that converge reach it (pressure and mean gap within 1e-6: their tolerance
    is 1e-8 of the pressure scale, rms), the package's CG is refused in the file and the
    table with its one-line reason, and no solver counts as converged whose answer is not
    the reference's (``gpcg``, a QP solver, stops far from it and is not converged)."""
    out = tmp_path / "compare.h5"
    done = cli("compare", "--grid", "32", "--hurst", "0.8", "--rms-slope", "0.1",
               "--pressures", "1e-2", *ADHESIVE, "0.005", "--solvers", "blmvm,bncg,cg,gpcg",
               "--time-limit", "60", "--output", str(out))  # fmt: skip
    assert done.returncode == 1  # some solver did not converge: cg refused
    assert "refused: --adhesion" in done.stdout
    with h5py.File(out) as f:
        assert f.attrs["reference_natural_residual"] < 1e-10
        for name in ("blmvm", "bncg"):
            g = f[name]
            assert g.attrs["converged"], g.attrs["verification"]
            assert g["pressure_error"][-1] < 1e-6 and g["mean_gap_error"][-1] < 1e-6
        assert not f["cg"].attrs["converged"] and f["cg"].attrs["iterations"] == 0
        assert f["cg"].attrs["reason"].startswith("refused: --adhesion")
        gpcg = f["gpcg"]
        assert gpcg.attrs["converged"] == (gpcg["pressure_error"][-1] < 1e-6)
