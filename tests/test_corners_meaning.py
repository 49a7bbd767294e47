"""A load keeps its meaning: a periodic sweep handed to the punch, loads beyond full contact."""

import csv
import warnings

import h5py
import numpy as np
import pytest
from conftest import cli

from petsc_contact import Run, periodic_contact, punch_contact, run_contact
from petsc_contact.conventions.warnings import ConvertedLoads, FullContact, Unconverged
from petsc_contact.geometries.punch import interfacial_stiffness

SURFACE = {"grid": 32, "hurst": 0.8, "rms_slope": 0.1, "seed": 1}
GEN = "--grid 32 --hurst 0.8 --rms-slope 0.1 --seed 1".split()


def test_periodic_sweep_made_a_punch_keeps_its_pressures_and_says_so():
    periodic = Run(**SURFACE, sweep=(3, 1e-3, 1e-2))
    with pytest.warns(ConvertedLoads, match=r"punch takes its 3 pressures \(0.001 to 0.01\)") as w:
        punch = periodic.with_(geometry="punch")
    assert w[0].filename == __file__  # the caller's line, not the package's
    assert punch.sweep is None
    assert punch.pressures == pytest.approx(np.geomspace(1e-3, 1e-2, 3))
    table = run_contact(punch).table
    assert [s["nominal_pressure"] for s in table] == pytest.approx(punch.pressures, rel=1e-6)
    assert all(s["converged"] and not s["full_contact"] for s in table)


def test_periodic_sweep_with_units_made_a_punch_is_in_the_runs_unit():
    periodic = Run(**SURFACE, length="1mm", modulus="1MPa", sweep=(2, "1kPa", "10kPa"))
    with pytest.warns(ConvertedLoads):
        punch = periodic.with_(geometry="punch")
    assert punch.pressures == pytest.approx((1e-3, 1e-2))  # MPa, the modulus's unit


def test_punch_sweep_made_periodic_is_refused_naming_what_to_give():
    punch = Run(**SURFACE, geometry="punch", sweep=(3, 1e-3, 1e-2))
    with pytest.raises(ValueError, match=r"of approaches.*geometry='periodic', sweep=") as e:
        punch.with_(geometry="periodic")
    assert "\n" not in str(e.value)


def test_a_load_given_with_the_geometry_or_a_count_alone_is_taken_as_given():
    periodic = Run(**SURFACE, sweep=(3, 1e-3, 1e-2))
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConvertedLoads)
        assert periodic.with_(geometry="punch", sweep=(2, 1e-3, 1e-2)).sweep == (2, 1e-3, 1e-2)
        moved = periodic.with_(geometry="punch", sweep=None, approaches=[1e-3])
        assert list(moved.approaches) == [1e-3] and moved.pressures is None
        assert Run(**SURFACE, sweep=4).with_(geometry="punch").sweep == (4,)
        assert periodic.with_(seed=2).sweep == (3, 1e-3, 1e-2)


def test_periodic_loads_beyond_full_contact_are_flagged_with_nan_stiffness(tmp_path):
    out = tmp_path / "full.h5"
    run = Run(**SURFACE, pressures=(0.01, 1.0), stiffness=True, output=str(out))
    with pytest.warns(FullContact, match=r"1 of 2 load steps are at or beyond full contact"):
        result = run_contact(run)
    (first, full) = result.table
    assert not first["full_contact"] and np.isfinite(first["stiffness"]) and first["stiffness"] > 0
    assert full["full_contact"] and full["area_fraction"] == 1.0
    assert np.isnan(full["stiffness"])  # unbounded, never a number (0.0 or inf)
    assert full["converged"] and full["accurate"]  # the answer is right: the load is flagged
    assert any("full contact" in text for text in result.warnings)
    with h5py.File(out) as f:
        assert f["full_contact"][:].tolist() == [False, True]
        assert np.isnan(f["stiffness"][1])
        assert "full contact" in f.attrs["warnings"]
    with open(tmp_path / "full.csv") as table:
        rows = list(csv.DictReader(table))
    assert [row["full_contact"] for row in rows] == ["False", "True"]


def test_punch_at_full_contact_has_nan_interfacial_stiffness():
    run = Run(**SURFACE, geometry="punch", approaches=(1e-2, 1.0), stiffness=True)
    with pytest.warns(FullContact):
        first, full = run_contact(run).table
    assert not first["full_contact"] and first["interfacial_stiffness"] > 0
    assert full["full_contact"] and full["converged"]
    assert np.isnan(full["interfacial_stiffness"]) and np.isnan(full["stiffness"])
    assert full["total_stiffness"] == pytest.approx(full["flat_punch_stiffness"], rel=1e-6)


def test_punch_step_that_did_not_converge_has_nan_not_zero_stiffness():
    assert np.isnan(interfacial_stiffness(np.nan, 1.0))
    assert interfacial_stiffness(0.0, 1.0) == 0.0  # no contact: no stiffness
    run = Run(**SURFACE, geometry="punch", approaches=(1e-2,), options=("-tao_max_it", "1"))
    with pytest.warns(Unconverged):
        (step,) = run_contact(run).table
    assert not step["converged"] and np.isnan(step["interfacial_stiffness"])


def test_library_functions_say_full_contact():
    heights = np.random.default_rng(0).normal(size=(32, 32)) * 1e-3
    with pytest.warns(FullContact) as w:
        (step,) = periodic_contact(heights, length=1.0, pressures=1.0, stiffness=True)
    assert w[0].filename == __file__
    assert step.scalars["full_contact"] and np.isnan(step.scalars["stiffness"])
    with pytest.warns(FullContact):
        (step,) = punch_contact(heights, length=1.0, approaches=1.0)
    assert step.scalars["full_contact"] and np.isnan(step.scalars["interfacial_stiffness"])


def test_cli_marks_the_full_contact_row_and_warns(tmp_path):
    out = tmp_path / "run.h5"
    r = cli("periodic", *GEN, "--pressures", "0.01,1", "--output", str(out))
    assert r.returncode == 0, r.stderr  # converged and accurate: flagged, not failed
    rows = [line for line in r.stdout.splitlines() if "CONVERGED" in line]
    assert "FULL CONTACT" not in rows[0] and "<-- FULL CONTACT" in rows[1]
    assert "warning: 1 of 2 load steps are at or beyond full contact" in r.stderr
    assert f"flagged full_contact = True in {out}" in r.stderr
