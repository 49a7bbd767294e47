"""The solver comparison: common errors along each run, table, files, time and stall limits."""

import csv

import h5py
import numpy as np
import pytest
from conftest import ROOT, cli

from petsc_contact.workflows import compare
from petsc_contact.workflows.compare import OPTIONS, solver_options

SCENE = ("compare", "--grid", "64", "--hurst", "0.7", "--rms-slope", "0.1")


def test_compare_command(tmp_path):
    out = tmp_path / "cmp.h5"
    r = cli(
        *SCENE,
        "--seed",
        "2",
        *"--pressures 3e-3".split(),
        "--solvers",
        f"cg,pk,tron,{ROOT / 'options' / 'bnls.opts'}",
        "--output",
        str(out),
    )
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout.count("CONVERGED_GATOL") == 4
    with open(tmp_path / "cmp.csv") as table:
        rows = list(csv.DictReader(table))
    assert [row["solver"] for row in rows][:3] == ["cg", "pk", "tron"]
    assert (tmp_path / "cmp.png").stat().st_size > 1000
    with h5py.File(out) as f:
        assert f.attrs["reference_natural_residual"] < 1e-11
        # what reproduces the run: versions, seed, each solver's options and options file
        assert "petsc4py" in f.attrs["versions"] and f.attrs["seed"] == 2
        assert "petsc_contact.backend.cg.PolonskyKeer" in f["pk"].attrs["options_file_text"]
        opts_group = f[str(ROOT / "options" / "bnls.opts").replace("/", "_")]
        assert "-tao_type bnls" in opts_group.attrs["options_file_text"]
        for name in ("cg", "pk", "tron"):
            g = f[name]
            t = g["time"][:]
            assert np.all(np.diff(t) >= 0) and g.attrs["converged"]
            # every solver ends at the reference within its own tolerance (1e-8 p0 rms)
            assert g["mean_gap_error"][-1] < 1e-7
            assert g["pressure_error"][-1] < 1e-6
            assert g["natural_residual"][-1] < 1e-7
            assert g["natural_residual"][0] > 1e-3  # the run starts far away


def test_each_solver_runs_with_its_options_file(tmp_path, monkeypatch):
    """The README's ``compare --solvers cg,tron,bqnls``, on a 128^2 grid instead of its 512^2
    (40 s there, 3 s here), run from another folder than the repository: every solver
    converges with the options file the package ships for it (at 1e-8, its default tolerance
    without the file, bqnls's line search stalls here as at 512^2), and each file and its text
    are recorded.  The repository's options/ is the package's."""
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "cmp.h5"
    scene = "--grid 128 --hurst 0.7 --rms-slope 0.1 --seed 1 --pressures 1e-3".split()
    r = cli("compare", *scene, "--solvers", "cg,tron,bqnls", "--output", str(out))
    assert r.returncode == 0, r.stdout + r.stderr
    with h5py.File(out) as f:
        for name in ("cg", "tron", "bqnls"):
            shipped = OPTIONS / f"{name}.opts"
            assert shipped.samefile(ROOT / "options" / f"{name}.opts")
            g = f[name]
            assert g.attrs["converged"], (name, g.attrs["reason"])
            assert g.attrs["petsc_options"] == f"-options_file {shipped}"
            assert g.attrs["options_file_text"] == shipped.read_text()


def test_the_command_line_wins_over_a_solvers_options_file(tmp_path):
    """PETSc options on the command line follow each solver's options file: bqnls.opts says
    ``-tao_gatol 1e-7``, and ``-tao_gatol 1e-4`` stops it at a residual a thousand times
    larger (the reference keeps its own 1e-12).  ``-tao_type`` is refused: the solvers are
    those of --solvers."""
    out = tmp_path / "cmp.h5"
    args = (*SCENE, "--pressures", "3e-3", "--solvers", "bqnls", "--output", str(out))
    r = cli(*args, "-tao_gatol", "1e-4")
    assert r.returncode == 0, r.stdout + r.stderr
    with h5py.File(out) as f:
        bqnls = f["bqnls"]
        options = f"-options_file {OPTIONS / 'bqnls.opts'} -tao_gatol 1e-4"
        assert bqnls.attrs["petsc_options"] == options
        assert bqnls.attrs["converged"] and bqnls["natural_residual"][-1] > 1e-6
        assert f.attrs["reference_natural_residual"] < 1e-11
    r = cli(*args, "-tao_type", "bncg")
    assert r.returncode == 2 and "from --solvers" in r.stderr


def test_solver_options(tmp_path, monkeypatch):
    """The package's solvers by their file (and any type with a shipped file), any other TAO
    type by name, a path as it is; a
    missing file of the package's and a name that is no bound-constrained type in one line."""
    assert solver_options("bqnkls") == ["-tao_type", "bqnkls"]
    assert solver_options("bqpip") == ["-options_file", str(OPTIONS / "bqpip.opts")]
    for name in ("python", "lmvm", "nosuch"):
        with pytest.raises(ValueError, match=f"unknown solver '{name}'"):
            solver_options(name)
    mine = tmp_path / "my.opts"
    mine.write_text("-tao_type bqnls\n")
    assert solver_options(str(mine)) == ["-options_file", str(mine)]
    monkeypatch.setattr(compare, "OPTIONS", tmp_path)
    with pytest.raises(OSError, match=f"solver 'tron' is missing: {tmp_path}/tron.opts"):
        solver_options("tron")


def test_compare_reads_its_pressure_with_a_unit(tmp_path):
    """``--pressures 1MPa --modulus 1GPa`` is ``--pressures 1e-3`` (the reference's mean gap
    bit for bit); a list is refused in words before anything is solved."""
    gaps = []
    for i, load in enumerate((["1e-3"], ["1MPa", "--modulus", "1GPa"])):
        out = tmp_path / f"u{i}.h5"
        r = cli(*SCENE, "--pressures", *load, "--solvers", "cg", "--output", str(out), "--quiet")
        assert r.returncode == 0, r.stderr
        with h5py.File(out) as f:
            gaps.append(f.attrs["reference_mean_gap"])
    assert gaps[0] == gaps[1]
    r = cli(*SCENE, "--pressures", "1e-3,1e-2", "--output", str(tmp_path / "l.h5"))
    assert r.returncode == 2 and "one pressure only (compare solves one load)" in r.stderr
    assert not list(tmp_path.glob("l*"))


def test_compare_time_limit_and_bad_solver(tmp_path):
    out = tmp_path / "cmp.h5"
    r = cli(
        *SCENE,
        "--pressures",
        "3e-3",
        "--solvers",
        "bncg",
        "--time-limit",
        "0",
        "--output",
        str(out),
    )
    assert r.returncode == 1, r.stderr
    assert "time limit" in r.stdout
    with h5py.File(out) as f:
        assert not f["bncg"].attrs["converged"]
    r = cli(*SCENE, "--pressures", "3e-3", "--solvers", "no/such.opts", "--output", str(out))
    assert r.returncode == 2 and "does not exist" in r.stderr
    # a name that is no solver is refused before the reference is solved: no file is left
    other = tmp_path / "other.h5"
    r = cli(*SCENE, "--pressures", "3e-3", "--solvers", "cg,nosuch", "--output", str(other))
    assert r.returncode == 2 and "unknown solver 'nosuch'" in r.stderr, r.stderr
    assert "bqpip" in r.stderr and "python" not in r.stderr
    assert not list(tmp_path.glob("other*"))


def test_compare_stall_limit(tmp_path):
    """A solver whose natural residual does not drop 10% below its best within the window
    is stopped and reported as such; BNCG's residual is not monotone, so a one-iteration
    window stops it long before it converges (about 100 iterations here)."""
    out = tmp_path / "cmp.h5"
    r = cli(
        *SCENE,
        *"--pressures 3e-3".split(),
        "--solvers",
        "bncg",
        "--stall-iterations",
        "1",
        "--output",
        str(out),
    )
    assert r.returncode == 1, r.stderr
    with h5py.File(out) as f:
        bncg = f["bncg"]
        assert not bncg.attrs["converged"] and "stalled" in bncg.attrs["reason"]
        assert bncg.attrs["iterations"] < 50
        assert bncg["natural_residual"][-1] > 1e-6  # stopped far from its tolerance
    r = cli(*SCENE, "--pressures", "3e-3", "--stall-iterations", "-1", "--output", str(out))
    assert r.returncode == 2 and "must not be negative" in r.stderr


def test_compare_under_mpi_matches_serial(tmp_path):
    """On two ranks the comparison runs, writes its files once, and reaches the same mean
    gap as in serial.  Both references are converged to 1e-12 p0 rms, which bounds their
    mean gaps' difference near 1e-12 relative (measured: 2e-16); 1e-10 leaves room for FFT
    rounding that differs between the serial and the distributed transform."""
    args = (*SCENE, "--seed", "3", "--pressures", "3e-3", "--solvers", "cg")
    serial = cli(*args, "--output", str(tmp_path / "serial.h5"))
    parallel = cli(*args, "--output", str(tmp_path / "mpi.h5"), mpi=2, timeout=120)
    assert serial.returncode == 0 and parallel.returncode == 0, parallel.stderr
    assert parallel.stdout.count("CONVERGED_GATOL") == 1  # one table, from rank 0
    with h5py.File(tmp_path / "serial.h5") as s, h5py.File(tmp_path / "mpi.h5") as m:
        assert m.attrs["mpi_size"] == 2
        assert abs(m.attrs["reference_mean_gap"] / s.attrs["reference_mean_gap"] - 1) < 1e-10


def test_each_solver_reads_its_own_prefixed_options(tmp_path):
    """``-NAME_tao_max_it`` limits solver NAME alone; unprefixed options reach every solver,
    and the file records what each ran with (prefixes taken off)."""
    out = tmp_path / "cmp.h5"
    limits = ("-tron_tao_max_it", "2", "-cg_tao_max_it", "3", "-tao_gatol", "1e-7")
    r = cli(*SCENE, "--pressures", "3e-3", "--solvers", "cg,tron,bncg", *limits,
            "--output", str(out))  # fmt: skip
    assert r.returncode == 1, r.stdout + r.stderr  # two solvers stopped at their limits
    assert "unused" not in r.stderr.lower()  # no solver was handed another's option
    with h5py.File(out) as f:
        its = {name: int(f[name].attrs["iterations"]) for name in ("cg", "tron", "bncg")}
        options = {name: f[name].attrs["petsc_options"].split() for name in ("cg", "tron", "bncg")}
    assert its["tron"] <= 2 and its["cg"] <= 3 and its["bncg"] > 3
    assert options["tron"][-4:] == ["-tao_max_it", "2", "-tao_gatol", "1e-7"]
    assert "-tao_max_it" not in options["bncg"] and options["bncg"][-2:] == ["-tao_gatol", "1e-7"]
