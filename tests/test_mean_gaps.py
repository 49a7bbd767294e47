"""Displacement control on the periodic cell (``--mean-gaps``, ``Run(mean_gaps=...)``): the
nominal pressure found by Newton's steps is the load-controlled one, Westergaard's on a
sinusoid, the same on the package's solver and TAO's, with the load-controlled stiffness;
it resumes exactly, and a mean gap no load reaches is refused in one line."""

from __future__ import annotations

import subprocess
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import cli

from petsc_contact import Run, run_contact
from petsc_contact.conventions.warnings import Unconverged
from petsc_contact.reference import westergaard
from petsc_contact.workflows.periodic_steps import MEAN_GAP_RTOL

SURFACE = {"grid": 64, "hurst": 0.7, "rms_slope": 0.1, "seed": 3}
GAPS = (8e-3, 4e-3, 1e-3)  # h_rms = 6.5e-3 on this surface: first touch at 1.25e-2


def _table(run: Run):
    result = run_contact(run)
    assert result.status == "complete"
    return result.to_dataframe()


@pytest.fixture(scope="module")
def by_gap():
    """The rough surface at :data:`GAPS`, with its fields, on the package's own solver."""
    return run_contact(Run(**SURFACE, mean_gaps=GAPS, fields=True, device="cpu-array"))


def test_the_load_controlled_answer_is_found_again(by_gap) -> None:
    """Load control at the pressures displacement control found gives back the prescribed mean
    gaps, the same gap fields and the same stiffness.

    Newton stops within ``MEAN_GAP_RTOL`` (1e-6) of each mean gap; the load-controlled solve at
    the same ``p0`` is converged to ``-tao_gatol 1e-8`` (pressures to 1e-8 ``p0``), which
    moves ``u_bar`` by about ``1e-8 u0`` (``u0 = p0/K``, at most ``1.6 u_bar`` here), so the
    mean gaps agree to ``2e-6``.  The gap fields differ by the same change of load over the
    stiffness, ``1e-6 u_bar`` in rms; the held-set stiffness is a linear solve to ``1e-8`` on
    a contact set that the two solutions share, so it agrees to ``1e-6``."""
    table = by_gap.to_dataframe()
    assert table["converged"].all() and table["accurate"].all()
    assert np.all(table["mean_gap_mismatch"] <= MEAN_GAP_RTOL)
    assert np.all(table["mean_gap_tolerance"] == MEAN_GAP_RTOL)
    assert list(table["target_mean_gap"]) == list(GAPS)
    pressures = tuple(table["nominal_pressure"])
    assert all(
        a < b for a, b in zip(pressures[:-1], pressures[1:], strict=True)
    )  # smaller gap, more load
    loaded = run_contact(Run(**SURFACE, pressures=pressures, fields=True, stiffness=True))
    for gap, mine, theirs in zip(GAPS, by_gap.steps, loaded.steps, strict=True):
        assert theirs.scalars["mean_gap"] == pytest.approx(gap, rel=2e-6)
        assert np.sqrt(np.mean((mine.gap - theirs.gap) ** 2)) < 1e-6 * gap
        assert np.array_equal(mine.contact, theirs.contact)
        k = theirs.scalars["stiffness"]
        assert mine.scalars["stiffness"] == pytest.approx(k, rel=1e-6)


def test_the_nominal_pressure_of_a_load_controlled_step_is_found_again() -> None:
    """A load-controlled step at ``p0`` has the mean gap ``g0``; displacement control at
    ``g0`` returns ``p0``: ``dp0/p0 = (du_bar/u_bar) (u_bar/u0)``, with ``du_bar/u_bar`` at most
    1e-6 (Newton) plus 1e-8 (each solve) and ``u_bar/u0`` below 3 at these loads."""
    p0 = (2e-3, 2e-2)
    loaded = _table(Run(**SURFACE, pressures=p0))
    found = _table(Run(**SURFACE, mean_gaps=tuple(loaded["mean_gap"])))
    assert np.allclose(found["nominal_pressure"], p0, rtol=5e-6, atol=0)
    assert np.all(found["newton_iterations"] >= 1)


def test_westergaard() -> None:
    """A sinusoid ``Delta cos(2 pi x/L)``: at Westergaard's mean gap
    ``u_bar = Delta (1 - r + r ln r)`` the nominal pressure is ``r p*``.  On 256 pixels a
    wavelength the discrete mean gap at the exact ``r p*`` is within 2.3e-4 of it (measured:
    2.8e-5, 4.8e-5, 2.2e-4 at r = 0.05, 0.3, 0.7), which moves ``p0`` by that times
    ``u_bar K/p0`` (5.3, 0.9 and 0.2), so ``p0`` is within 1e-3 of ``r p*`` (measured 1.5e-4,
    4.5e-5, 4.4e-5); the stiffness within 3% of ``p*/(Delta ln(1/r))`` (the contact edge's
    discretisation, measured 0.2 to 2%)."""
    n, delta, length, modulus = 256, 0.01, 1.0, 2.0
    x = np.arange(n) * length / n
    heights = np.repeat(delta * np.cos(2 * np.pi * x / length)[:, None], 4, axis=1)
    p_star = westergaard.full_contact_pressure(delta, length, modulus)
    ratios = np.array([0.05, 0.3, 0.7])
    gaps = tuple(westergaard.mean_gap(r * p_star, delta, length, modulus) for r in ratios)
    cell = {"heights": heights, "length": (length, 4 * length / n), "modulus": modulus}
    table = _table(Run(**cell, mean_gaps=gaps))
    assert table["converged"].all()
    assert np.allclose(table["nominal_pressure"], ratios * p_star, rtol=1e-3, atol=0)
    k = [westergaard.stiffness(r * p_star, delta, length, modulus) for r in ratios]
    assert np.allclose(table["stiffness"], k, rtol=0.03, atol=0)


@pytest.mark.parametrize("options", [(), ("-tao_type", "bnls"), ("-tao_type", "tron")])
def test_the_package_solver_and_tao_agree(by_gap, options: tuple[str, ...]) -> None:
    """The package's CG on NumPy arrays (``cpu-array``, no PETSc) gave :data:`GAPS`' pressures;
    TAO's types find them too, each to its Newton tolerance: ``dp0/p0`` at most ``1e-6
    u_bar/u0`` from each, ``u_bar/u0`` below 3 here."""
    mine = by_gap.to_dataframe()
    theirs = _table(Run(**SURFACE, mean_gaps=GAPS, options=options))
    assert theirs["converged"].all() and np.all(theirs["mean_gap_mismatch"] <= MEAN_GAP_RTOL)
    assert np.allclose(theirs["nominal_pressure"], mine["nominal_pressure"], rtol=6e-6, atol=0)
    assert np.allclose(theirs["stiffness"], mine["stiffness"], rtol=1e-5, atol=0)


def test_a_resumed_run_goes_on_exactly(tmp_path: Path) -> None:
    """Paused after its first mean gap, the run goes on from its saved state and load path as
    if it had not stopped: the same Newton steps and iterations, the same pressures to
    rounding (the state is stored in lengths, solved in units of h_rms: 1e-16 amplified by the
    operator's condition number, about 1e4 here, x 100, as tests/kill_at.py's ``EXACT``); a
    changed list of mean gaps is refused in one line."""
    whole = _table(Run(**SURFACE, mean_gaps=GAPS))
    run = Run(**SURFACE, mean_gaps=GAPS, output=str(tmp_path / "g.h5"))
    assert run_contact(run.with_(stop_after=0)).status == "paused"
    with pytest.raises(ValueError, match=r"different parameters \(mean_gaps\)") as caught:
        run_contact(run.with_(mean_gaps=(8e-3, 5e-3, 1e-3), resume=True))
    assert "\n" not in str(caught.value)
    resumed = _table(run.with_(resume=True))
    assert np.allclose(resumed["nominal_pressure"], whole["nominal_pressure"], rtol=1e-10, atol=0)
    for name in ("newton_iterations", "iterations"):
        assert np.array_equal(resumed[name], whole[name])


def test_near_first_touch_the_mean_gap_is_out_of_reach() -> None:
    """A mean gap ``1e-9`` of itself below first touch needs an approach the smallest nominal
    pressure double precision resolves on the surface overshoots: not converged, saying so.
    ``1e-6`` below first touch is reached, to about ``MEAN_GAP_RTOL`` of that approach
    (Newton's tolerance is relative to the nearer of the mean gap and the approach; it stops
    earlier where a solve accepts its warm start, here at 1.2e-6 of it)."""
    heights = 1e-3 * np.random.default_rng(1).standard_normal((32, 32))
    largest = heights.max() - heights.mean()
    gaps = (largest * (1 - 1e-9), largest * (1 - 1e-6))
    with pytest.warns(Unconverged, match="1 of 2"):
        table = _table(Run(heights=heights, length=1.0, mean_gaps=gaps))
    assert not table["converged"][1]
    assert "out of reach" in table["verification"][1]
    assert "smallest this surface resolves" in table["verification"][1]
    assert table["converged"][2] and table["mean_gap_mismatch"][2] <= 1e-5
    assert abs(table["mean_gap"][2] - gaps[1]) <= 1e-5 * 1e-6 * largest


def _refused(r: subprocess.CompletedProcess, *words: str) -> None:
    """Exit status 2 with one error line naming every word."""
    assert r.returncode == 2, r.stderr
    errors = [line for line in r.stderr.splitlines() if "error:" in line]
    assert len(errors) == 1 and "Traceback" not in r.stderr, r.stderr
    for word in words:
        assert word in errors[0], (word, r.stderr)


def test_the_command_line_and_its_refusals(tmp_path: Path) -> None:
    """``periodic --mean-gaps`` in the unit of ``--length``; a mean gap at or above first touch
    (``max(h) - mean(h)``), zero or negative, beside another load or on the punch is refused
    in one line."""
    scene = ["periodic", "--grid", "32", "--hurst", "0.7", "--rms-slope", "0.1"]
    out = tmp_path / "g.h5"
    r = cli(*scene, "--length", "1um", "--mean-gaps", "4nm,0.002", "--output", str(out))
    assert r.returncode == 0, r.stderr
    header = next(line for line in r.stdout.splitlines() if line.split()[:1] == ["step"])
    end = header.index(" target") + len(" target")  # right-aligned, 12 wide
    rows = [line for line in r.stdout.splitlines() if line.split()[:1] in (["1/2"], ["2/2"])]
    assert [row[end - 12 : end].strip() for row in rows] == ["4 nm", "2 nm"]
    with h5py.File(out) as f:
        assert list(f["target_mean_gap"][:]) == pytest.approx([4e-3, 2e-3], rel=1e-12)
        assert f["mean_gap"].attrs["units"] == "um"
        assert np.all(f["mean_gap_mismatch"][:] <= MEAN_GAP_RTOL)
        assert np.all(f["stiffness"][:] > 0)
    other = ["--output", str(tmp_path / "no.h5")]
    _refused(cli(*scene, *other, "--mean-gaps", "1"), "mean gap 1", "first touch")
    _refused(cli(*scene, *other, "--mean-gaps", "0"), "--mean-gaps")
    _refused(cli(*scene, *other, "--mean-gaps", "-1e-3"), "--mean-gaps")
    _refused(cli(*scene, *other, "--mean-gaps", "1e-3", "--pressures", "1e-2"), "--mean-gaps")
    punch = ["punch", "--grid", "32", "--hurst", "0.7", "--rms-slope", "0.1", *other]
    _refused(cli(*punch, "--approaches", "1e-3", "--mean-gaps", "1e-3"), "--mean-gaps")
    assert not (tmp_path / "no.h5").exists()
    for given in ({"pressures": 1e-2}, {"sweep": 4}, {"geometry": "punch"}, {"hardness": 0.5}):
        with pytest.raises(ValueError, match="--mean-gaps") as caught:
            Run(**SURFACE, mean_gaps=1e-3, **given)
        assert "\n" not in str(caught.value)
