"""Adhesion on the punch: the free half-space's padded cell, the weak-adhesion limit (the
hard-wall punch), a sphere's pull-off between Maugis' JKR and DMT limits with no periodic
images, the approach-controlled cycle, and the command line."""

import h5py
import numpy as np
import pytest
from conftest import cli

from petsc_contact import punch_contact
from petsc_contact.backend._petsc import scoped_options
from petsc_contact.backend.tao import PetscBackend
from petsc_contact.conventions.grid import Grid
from petsc_contact.geometries.adhesive_punch import AdhesivePunchProblem
from petsc_contact.interactions.adhesion import Adhesion
from petsc_contact.workflows.adhesive_steps import BranchJump, adhesive_sweep, pull_off_pressure
from petsc_contact.workflows.compare import AdhesivePunchPosed, compare

RHO = 0.01  # the sphere's interaction range (1.28 pixels at 128^2)


def sphere(n):
    """A paraboloid ``R = 1`` on an ``n x n`` unit footprint (its apex at the centre)."""
    x = (np.arange(n) + 0.5) / n - 0.5
    return -(x[:, None] ** 2 + x[None, :] ** 2) / 2


def sphere_problem(law, tabor, n=128):
    """The sphere's problem at the Tabor parameter ``mu = (R w^2 / (E*^2 rho^3))^(1/3)``
    and ``2 pi R w``, DMT's pull-off."""
    w = np.sqrt(tabor**3 * RHO**3)
    problem = AdhesivePunchProblem(Grid(n, 1.0), sphere(n), 1.0, Adhesion(law, w, RHO),
                                   backend=PetscBackend())  # fmt: skip
    return problem, 2 * np.pi * w


@pytest.mark.parametrize("tao_type", ["blmvm", "bncg"])
def test_weak_adhesion_is_the_hard_wall_punch(tao_type):
    """At ``w = 1e-12`` the sphere pressed by the same forces reaches the hard-wall punch's
    approach, mean gap and contact area.  The attraction's own share of the force is
    ``w dF/dw`` (3e-8 of it: ``w = 1e-6`` moves the approach by 1-3%, which the check must
    see, 100 times its tolerance); what
    is left is the hard-wall punch's accuracy at its default tolerance (a gap residual of
    ``1e-8 l``): its force Newton reaches to ``1e-6``, so approach and mean gap to ``1e-5``."""
    h, forces = sphere(64), [1.2e-4, 3.5e-4]
    wall = punch_contact(h, length=1.0, forces=forces, progress=False)
    given = {"options": ["-tao_type", tao_type], "adhesion": "exponential"}
    found = {}
    for w in (1e-12, 1e-6):
        found[w] = punch_contact(h, length=1.0, forces=forces, progress=False, **given,
                                 work_of_adhesion=w, interaction_range=1e-3)  # fmt: skip
    for ref, weak, strong in zip(wall, found[1e-12], found[1e-6], strict=True):
        assert weak.converged and strong.converged, weak.scalars["verification"]
        for name in ("approach", "mean_gap"):
            assert weak.scalars[name] == pytest.approx(ref.scalars[name], rel=1e-5)
        assert weak.scalars["area_fraction"] == ref.scalars["area_fraction"]
        assert weak.scalars["force"] == pytest.approx(ref.scalars["force"], rel=1e-5)
        assert abs(strong.scalars["approach"] / ref.scalars["approach"] - 1) > 1e-3


def test_the_approach_is_what_was_prescribed():
    """Under displacement control the approach measured from the solution (the mean mode of
    the padded cell, ``mean(p)/c0 - mean(u - δ)``) is the one prescribed, to rounding."""
    problem, _ = sphere_problem("exponential", 1.0, n=32)
    with scoped_options(["-tao_type", "blmvm"]):
        steps = list(adhesive_sweep(problem, [1e-2, 0.0, -2e-3], approach=problem.set_approach))
    for delta, step in zip([1e-2, 0.0, -2e-3], steps, strict=True):
        assert step.converged and abs(step.scalars["approach"] - delta) < 1e-12


FRACTIONS = (0.0, 0.5, 0.7, 0.74, 0.76, 0.78, 0.8, 0.85, 0.9, 0.95, 0.98, 1.0, 1.02)


@pytest.mark.parametrize(
    ("law", "tabor", "tao_type", "low", "high"),
    [
        ("exponential", 0.1, "blmvm", 0.95, 1.0),
        ("maugis", 0.1, "bncg", 0.9, 1.0),
        ("exponential", 2.0, "blmvm", 0.75, 0.85),
    ],
)
def test_a_spheres_pull_off_lies_between_jkr_and_dmt(law, tabor, tao_type, low, high):
    """The pull-off force of a sphere on the free half-space (Maugis 1992), unloaded under
    load control from half DMT's ``2 pi R w``: at ``mu = 0.1`` the rigid sphere's Derjaguin
    force within the load step (5%, 10% for the smoothed Maugis law), at ``mu = 2`` strictly
    between JKR's ``1.5 pi R w`` and DMT's.  The steps beyond it are not converged and say
    ``pulled off``; it is bracketed; the force balances (no traction off the face)."""
    problem, dmt = sphere_problem(law, tabor)
    loads = [0.5 * dmt] + [-f * dmt for f in FRACTIONS]
    with scoped_options(["-tao_type", tao_type]):
        steps = [s.scalars for s in adhesive_sweep(problem, loads)]
    p_off, bracketed = pull_off_pressure(steps)
    assert bracketed and low <= -p_off / dmt < high
    beyond = [s for s in steps if s["nominal_pressure"] < p_off]
    assert beyond and all(s["verification"].startswith("pulled off") for s in beyond)
    for s in (s for s in steps if s["converged"]):
        assert s["force_balance"] < 1e-6 and s["min_gap"] >= 0


def test_the_approach_controlled_cycle_passes_the_load_controlled_pull_off():
    """At ``mu = 2`` the sphere pulled back by its approach holds on past the load-controlled
    pull-off (the rigid punch holds the branch that load control leaves): its most tensile
    force lies in load control's bracket (0.78 held, 0.80 pulled off, of ``2 pi R w``); the
    path is reversible (the same force at the same approach, to 1e-6 of it: the tolerance's
    1e-8 of ``P`` over the footprint); then it jumps out of contact (the area falls from a
    tenth to 0 and the force to a few % of the pull-off), a branch jump its force tells and
    warns of (its area's tangent, steep there, predicts little contact)."""
    problem, dmt = sphere_problem("exponential", 2.0)
    approaches = [0.02, 0.0, -0.01, -0.02, -0.03, -0.01, -0.02, -0.04, -0.06]
    with scoped_options(["-tao_type", "blmvm"]), pytest.warns(BranchJump, match="force"):
        steps = [s.scalars for s in adhesive_sweep(problem, approaches,
                                                   approach=problem.set_approach)]  # fmt: skip
    assert all(s["converged"] for s in steps)
    assert 0.78 < -steps[-1]["pull_off_pressure"] * problem.face_area / dmt < 0.80
    for first, again in ((2, 5), (3, 6)):
        assert steps[again]["force"] == pytest.approx(steps[first]["force"], rel=1e-6)
    assert not any(s["branch_jump"] for s in steps[:7]) and steps[6]["area_fraction"] > 0.1
    assert steps[7]["area_fraction"] == 0 and abs(steps[7]["force"]) < 0.05 * dmt
    assert steps[7]["branch_jump"]
    assert steps[8]["area_fraction"] == 0 and not steps[8]["branch_jump"]  # stays apart


def test_an_adhesive_punch_on_the_command_line(tmp_path):
    """``petsc-contact punch --adhesion`` presses and pulls back by its approaches with
    ``-tao_type bncg``: the file records the steps with their forces in tension and the
    pull-off as it stands; the package's CG is refused in one line."""
    common = ("punch", "--grid", "32", "--hurst", "0.8", "--rms-slope", "0.1",
              "--adhesion", "exponential", "--work-of-adhesion", "1e-4",
              "--interaction-range", "0.005", "--approaches", "0.03,0.01,-0.002")  # fmt: skip
    out = tmp_path / "punch.h5"
    done = cli(*common, "-tao_type", "bncg", "--output", str(out))
    assert done.returncode == 0, done.stderr
    with h5py.File(out) as f:
        force, approach = f["force"][()], f["approach"][()]
        assert f["converged"][()].all() and f["pull_off_pressure"][-1] < 0
    assert force[0] > 0 > force[-1]
    assert np.allclose(approach, [0.03, 0.01, -0.002], rtol=0, atol=1e-12)
    refused = cli(*common, "--output", str(tmp_path / "x.h5"))
    assert refused.returncode != 0 and "-tao_type blmvm" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1
    paused = cli(*common, "-tao_type", "bncg", "--output", str(out), "--overwrite",
                 "--stop-after", "0")  # fmt: skip
    assert paused.returncode == 75 and not (tmp_path / "punch.h5.state.npz").exists()
    resumed = cli(*common, "-tao_type", "bncg", "--output", str(out), "--resume")
    assert resumed.returncode == 2 and "it is not resumed" in resumed.stderr


def test_compare_on_an_adhesive_punch():
    """``compare`` on the sphere's adhesive punch (32^2, ``mu = 1``, at a fifth of DMT's
    pull-off in compression): ``blmvm`` and ``bncg`` reach the tight ``blmvm`` reference
    (pressure and mean gap within 1e-6: their tolerance is 1e-8 of the pressure scale,
    rms), and ``pk``, the package's CG, is refused, a failed solver saying why."""
    problem, dmt = sphere_problem("exponential", 1.0, n=32)
    posed = AdhesivePunchPosed(problem)
    reference, found = compare(posed, 0.2 * dmt, ["blmvm", "bncg", "pk"], time_limit=60)
    assert reference["natural_residual"] < 1e-10
    for t in found[:2]:
        assert t.converged, t.verification
        assert t.pressure_error[-1] < 1e-6 and t.mean_gap_error[-1] < 1e-6
    assert not found[2].converged and found[2].reason.startswith("refused: --adhesion")
