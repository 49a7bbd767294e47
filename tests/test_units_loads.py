"""Loads and moduli in the units people use: ``--modulus 1GPa``, ``--pressures 2MPa``,
``--forces 1mN``, the punch by nominal pressure; bare numbers keep their meaning."""

import h5py
import numpy as np
import pytest
from conftest import cli

from petsc_contact.conventions.units import force_value, parse_quantity, pressure_value


def test_conversions():
    assert pressure_value("2MPa", "GPa", "p") == pytest.approx(2e-3)
    assert pressure_value(0.5, "GPa", "p") == 0.5  # bare: in the modulus's unit
    assert force_value("1mN", "GPa", "um", "F") == pytest.approx(1.0)  # GPa um^2 = mN
    assert force_value("1 N", "Pa", "m", "F") == pytest.approx(1.0)
    assert parse_quantity("3 psi", {"psi": 6894.757}, "p").unit == "psi"
    with pytest.raises(ValueError, match="need a modulus with a unit"):
        pressure_value("2MPa", None, "--pressures")
    with pytest.raises(ValueError, match="need a modulus and lengths with units"):
        force_value("1mN", "GPa", None, "--forces")
    with pytest.raises(ValueError, match="optional unit"):
        parse_quantity("2 parsec", {"Pa": 1.0}, "--pressures")


def _map(tmp_path):
    rng = np.random.default_rng(4)
    x, y = np.meshgrid(*(np.arange(48) / 48,) * 2, indexing="ij")
    h = 0.05 * sum(
        rng.standard_normal() * np.cos(2 * np.pi * (i * x + j * y) + rng.uniform(0, 6.3))
        for i in range(1, 4)
        for j in range(-3, 4)
    )
    np.save(tmp_path / "h.npy", h)
    return ["--heights", str(tmp_path / "h.npy"), "--height-unit", "um", "--length", "20um"]


def _out(tmp_path, name, *args):
    r = cli(*args, "--quiet", "--output", str(tmp_path / f"{name}.h5"))
    assert r.returncode == 0, r.stderr
    return h5py.File(tmp_path / f"{name}.h5")


def test_units_give_the_bare_numbers_answer(tmp_path):
    """2 MPa on a 1 GPa modulus is the bare 0.002 on a modulus of 1; 1 mN on a map in um is
    the bare force 1 (GPa um^2); the punch at 2 MPa over its 20 um x 20 um face is the force
    0.8 mN.  The file records the units of its pressures and forces."""
    scan = _map(tmp_path)
    with _out(tmp_path, "si", "periodic", *scan, "--modulus", "1GPa", "--pressures", "2MPa") as a:
        with _out(tmp_path, "bare", "periodic", *scan, "--pressures", "0.002") as b:
            assert a["mean_gap"][0] == pytest.approx(b["mean_gap"][0], rel=1e-10)
        assert a.attrs["pressure_unit"] == "GPa" and a["nominal_pressure"].attrs["units"] == "GPa"
        assert (
            a["mean_gap"].attrs["units"] == "um" and a["elastic_energy"].attrs["units"] == "GPa*um"
        )
    punch = ["punch", *scan, "--modulus", "1GPa"]
    with _out(tmp_path, "mN", *punch, "--forces", "1mN") as a:
        with _out(tmp_path, "one", *punch, "--forces", "1") as b:
            assert a["approach"][0] == pytest.approx(b["approach"][0], rel=1e-10)
        assert a["force"].attrs["units"] == "GPa*um^2" and a.attrs["force_unit"] == "GPa*um^2"
    with _out(tmp_path, "p0", *punch, "--pressures", "2MPa") as a:
        assert a["force"][0] == pytest.approx(0.8, rel=1e-6)  # mN
        assert a["nominal_pressure"][0] == pytest.approx(2e-3, rel=1e-6)  # GPa


def test_sweeps_take_units(tmp_path):
    """A sweep's bounds with units are the bare bounds in the run's units: 100 kPa to 10 MPa
    on a 1 GPa modulus is 1e-4 to 1e-2 (the same loads, exactly); the punch's approaches 1 nm
    to 5 nm on a map in um are 1e-3 to 5e-3.  Bounds in the wrong order are refused in one
    line, with or without units."""
    scan = _map(tmp_path)
    si = ["periodic", *scan, "--modulus", "1GPa", "--sweep", "3,100kPa,10MPa"]
    bare = ["periodic", *scan, "--sweep", "3,1e-4,1e-2"]
    with _out(tmp_path, "si", *si) as a, _out(tmp_path, "bare", *bare) as b:
        assert np.allclose(a["nominal_pressure"][:], b["nominal_pressure"][:], rtol=1e-12)
        assert np.allclose(a["mean_gap"][:], b["mean_gap"][:], rtol=1e-10)
    with _out(tmp_path, "nm", "punch", *scan, "--sweep", "3,1nm,5nm") as a:
        assert a["approach"][0] == pytest.approx(1e-3, rel=1e-12)
        assert a["approach"][-1] == pytest.approx(5e-3, rel=1e-12)
    for bounds in ("3,10MPa,100kPa", "3,1e-2,1e-4"):
        r = cli(
            "periodic",
            *scan,
            "--modulus",
            "1GPa",
            "--sweep",
            bounds,
            "--output",
            str(tmp_path / "x.h5"),
        )
        assert r.returncode == 2 and "0 < PMIN < PMAX" in r.stderr, r.stderr
        assert len(r.stderr.strip().splitlines()) == 1


def test_units_without_a_unit_system_are_refused(tmp_path):
    scan = _map(tmp_path)
    for args, words in (
        (["periodic", *scan, "--pressures", "2MPa"], "need a modulus with a unit"),
        (
            ["punch", *"--grid 32 --hurst 0.7 --rms-slope 0.1 --modulus 1GPa --forces 1mN".split()],
            "need a modulus and lengths with units",
        ),
        (["periodic", *scan, "--modulus", "1 Gigapascal", "--pressures", "1"], "optional unit"),
    ):
        r = cli(*args, "--output", str(tmp_path / "x.h5"))
        assert r.returncode == 2 and words in r.stderr and r.stderr.count("\n") == 1, r.stderr
