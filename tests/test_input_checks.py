"""Every input is checked before anything is computed or written: each bad input injected
ends in its exit status and one line, and leaves no file behind."""

from __future__ import annotations

import json
import os
import stat
import warnings
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import ROOT, cli, python

from petsc_contact import periodic_contact
from petsc_contact.conventions.grid import Grid
from petsc_contact.conventions.warnings import Unconverged
from petsc_contact.devices.fft import make_fft
from petsc_contact.physics.surface import self_affine
from petsc_contact.solver.linear import StiffnessNotConverged
from petsc_contact.workflows.description import Run
from petsc_contact.workflows.punch_sweep import FORCE_RESOLVED, FORCE_RTOL
from petsc_contact.workflows.runner import prepare, run_contact

SURFACE = ("--grid", "16", "--hurst", "0.7", "--rms-slope", "0.1")
PERIODIC = ("periodic", *SURFACE, "--pressures", "1e-3", "--quiet")
THEORY = ("theory", "--grid", "64", "--hurst", "0.7", "--rms-slope", "0.1", "--quiet")


def refused(tmp: Path, *args: str, says: str) -> None:
    """``petsc-contact ARGS`` in ``tmp`` exits 2 with one line saying ``says``, and ``tmp``
    holds the same files afterwards."""
    before = sorted(os.listdir(tmp))
    r = cli(*args)
    lines = r.stderr.strip().splitlines()
    assert (r.returncode, len(lines)) == (2, 1), r.stderr
    assert says in lines[0], lines[0]
    assert sorted(os.listdir(tmp)) == before


@pytest.fixture
def heights(tmp_path: Path) -> Path:
    path = tmp_path / "h.npy"
    np.save(path, np.random.default_rng(0).random((16, 16)))
    return path


@pytest.fixture
def run_file(tmp_path: Path):
    """A results file of a given geometry, made with h5py (no run)."""

    def make(name: str, geometry: str, **datasets: np.ndarray) -> Path:
        path = tmp_path / name
        with h5py.File(path, "w") as f:
            f.attrs["geometry"] = geometry
            for key, value in datasets.items():
                f[key] = value
        return path

    return make


def test_output_that_is_no_regular_file(tmp_path: Path) -> None:
    """A device, a FIFO and a folder are refused as --output; the device stays a device
    (no HDF5 written over it, no /dev/full.csv)."""
    fifo, folder = tmp_path / "fifo", tmp_path / "folder"
    os.mkfifo(fifo)
    folder.mkdir()
    for output, what in (
        ("/dev/null", "is a device"),
        ("/dev/full", "is a device"),
        (str(fifo), "is a FIFO"),
        (str(folder), "is a folder"),
    ):
        refused(tmp_path, *PERIODIC, "--output", output, says=f"--output '{output}' {what}")
    assert stat.S_ISCHR(os.stat("/dev/full").st_mode) and not os.path.exists("/dev/full.csv")


def test_output_that_is_an_input(tmp_path: Path, heights: Path, run_file) -> None:
    """The output may not be an input: by a hard link, by another spelling, for every
    command that reads files."""
    link = tmp_path / "link.h5"
    os.link(heights, link)
    table = tmp_path / "ps.txt"
    table.write_text("1 0.1\n2 0.2\n3 0.25\n")
    run = run_file("run.h5", "periodic", mean_gap=np.ones(3))
    same = "is the same file as"
    loads = ("--pressures", "1e-3")
    refused(tmp_path, "periodic", "--heights", str(heights), *loads, "--output", str(link),
            says=f"{same} --heights")  # fmt: skip
    refused(tmp_path, "periodic", "--heights", f"{tmp_path}/./h.npy", *loads, "--output",
            str(heights), says=f"{same} --heights")  # fmt: skip
    refused(tmp_path, *THEORY, "--output", str(run), "--plot", str(tmp_path / "t.png"),
            "--compare", str(run), says=f"{same} --compare")  # fmt: skip
    refused(tmp_path, "plot", str(run), "--output", str(run), says="--output")
    refused(tmp_path, "experiment", "--table", str(table), "--modulus", "1", "--thickness", "1",
            "--output", str(table), says=f"{same} --table")  # fmt: skip


def test_outputs_that_clash(tmp_path: Path) -> None:
    """--plot equal to --output, or in a format no figure has (``OUT.csv`` among them), is
    refused before the run."""
    out = str(tmp_path / "a.h5")
    png = str(tmp_path / "a.png")
    refused(tmp_path, *PERIODIC, "--output", png, "--plot", png, says="is the same file as")
    refused(tmp_path, *PERIODIC, "--output", out, "--plot", str(tmp_path / "a.dat"),
            says="cannot be written as '.dat'")  # fmt: skip


def test_a_figure_in_a_missing_folder(tmp_path: Path) -> None:
    """--plot into a folder that does not exist is refused before the run, as --output is
    (exit 74, one line): it was found only after every step had been solved."""
    out, plot = str(tmp_path / "a.h5"), str(tmp_path / "nowhere" / "a.png")
    r = cli(*PERIODIC, "--output", out, "--plot", plot)
    assert r.returncode == 74 and r.stderr.strip().splitlines() == [
        f"petsc-contact: error: --plot's folder '{tmp_path / 'nowhere'}' does not exist"
    ], r.stderr
    assert os.listdir(tmp_path) == []


def test_negative_values_in_every_spelling(tmp_path: Path) -> None:
    """A negative load or length is refused by its check in every spelling: argparse alone
    takes ``-1e-3`` for an option (``expected one argument``)."""
    out = str(tmp_path / "a.h5")
    for value in ("-1e-3", "-1", "-.5", "-2E+1"):
        refused(tmp_path, "periodic", *SURFACE, "--output", out, "--pressures", value,
                says="--pressures must be positive")  # fmt: skip
    refused(tmp_path, "periodic", *SURFACE, "--output", out, "--pressures", "1e-3",
            "--length", "-2e-3", says="a length must be positive")  # fmt: skip


def test_lists_and_solvers(tmp_path: Path) -> None:
    """An empty item in a comma list is refused, not dropped; a solver named twice too, and a
    reversed range of seeds."""
    out = str(tmp_path / "a.h5")
    for option, value in (
        ("--pressures", "1e-3,,2e-3"),
        ("--pressures", "1e-3,"),
        ("--sweep", "12,,1e-2"),
        ("--grid", "16,"),
    ):
        refused(tmp_path, "periodic", *SURFACE, "--output", out, option, value,
                says="an empty item")  # fmt: skip
    refused(tmp_path, "ensemble", *SURFACE, "--pressures", "1e-3", "--seeds", "1,,2",
            "--output", out, says="an empty item")  # fmt: skip
    ensemble = ("ensemble", *SURFACE, "--pressures", "1e-3", "--output", out)
    refused(tmp_path, *ensemble, "--seeds", "3-1", says="a range A-B of seeds with B >= A")
    compare = ("compare", *SURFACE, "--pressures", "1e-3", "--output", out)
    refused(tmp_path, *compare, "--solvers", "cg,cg", says="a solver named twice: cg")
    refused(tmp_path, *compare, "--solvers", "cg,,pk", says="an empty item")


def test_options_files(tmp_path: Path) -> None:
    """An options file of random bytes, or with a line that is no option, is one line."""
    noise, prose = tmp_path / "noise.opts", tmp_path / "prose.opts"
    noise.write_bytes(bytes(np.random.default_rng(1).integers(128, 256, 300, dtype=np.uint8)))
    prose.write_text("# fine\n-tao_monitor\n\n-tao_gatol 1e-9\nmore speed please\n")
    out = str(tmp_path / "a.h5")
    refused(tmp_path, *PERIODIC, "--output", out, "-options_file", str(noise),
            says="is not text (-options_file)")  # fmt: skip
    refused(tmp_path, *PERIODIC, "--output", out, "-options_file", str(prose),
            says="line 5 is not a PETSc option")  # fmt: skip
    for name in os.listdir(ROOT / "petsc_contact" / "options"):  # the package's own are fine
        from petsc_contact.cli.common import check_options_file

        check_options_file(str(ROOT / "petsc_contact" / "options" / name))


def test_heights_that_are_no_map_file(tmp_path: Path) -> None:
    """A folder, a device or an empty file as --heights says what it is."""
    (tmp_path / "folder").mkdir()
    (tmp_path / "empty.npy").touch()
    loads = ("--pressures", "1e-3", "--output", str(tmp_path / "a.h5"))
    for given, what in (
        (str(tmp_path / "folder"), "is a folder"),
        ("/dev/null", "is a device"),
        (str(tmp_path / "empty.npy"), "is empty"),
        (str(tmp_path / "none.npy"), "does not exist"),
    ):
        refused(tmp_path, "periodic", "--heights", given, *loads, says=what)


def test_theory_compare(tmp_path: Path, run_file) -> None:
    """theory --compare needs --plot and periodic runs; a file that fails to give its table
    leaves neither the output nor the plot."""
    out, png = str(tmp_path / "t.h5"), str(tmp_path / "t.png")
    periodic = run_file("p.h5", "periodic", mean_gap=np.ones(3))
    punch = run_file("punch.h5", "punch", mean_gap=np.ones(3))
    empty = run_file("e.h5", "periodic")
    refused(tmp_path, *THEORY, "--output", out, "--compare", str(periodic), says="give --plot")
    refused(tmp_path, *THEORY, "--output", out, "--plot", png, "--compare", str(punch),
            says="geometry 'punch'")  # fmt: skip
    refused(tmp_path, *THEORY, "--output", out, "--plot", png, "--compare", str(empty),
            says="no mean_gap")  # fmt: skip


def test_plot_of_an_unfinished_run(tmp_path: Path, run_file) -> None:
    """plot OUT.h5.partial says where an unfinished run's maps are, not 'run with --fields'."""
    partial = run_file("r.h5.partial", "periodic", nominal_pressure=np.ones(1))
    with h5py.File(partial, "a") as f:
        f.attrs["parameters"] = json.dumps({"fields": True})
    refused(tmp_path, "plot", str(partial), says=f"its maps are in {tmp_path}/r.h5.parts")
    finished = run_file("s.h5", "periodic", nominal_pressure=np.ones(1))
    refused(tmp_path, "plot", str(finished), says="(run with --fields)")


def test_an_ensemble_says_it_ignores_seed(tmp_path: Path) -> None:
    """``ensemble --seed K`` runs its ``--seeds`` and says that ``--seed`` is ignored."""
    out = str(tmp_path / "e.h5")
    r = cli("ensemble", *SURFACE, "--pressures", "1e-3", "--seeds", "0-1", "--seed", "5",
            "--output", out, "--quiet")  # fmt: skip
    assert r.returncode == 0 and r.stderr.splitlines() == [
        "petsc-contact: warning: --seed is ignored: an ensemble's surfaces are its --seeds"
    ], r.stderr


def test_a_study_away_from_its_data(tmp_path: Path) -> None:
    """``study`` without ``--data`` outside the repository's root is refused in one line (it
    would have started the whole 8192^2 study there); with ``--data`` a new folder is made."""
    import subprocess
    import sys

    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    for extra in ((), ("--list",)):
        r = subprocess.run([sys.executable, "-m", "petsc_contact.cli", "study", *extra,
                            "--minutes", "0.001"], cwd=tmp_path, env=env, capture_output=True,
                           text=True, timeout=120)  # fmt: skip
        assert r.returncode == 2 and r.stderr.splitlines() == [
            f"petsc-contact: error: no data/paper in {tmp_path}: run the study in the "
            "repository's root, where the paper's data are, or name a folder with --data (a "
            "new one starts the study afresh)"
        ], r.stderr
    assert os.listdir(tmp_path) == []
    # a new folder named: listed, each piece's command makes its folder first
    new = tmp_path / "my data"
    r = cli("study", "--list", "--figure", "1", "--shrink", "128", "--data", str(new))
    first = r.stdout.splitlines()[0]
    assert r.returncode == 0, r.stderr
    assert first.startswith(f" todo  '{new}/fig1/punch.h5'  mkdir -p '{new}/fig1' && ")
    assert "&& petsc-contact punch --grid 16 " in first and not new.exists()
    assert f"--output '{new}/fig1/punch.h5'" in first


def test_plot_of_what_no_command_plots(tmp_path: Path, heights: Path, run_file) -> None:
    """plot of a heights file, or of a comparison (with or without --sweep), says what the
    file is in one line (h5py's 'file signature not found'; a comparison was sent to
    --sweep, which then found no sweep)."""
    refused(tmp_path, "plot", str(heights), says="is not an HDF5 file: plot draws the files")
    compared = run_file("c.h5", "periodic", cg=np.ones(1))
    with h5py.File(compared, "a") as f:
        f.attrs["solvers"] = json.dumps(["cg"])
    for extra in ((), ("--sweep",)):
        refused(tmp_path, "plot", str(compared), *extra,
                says=f"is a solver comparison, with no maps and no load sweep: compare drew "
                f"its figure as {tmp_path}/c.png")  # fmt: skip


@pytest.mark.parametrize("device", ["cpu", "cpu-array"])
def test_stiffness_solve_not_converged(device: str) -> None:
    """A held-set solve stopped by -stiffness_ksp_max_it 1 gives a NaN stiffness, its warning
    and the step flagged not accurate, said once, not a traceback."""
    grid = Grid(32, 1.0)
    h = self_affine(grid, make_fft(grid), hurst=0.7, rolloff_ratio=2, cutoff_ratio=16, seed=5,
                    rms_slope=0.1)  # fmt: skip
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        (step,) = periodic_contact(
            h,
            length=1.0,
            modulus=1.0,
            pressures=[3e-2],
            stiffness=True,
            device=device,
            options=["-stiffness_ksp_max_it", "1"],
        )
    assert np.isnan(step.scalars["stiffness"]) and not step.scalars["accurate"]
    assert [w.category for w in caught] == [StiffnessNotConverged, Unconverged]
    assert "1 of 1 load steps are NOT accurate" in str(caught[1].message)


def test_library_door(tmp_path: Path, heights: Path) -> None:
    """run_contact refuses what the command line refuses, before any file is touched (its
    lock included): an output that is its heights, a device, heights that are a folder.  A
    Run is only a description: it reads no file."""
    refused = {
        "is the same file as --heights": Run(heights=str(heights), pressures=[1e-3],
                                             output=str(heights)),
        "is a device": Run(grid=16, hurst=0.7, rms_slope=0.1, pressures=[1e-3],
                           output="/dev/null"),
        "is a folder": Run(heights=str(tmp_path), pressures=[1e-3]),
    }  # fmt: skip
    before = sorted(os.listdir(tmp_path))
    for says, run in refused.items():
        with pytest.raises(ValueError, match=says):
            run_contact(run)
        with pytest.raises(ValueError, match=says):
            prepare(run)
    assert sorted(os.listdir(tmp_path)) == before


def test_a_run_is_a_description(tmp_path: Path) -> None:
    """``Run(...)`` reads no file and loads no PETSc (its values are checked, its files when
    it is prepared): a missing heights file and an output that is a device describe a run."""
    code = (
        "import sys\n"
        "sys.modules['petsc4py'] = None\n"
        "from petsc_contact import Run\n"
        f"Run(heights={str(tmp_path / 'none.npy')!r}, pressures=1e-3, output='/dev/null',\n"
        "    options='-tao_type bncg')\n"
        "print('described')\n"
    )
    done = python("-c", code)
    assert done.returncode == 0 and done.stdout.split() == ["described"], done.stderr
    with pytest.raises(FileNotFoundError, match="--heights '.*none.npy' does not exist"):
        prepare(Run(heights=str(tmp_path / "none.npy"), pressures=1e-3))


def test_docs_state_the_force_tolerances() -> None:
    """docs/cli.md gives the punch's force tolerances the code uses."""
    text = (ROOT / "docs" / "cli.md").read_text()
    for tolerance in (FORCE_RTOL, FORCE_RESOLVED):
        assert f"`{tolerance:.0e}`".replace("e-0", "e-") + " relative" in text
