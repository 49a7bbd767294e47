"""One name for each thing: the printed table names the output's datasets, the console shows
values with an SI prefix and their unit, and the package's solver has one name (``cg``) in
``compare``, in the files and in the options that choose it."""

from __future__ import annotations

import csv
import re

import h5py
import pytest
from conftest import cli

from petsc_contact import periodic_contact
from petsc_contact.cli.runs import LOAD_COLUMNS, STEP_COLUMNS
from petsc_contact.conventions.grid import Grid
from petsc_contact.conventions.units import format_quantity
from petsc_contact.devices.fft import make_fft
from petsc_contact.io.schema import GEOMETRIES
from petsc_contact.physics.surface import self_affine
from petsc_contact.workflows.compare import DEFAULT_SOLVERS, solver_options

SCENE = "--grid 32 --hurst 0.7 --rms-slope 0.1 --seed 3".split()
LEGEND = "# the output's datasets [in its units]: "


@pytest.fixture(scope="module")
def units_run(tmp_path_factory):
    """A periodic run with units (E* = 1 GPa, p0 = 100 kPa, L = 500 um): its output and file."""
    out = tmp_path_factory.mktemp("units") / "run.h5"
    loads = ["--modulus", "1GPa", "--length", "500um", "--pressures", "100kPa,1MPa"]
    r = cli("periodic", *SCENE, *loads, "--output", str(out))
    assert r.returncode == 0, r.stderr
    return r.stdout.splitlines(), out


@pytest.mark.parametrize(
    "value, unit, shown",
    [
        (1e-4, "GPa", "100 kPa"),
        (1e-3, "GPa", "1 MPa"),
        (5.62305e-4, "m", "562.3 um"),
        (2.5, "GPa*um^2", "2.5 mN"),
        (3.0, "GPa*um", "3 kN/m"),
        (999.96, "um", "1 mm"),
        (0.0, "GPa", "0 Pa"),
        (1e-4, None, "0.0001"),
    ],
)
def test_format_quantity(value, unit, shown):
    assert format_quantity(value, unit) == shown


def test_columns_are_datasets_of_the_output():
    for geometry, load in LOAD_COLUMNS.items():
        for _, key, *_ in (*load, *STEP_COLUMNS):
            assert key in GEOMETRIES[geometry], (geometry, key)


def test_the_legend_maps_every_header_to_its_dataset_and_unit(units_run):
    lines, out = units_run
    (legend,) = [line for line in lines if line.startswith(LEGEND)]
    header = next(line for line in lines if line.split()[:1] == ["step"])
    named = {}
    for part in legend[len(LEGEND) :].split(", "):
        m = re.fullmatch(r"(?:(\S+) = )?(\S+)(?: \[(\S+)\])?", part)
        assert m is not None, part
        named[m[1] or m[2]] = (m[2], m[3])
    assert list(named) == header.split()[1:-1]  # all but step and tao_reason
    with h5py.File(out) as f:
        for dataset, unit in named.values():
            stored = f[dataset].attrs["units"]
            assert unit == (stored if stored not in ("1", "count") else None), dataset


def test_the_console_shows_units_with_a_prefix(units_run):
    lines, _ = units_run
    problem = next(line for line in lines if line.startswith("# periodic "))
    assert "on 500 um x 500 um, E* = 1 GPa, h_rms = " in problem
    assert re.search(r"h_rms = \d+(\.\d+)? [mun]m,", problem)
    rows = [line.split() for line in lines if re.match(r"\s*\d+/2 ", line)]
    assert [row[1:3] for row in rows] == [["100", "kPa"], ["1", "MPa"]]
    assert all(re.fullmatch("[mun]m", row[4]) for row in rows)  # the mean gap


@pytest.fixture(scope="module")
def heights():
    grid = Grid(32, 1.0)
    return self_affine(
        grid, make_fft(grid), hurst=0.7, rolloff_ratio=2, cutoff_ratio=16, seed=3, rms_slope=0.1
    )


@pytest.mark.parametrize(
    "options, name",
    [
        ((), "cg"),
        (tuple(solver_options("cg")), "cg"),
        (
            (
                "-tao_type",
                "python",
                "-tao_python_type",
                "petsc_contact.backend.cg.PreconditionedCG",
            ),
            "cg",
        ),
        (tuple(solver_options("pk")), "pk"),
        (("-tao_type", "bncg"), "bncg"),
    ],
)
def test_a_run_records_its_solver_by_compares_name(heights, options, name):
    assert name in DEFAULT_SOLVERS
    (step,) = periodic_contact(heights, length=1.0, modulus=1.0, pressures=[1e-2], options=options)
    assert step.scalars["tao_type"] == name


def test_compare_and_the_file_name_the_solver_alike(tmp_path):
    out = tmp_path / "cmp.h5"
    r = cli("compare", *SCENE, "--pressures", "1e-2", "--solvers", "cg", "--output", str(out))
    assert r.returncode == 0, r.stdout + r.stderr
    assert re.search(r"^\s*cg\s", r.stdout, re.MULTILINE)
    with open(tmp_path / "cmp.csv") as table:
        assert [row["solver"] for row in csv.DictReader(table)] == ["cg"]
    with h5py.File(out) as f:
        assert "cg" in f
    run = tmp_path / "run.h5"
    r = cli("periodic", *SCENE, "--pressures", "1e-2", "--output", str(run))
    assert r.returncode == 0, r.stderr
    with h5py.File(run) as f:
        assert [v.decode() for v in f["tao_type"][...]] == ["cg"]
