"""The adhesive periodic cell through a cycle: the load cycle a ``--sweep`` is, the energy a
displacement-controlled cycle loses, and Johnson's (1995) adhesive wave in the JKR limit."""

import json
import signal
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pytest
from conftest import ROOT, cli, python
from kill_at import EXACT

from petsc_contact import Run, run_contact
from petsc_contact.backend._petsc import scoped_options
from petsc_contact.backend.tao import PetscBackend
from petsc_contact.conventions.grid import Grid
from petsc_contact.devices.fft import make_fft
from petsc_contact.geometries.adhesive_periodic import AdhesivePeriodicProblem
from petsc_contact.geometries.periodic import PeriodicProblem
from petsc_contact.interactions.adhesion import Adhesion
from petsc_contact.reference import johnson_wavy, westergaard
from petsc_contact.workflows.adhesive_steps import (
    BranchJump,
    adhesive_mean_gap_sweep,
    adhesive_sweep,
    hysteresis_energy,
)
from petsc_contact.workflows.description import cycled
from petsc_contact.workflows.periodic_steps import sweep


def test_an_adhesive_sweep_is_a_load_cycle():
    """``N,PMIN,PMAX``: N equal steps up to PMAX, N equal steps down to PMIN."""
    assert cycled((2, -1.0, 4.0)) == [2.0, 4.0, 1.5, -1.0]
    assert cycled((3, 1.0, 3.0)) == pytest.approx([1.0, 2.0, 3.0, 2 + 1 / 3, 1 + 2 / 3, 1.0])


@pytest.mark.parametrize(
    ("fields", "words"),
    [
        ({"sweep": (4, -1e-3, 1e-2)}, "adhesive load cycle's"),
        ({"sweep": (4, -1e-3, 1e-2), "geometry": "punch"}, "adhesive load cycle's"),
        ({"sweep": (4, -1e-3, -1e-4)}, "0 < PMIN < PMAX"),
    ],
)
def test_a_tensile_sweep_without_adhesion_is_refused(fields, words):
    """A tensile end is an adhesive cycle's: refused without ``--adhesion`` (and on the
    punch), as is a sweep with no compressive end, in one line naming the option."""
    with pytest.raises(ValueError, match=words):
        Run(grid=32, hurst=0.8, rms_slope=0.1, **fields)


COMMON = ("periodic", "--grid", "32", "--hurst", "0.8", "--rms-slope", "0.1")
ADHESIVE = ("--adhesion", "exponential", "--work-of-adhesion", "1e-4", "--interaction-range")


def test_a_sweep_with_adhesion_cycles_on_the_command_line(tmp_path):
    """``--sweep 4,-6e-3,2e-2`` with adhesion: loading to 2e-2, unloading into tension, the
    file records the cycle's pressures, every step of the cycle that held converged, the
    pull-off as it stands printed after the table; a sweep without its bounds is refused."""
    out = tmp_path / "cycle.h5"
    done = cli(*COMMON, "--sweep", "4,-6e-3,2e-2", *ADHESIVE, "0.005", "-tao_type", "blmvm",
               "--output", str(out))  # fmt: skip
    with h5py.File(out) as f:
        p0 = f["nominal_pressure"][()]
        converged = f["converged"][()]
        pull_off = f["pull_off_pressure"][()]
    assert p0 == pytest.approx([5e-3, 1e-2, 1.5e-2, 2e-2, 1.35e-2, 7e-3, 5e-4, -6e-3])
    assert converged[:7].all(), done.stdout
    assert pull_off[6] == p0[6] and f"pull_off_pressure = {pull_off[-1]:.6g}" in done.stdout
    bare = cli(*COMMON, "--sweep", "4", *ADHESIVE, "0.005", "--output", str(tmp_path / "b.h5"))
    assert bare.returncode == 2 and "give N,PMIN,PMAX" in bare.stderr


LOOP = [round(0.12 - 0.005 * k, 4) for k in range(13)]  # 0.12 down to 0.06: first touch at 1/12
LOOP += LOOP[-2::-1]  # and back


def sphere_loop(tabor, gaps=LOOP, n=64, rho=0.02):
    """The steps of a sphere ``R = 1`` in a unit cell (``n^2``) with Maugis' law of range
    ``rho`` (1.28 pixels) and ``w`` from the Tabor parameter ``(R w^2 / (E*^2 rho^3))^(1/3)``,
    held by the loading machine at ``gaps``, and ``w``."""
    grid = Grid(n, 1.0)
    x = (np.arange(n) + 0.5) / n - 0.5
    h = -(x[:, None] ** 2 + x[None, :] ** 2) / 2
    w = np.sqrt(tabor**3 * rho**3)
    with scoped_options(["-tao_type", "blmvm"]):
        law = Adhesion("maugis", w, rho)
        problem = AdhesivePeriodicProblem(grid, make_fft(grid), h, 1.0, law, PetscBackend())
        return [s.scalars for s in adhesive_mean_gap_sweep(problem, gaps)], w


def test_weak_adhesion_loses_no_energy_around_a_cycle():
    """At Tabor parameter 0.1 the attraction deforms the sphere far less than its range: one
    branch, retraced, so the loop encloses only the solve's tolerance, ``1e-6 P`` per step
    over the 0.12 of travel: ``1e-7 P``, ``2e-5 w`` (``P = w/rho``; tested: ``1e-4 w``).
    Each step records the loop's energy as it stands: NaN until the first mean gap is
    reached again."""
    steps, w = sphere_loop(0.1)
    assert all(s["converged"] for s in steps)
    assert np.isnan([s["hysteresis_energy"] for s in steps[:-1]]).all()
    assert abs(steps[-1]["hysteresis_energy"]) < 1e-4 * w
    assert steps[-1]["hysteresis_energy"] == hysteresis_energy(steps)


def test_a_jump_in_and_a_pull_off_lose_energy_but_less_than_the_work_of_adhesion():
    """At Tabor parameter 1 the sphere jumps into contact on the approach and is pulled off
    on the retraction at a larger mean gap, both flagged: the loop loses energy.  It is the
    cycle's total energy (``elastic_energy + interaction_energy``) just before the pull-off
    less that just after the jump in, to the work along the two steps that hold a jump (at
    most the step times the larger pressure of each; the branches' trapezoids are far
    closer).  The first is at most 0 (measured), the second at least ``-w f`` (the
    interaction energy is at least ``-w`` on the area ``f`` it acts on, within the range of
    contact): the loss is positive and at most ``w f`` with ``f`` the largest contact area
    (measured: 0.17 ``w f``)."""
    with pytest.warns(BranchJump):
        steps, w = sphere_loop(1.0)
    assert all(s["converged"] for s in steps)
    jumps = [k for k, s in enumerate(steps) if s["branch_jump"]]
    assert len(jumps) == 2 and jumps[0] < len(LOOP) // 2 < jumps[1]
    energy = [s["elastic_energy"] + s["interaction_energy"] for s in steps]
    u = np.array([s["mean_gap"] for s in steps])
    p0 = np.array([s["nominal_pressure"] for s in steps])
    chords = sum(abs(u[k] - u[k - 1]) * max(abs(p0[k]), abs(p0[k - 1])) for k in jumps)
    lost = steps[-1]["hysteresis_energy"]
    before_pull_off, after_jump_in = energy[jumps[1] - 1], energy[jumps[0]]
    assert before_pull_off <= 0
    assert abs(lost - (before_pull_off - after_jump_in)) <= chords
    f = max(s["area_fraction"] for s in steps)
    assert 0.01 * w * f < lost <= -after_jump_in + chords <= w * f


def test_johnsons_wave_is_westergaards_without_adhesion_and_jkrs_when_narrow():
    """At ``w = 0`` the stable branch is all of Westergaard's: the same half-width at every
    pressure; for ``a << L`` the JKR cylinder's of ``R = L^2/(4 pi^2 Delta)`` per wavelength
    (the next terms are ``(a/L)^2`` smaller: 4e-4 at ``a = L/100``); the pull-off is the
    branch's lowest pressure, and the half-width at a pressure is the root there."""
    amp, lam, modulus, w = 0.01, 2.0, 3.0, 2e-5
    for p0 in (1e-4, 1e-3, 1e-2):
        a = westergaard.half_width(p0, amp, lam, modulus)
        assert johnson_wavy.half_width(p0, amp, lam, modulus, 0.0) == pytest.approx(a, rel=1e-12)
        assert johnson_wavy.mean_pressure(a, amp, lam, modulus, 0.0) == pytest.approx(p0, rel=1e-12)
    a, radius = lam / 100, lam**2 / (4 * np.pi**2 * amp)
    jkr = np.pi * modulus * a**2 / (4 * radius) - np.sqrt(2 * np.pi * modulus * w * a)
    assert johnson_wavy.mean_pressure(a, amp, lam, modulus, w) * lam == pytest.approx(jkr, rel=1e-3)
    a_off, a_max = johnson_wavy.stable_branch(amp, lam, modulus, w)
    p_off = johnson_wavy.pull_off(amp, lam, modulus, w)
    for a in (0.99 * a_off, 1.01 * a_off):
        assert johnson_wavy.mean_pressure(a, amp, lam, modulus, w) > p_off
    p0 = 0.5 * p_off
    a = johnson_wavy.half_width(p0, amp, lam, modulus, w)
    assert a_off < a < a_max
    assert johnson_wavy.mean_pressure(a, amp, lam, modulus, w) == pytest.approx(p0, rel=1e-10)
    with pytest.raises(ValueError, match="off the stable branch"):
        johnson_wavy.half_width(1.01 * p_off, amp, lam, modulus, w)


WAVE = 0.01, 1.0, 1.0, 2e-5  # Johnson's wave: amplitude, wavelength, E*, w (p* = 0.0314)


def wave_cycle(n, rho, loads):
    """The wave on ``n x 4`` square pixels with Maugis' law of range ``rho``: the steps of
    ``loads`` from the hard wall's contact at the first (a start off the full contact that
    an attraction ``w/rho`` above ``p*`` also holds)."""
    amp, lam, modulus, w = WAVE
    grid = Grid((n, 4), (lam, 4 * lam / n))
    x = (np.arange(n) + 0.5) / n * lam
    h = np.repeat(amp * np.cos(2 * np.pi * x / lam)[:, None], 4, axis=1)
    with scoped_options(["-tao_type", "blmvm"]):
        wall = PeriodicProblem(grid, make_fft(grid), h, modulus, PetscBackend())
        (start,) = sweep(wall, loads[:1], fields=True)
        law = Adhesion("maugis", w, rho)
        problem = AdhesivePeriodicProblem(grid, make_fft(grid), h, modulus, law, PetscBackend())
        return [s.scalars for s in adhesive_sweep(problem, loads, start=start.gap)]


def test_the_adhesive_wave_approaches_johnsons_jkr_limit():
    """Loading to 0.012 and unloading into tension on the stable branch (0.38 p* down to
    -0.03 p*, the pull-off at -0.056 p*), the contact's half-width (half the area fraction
    times L) against Johnson's at each mean pressure.  The JKR limit is a crack tip; Maugis'
    law spreads it over the cohesive zone ``d = (pi/4) E* rho^2 / w`` (Dugdale's at ``K =
    sqrt(2 E* w)`` and the stress ``w/rho``), within which the contact edge lies: within
    ``d`` of Johnson's (measured: 0.42-0.53 d) where ``d`` spans 26 and 103 pixels (at fewer
    the discrete front moves it by more), and closer as ``rho`` shrinks (the JKR limit; by
    a factor 3 for 4 in ``d``)."""
    loads = [0.012, 0.006, 0.0, -0.001]
    n, misses = 4096, {}
    for rho in (8e-4, 4e-4):
        d = np.pi / 4 * WAVE[2] * rho**2 / WAVE[3]
        steps = wave_cycle(n, rho, loads)
        assert all(s["converged"] and not s["branch_jump"] for s in steps)
        a = np.array([s["area_fraction"] * WAVE[1] / 2 for s in steps])
        johnson = np.array([johnson_wavy.half_width(p0, *WAVE) for p0 in loads])
        misses[rho] = np.abs(a - johnson).max()
        assert misses[rho] < d and d > 20 * WAVE[1] / n
    assert misses[4e-4] < misses[8e-4] / 2


CYCLE = dict(grid=32, hurst=0.8, rms_slope=0.1, adhesion="exponential", work_of_adhesion=1e-4,
             interaction_range=5e-3, options=("-tao_type", "blmvm"))  # fmt: skip
LOAD_CYCLE = (4, -6e-3, 2e-2)  # loading to 2e-2, unloading to 5e-4 in contact, -6e-3 pulled off
APPROACH_RETRACT = (0.014, 0.008, 0.004, 0.008, 0.014)  # w = 1e-3: a loop of 3e-6 lost
PATH = ("preconditioner_applications", "objective_gradient_evaluations", "hessian_applications")
# a step's path inside the solver: its preconditioner keeps between solves the contact set it
# was last adapted to, which a resumed run's fresh solver has not (the pulled-off step of the
# load cycle applies it once more: 13 against 12)
RESIDUALS = ("force_balance", "kkt_residual", "gradient_norm", "mean_gap_mismatch")  # of P


def paused_at_every_step(out: Path, **run: Any) -> list[str]:
    """``run`` into ``out``, paused after every step (``stop_after=0``) and resumed until it
    is complete; the status of each call."""
    statuses = [run_contact(Run(**run, output=str(out), stop_after=0), progress=False).status]
    while statuses[-1] == "paused":
        resumed = Run(**run, output=str(out), resume=True, stop_after=0)
        statuses.append(run_contact(resumed, progress=False).status)
    return statuses


def _loop_work(f: h5py.File) -> float:
    """What bounds the change of a loop's lost energy when each step's ``p0`` and mean gap
    ``u`` change by a fraction of themselves: ``max|p0|`` times the sum of
    ``|u' - u| + |u| + |u'|`` over consecutive steps."""
    u, p0 = f["mean_gap"][()], f["nominal_pressure"][()]
    return float(np.abs(p0).max() * np.sum(np.abs(np.diff(u)) + np.abs(u[1:]) + np.abs(u[:-1])))


def same_datasets(whole: Path, cut: Path, rtol: float, unlike: tuple[str, ...] = ()) -> None:
    """Every dataset of run ``cut`` (paused or killed and resumed, each time from its saved
    state) that of the uninterrupted run ``whole`` but the solve times and ``unlike``: the
    same names, integers, flags and words exactly, numbers to ``rtol`` of the dataset's
    largest magnitude, the residuals (:data:`RESIDUALS`, fractions near zero) to ``rtol``,
    the mean gaps to ``rtol`` each, the loop's lost energy to ``rtol`` of the works it is the
    difference of (:func:`_loop_work`)."""
    with h5py.File(whole) as a, h5py.File(cut) as b:
        assert set(a) == set(b) and b.attrs["complete"]
        segments = json.loads(str(b.attrs["resumed"]))
        assert segments and all(s["from_saved_state"] for s in segments)
        for name in sorted(set(a) - {"solve_time", *unlike}):
            x, y = a[name][()], b[name][()]
            if x.dtype.kind == "f":
                scale = rtol * (1.0 if name in RESIDUALS else np.nanmax(np.abs(x), initial=0.0))
                if name == "hysteresis_energy":  # sum (p0 + p0') (u' - u) / 2 of p0 and u each
                    scale = rtol * _loop_work(a)  # to rtol: the works' size, not the loss's
                assert np.allclose(y, x, rtol=rtol, atol=scale, equal_nan=True), name
            else:
                assert np.array_equal(y, x), name
        assert np.allclose(b["mean_gap"][()], a["mean_gap"][()], rtol=rtol, atol=0)


def test_a_paused_load_cycle_goes_on_exactly(tmp_path):
    """The load cycle paused after every step (after the first, on the unloading branch and
    after the step that pulled off) and resumed from its saved gap, its history (the jumps
    and the pull-off are of every step) the committed table's: every dataset the
    uninterrupted run's, to rounding (:data:`~kill_at.EXACT`) and in iterations."""
    whole = tmp_path / "whole.h5"
    run_contact(Run(**CYCLE, sweep=LOAD_CYCLE, output=str(whole)), progress=False)
    statuses = paused_at_every_step(tmp_path / "cut.h5", **CYCLE, sweep=LOAD_CYCLE)
    assert statuses == ["paused"] * 7 + ["complete"]
    with h5py.File(whole) as f:  # the cycle tests what it should: a pull-off bracketed
        assert not f["converged"][-1] and f["pull_off_pressure"][-1] == f["nominal_pressure"][-2]
    same_datasets(whole, tmp_path / "cut.h5", EXACT, PATH)


def test_a_paused_approach_and_retraction_goes_on_to_the_same_loop(tmp_path):
    """Displacement control down and back up, paused after every step and resumed: every
    dataset the uninterrupted run's, the energy the loop lost (of every step) too.  Each
    step's loading machine takes a few hundred iterations, along which the saved gap's
    rounding (``g/l`` of ``g = x l``) and the fresh solver (:data:`PATH`) lead another way
    to the same point: to the machine's solves' tolerance (``1e-8`` of the pressure scale;
    measured: ``2e-12`` relative, ``1e-10`` in the loop's energy, a difference of nearly
    equal works), not in iterations."""
    gaps = dict(CYCLE, work_of_adhesion=1e-3, mean_gaps=APPROACH_RETRACT)
    whole = tmp_path / "whole.h5"
    run_contact(Run(**gaps, output=str(whole)), progress=False)
    assert paused_at_every_step(tmp_path / "cut.h5", **gaps)[-1] == "complete"
    with h5py.File(whole) as f:  # the retraction holds the most tensile step, the loop closes
        assert f["converged"][()].all() and f["hysteresis_energy"][-1] > 0
        assert np.argmin(f["pull_off_pressure"][()]) == 3
    same_datasets(whole, tmp_path / "cut.h5", 1e-8, ("iterations", *PATH))


def test_a_load_cycle_killed_on_its_unloading_branch_comes_back_whole(tmp_path):
    """SIGKILL once the state after the first unloading step is written (tests/kill_at.py):
    ``--resume`` ends the cycle as the uninterrupted run did, every dataset to rounding."""
    command = ["periodic", "--grid", "32", "--hurst", "0.8", "--rms-slope", "0.1", *ADHESIVE,
               "0.005", "--sweep", "4,-6e-3,2e-2", "-tao_type", "blmvm", "--quiet"]  # fmt: skip
    whole, out = tmp_path / "whole.h5", tmp_path / "cut.h5"
    assert cli(*command, "--output", str(whole)).returncode == 1  # the last step pulled off
    killed = python(str(ROOT / "tests" / "kill_at.py"), "after:state:5", "--", *command,
                    "--output", str(out))  # fmt: skip
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    assert cli(*command, "--output", str(out), "--resume").returncode == 1
    same_datasets(whole, out, EXACT, PATH)
