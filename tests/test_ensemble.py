"""Ensembles over seeds, power-law fits, and the experiment subcommand (paper Eq. C3)."""

import json

import h5py
import numpy as np
import pytest
from conftest import cli

from petsc_contact.paper.fits import ensemble_statistics, power_law_fit


def test_power_law_fit_exact_and_noisy():
    p = np.geomspace(1e-6, 1e-3, 10)
    fit = power_law_fit(p, 3.0 * p**0.62, points=4)
    assert fit.alpha == pytest.approx(0.62, rel=1e-12) and fit.alpha_error < 1e-12
    assert fit.prefactor == pytest.approx(3.0, rel=1e-10)
    # log-normal noise of 5%: the fitted slopes scatter by about the reported error
    rng = np.random.default_rng(0)
    fits = [
        power_law_fit(p, p**0.6 * np.exp(0.05 * rng.standard_normal(p.size)), points=6)
        for _ in range(400)
    ]
    alphas = np.array([f.alpha for f in fits])
    assert alphas.mean() == pytest.approx(0.6, abs=0.01)
    assert np.median([f.alpha_error for f in fits]) == pytest.approx(alphas.std(), rel=0.3)
    with pytest.raises(ValueError):
        power_law_fit(p[:3], p[:3], points=4)


def test_ensemble_statistics_skip_failed_steps():
    v = np.array([[1.0, 2.0], [3.0, np.nan], [5.0, 4.0]])
    s = ensemble_statistics(v)
    assert np.allclose(s["mean"], [3.0, 3.0])
    assert np.allclose(s["std"], [2.0, np.sqrt(2.0)])
    assert np.array_equal(s["count"], [3, 2])


def test_resolution_rule_counts_pixels_and_keeps_unresolved_loads_out_of_the_fit():
    """A load is resolved when every seed has at least 16 contact pixels, counted from the
    area fraction whatever its rounding (1536^2 is not a power of two); the fit of exact
    power laws ``K = c p^0.8`` over the resolved loads below ``p_c`` returns 0.8."""
    from petsc_contact.paper.figures import contact_resolved, finite_size_fit, resolved

    n = 1536
    pixels = np.array([[8, 15, 16, 40, 90, 200, 500, 2000], [9, 16, 17, 50, 99, 300, 700, 3000]])
    area = pixels / float(n * n)
    assert np.array_equal(resolved(area, n), pixels >= 16)
    assert np.array_equal(contact_resolved(area, n * n, 40), pixels >= 40)
    p = np.geomspace(1e-8, 1e-4, pixels.shape[1])
    curves = {
        "nominal_pressure": p,
        "area_fraction": area,
        "stiffness": np.array([2.0, 3.0])[:, None] * p**0.8,
    }
    fit = finite_size_fit(curves, n * n, crossover=3e-5)
    assert np.array_equal(fit["resolved"], pixels.min(axis=0) >= 16)  # the 15-pixel seed
    assert np.flatnonzero(fit["fitted"]).tolist() == [2, 3, 4, 5]
    assert fit["below_crossover"] == 4
    assert fit["alpha"] == pytest.approx(0.8, abs=1e-12)
    assert fit["alpha_interval"] == pytest.approx([0.8, 0.8], abs=1e-12)  # seeds that agree


def test_the_seed_bootstrap_spans_what_the_seeds_disagree_on():
    """Four seeds of exponents 0.6, 0.7, 0.8 and 0.9: the 68% interval of the averaged
    stiffness' exponent over resampled seeds lies inside the seeds' range and holds the
    average's own exponent; it narrows as the seeds agree more."""
    from petsc_contact.paper.figures import finite_size_fit

    n, p = 512, np.geomspace(1e-6, 1e-5, 4)
    curves = {"nominal_pressure": p, "area_fraction": np.full((4, 4), 0.01)}
    wide = finite_size_fit(curves | {"stiffness": p ** np.array([[0.6], [0.7], [0.8], [0.9]])},
                           n * n, crossover=1.0)  # fmt: skip
    low, high = wide["alpha_interval"]
    assert 0.6 < low < wide["alpha"] < high < 0.9 and high - low > 0.05
    close = p ** np.array([[0.74], [0.75], [0.75], [0.76]])
    narrow = finite_size_fit(curves | {"stiffness": close}, n * n, crossover=1.0)
    assert np.diff(narrow["alpha_interval"])[0] < 0.2 * (high - low)


def test_ensemble_command(tmp_path):
    out = tmp_path / "ens.h5"
    args = [
        "ensemble",
        "--grid",
        "32",
        "--hurst",
        "0.7",
        "--rms-slope",
        "0.1",
        "--seeds",
        "0-3",
        "--pressures",
        "1e-3,1e-2",
        "--stiffness",
        "--output",
        str(out),
        "--quiet",
    ]
    r = cli(*args)
    assert r.returncode == 0, r.stderr
    with h5py.File(out) as f:
        gaps = f["mean_gap"][:]
        assert gaps.shape == (4, 2) and list(f["seeds"][:]) == [0, 1, 2, 3]
        assert np.allclose(f["mean_gap_mean"][:], gaps.mean(axis=0))
        assert np.allclose(f["mean_gap_std"][:], gaps.std(axis=0, ddof=1))
        assert np.all(f["mean_gap_std"][:] > 0)  # different seeds, different surfaces
        assert np.all(f["stiffness"][:] > 0)
    for k in range(4):
        with h5py.File(tmp_path / f"ens_seed{k}.h5") as f:
            assert f.attrs["seed"] == k and np.allclose(f["mean_gap"][:], gaps[k])
    before = (tmp_path / "ens_seed2.h5").stat().st_mtime_ns
    r = cli(*args, "--resume")
    assert r.returncode == 0 and (tmp_path / "ens_seed2.h5").stat().st_mtime_ns == before
    # --sweep N: the documented default range, the same pressures for every seed, a plot and
    # the run record in the summary
    plot = tmp_path / "ens.png"
    r = cli(*args[:-6], "--sweep", "4", "--output", str(out), "--plot", str(plot), "--quiet",
            "--overwrite")  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert plot.stat().st_size > 1000
    with h5py.File(out) as f:
        p = f["nominal_pressure"][:]
        assert p.size == 4 and p[-1] / p[0] == pytest.approx(0.9 / 1e-4, rel=1e-9)
        assert "petsc4py" in f.attrs["versions"] and "--sweep 4" in f.attrs["command_line"]
        assert json.loads(f.attrs["parameters"])["pressures"] == pytest.approx(list(p))
    for k in range(4):
        with h5py.File(tmp_path / f"ens_seed{k}.h5") as f:
            assert np.array_equal(f["nominal_pressure"][:], p)


def test_experiment_command(tmp_path):
    """A synthetic squeeze test with u_bar = -u0 ln p: Eq. C3 recovers K = p/u0."""
    u0, d, e = 1e-4, 1e-2, 4.2e6
    p = np.geomspace(1e3, 1e5, 60)
    s = u0 * np.log(p / p[0]) + p * d / e
    table = tmp_path / "ps.csv"
    np.savetxt(table, np.column_stack([p, s]), delimiter=",", header="p, s")
    out = tmp_path / "exp.h5"
    r = cli(
        "experiment",
        "--table",
        str(table),
        "--modulus",
        str(e),
        "--thickness",
        str(d),
        "--output",
        str(out),
        "--quiet",
    )
    assert r.returncode == 0, r.stderr
    with h5py.File(out) as f:
        assert np.allclose(f["stiffness"][1:-1], p[1:-1] / u0, rtol=5e-3)
    (tmp_path / "bad.csv").write_text("1,2,3\n4,5,6\n7,8,9\n")
    r = cli(
        "experiment",
        "--table",
        str(tmp_path / "bad.csv"),
        "--modulus",
        "1",
        "--thickness",
        "1",
        "--output",
        str(out),
    )
    assert r.returncode == 2 and "has 3 columns, not 2" in r.stderr
    # a header line and whitespace-separated columns are read like the comma file
    text = "pressure  displacement\n" + "\n".join(
        f"{a:.17g}  {b:.17g}" for a, b in zip(p, s, strict=True)
    )
    (tmp_path / "ps.txt").write_text(text + "\n")
    out2 = tmp_path / "exp2.h5"
    r = cli(
        *f"experiment --table {tmp_path / 'ps.txt'} --modulus {e} --thickness {d}".split(),
        "--output",
        str(out2),
        "--quiet",
    )
    assert r.returncode == 0, r.stderr
    with h5py.File(out) as f, h5py.File(out2) as g:
        assert np.array_equal(f["stiffness"][:], g["stiffness"][:])


def test_experiment_rows_without_a_stiffness_are_said(tmp_path):
    """A table whose pressure falls with the displacement at some rows (noise, or s of the
    wrong sign) gives K = NaN there and one warning, not a negative stiffness; so do rows
    where the block's own compression dominates (K* d/E' >= 1)."""
    from petsc_contact.conventions.warnings import DoubtfulTable
    from petsc_contact.workflows.experiment import squeeze_test

    u0, d, e = 1e-4, 1e-2, 4.2e6
    p = np.geomspace(1e3, 1e5, 30)
    s = u0 * np.log(p / p[0]) + p * d / e
    p[10] *= 0.5  # one bad row: K* < 0 around it
    table = tmp_path / "ps.csv"
    np.savetxt(table, np.column_stack([p, s]), delimiter=",")
    with pytest.warns(DoubtfulTable, match=r"K is NaN at \d+ of 30 rows .*K\* <= 0"):
        found = squeeze_test(str(table), e, d, str(tmp_path / "e.h5"))
    falling = found.measured_stiffness <= 0
    assert falling.any() and np.isnan(found.stiffness[falling]).all()
    assert np.all(np.isnan(found.stiffness) | (found.stiffness > 0))
    with pytest.warns(DoubtfulTable) as caught:
        squeeze_test(str(table), e, 100 * d, str(tmp_path / "f.h5"))
    said = [str(w.message) for w in caught]
    assert len(said) == 2 and "the block's own compression dominates" in said[1]
    r = cli("experiment", "--table", str(table), "--modulus", str(e), "--thickness", str(d),
            "--output", str(tmp_path / "g.h5"))  # fmt: skip
    assert r.returncode == 0 and "petsc-contact: warning: K is NaN at" in r.stderr
    assert f"# wrote {tmp_path / 'g.h5'}" in r.stdout
