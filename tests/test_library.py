"""One run, two doors: the library does what the command line does, to the same file."""

import json
import os
import sys

import h5py
import numpy as np
import pytest
from conftest import cli, python

from petsc_contact import Run, read_frame, run_contact, run_ensemble

GEN = dict(grid=48, hurst=0.7, rms_slope=0.1, seed=2)
CLI_GEN = "--grid 48 --hurst 0.7 --rms-slope 0.1 --seed 2".split()


def test_a_run_from_python_writes_the_command_lines_file(tmp_path, petsc):
    """run_contact with a progress callback and a TAO monitor: the same steps and file as
    ``petsc-contact periodic``; the table as a DataFrame, from the result or the file."""
    seen, its = [], []
    run = Run(**GEN, sweep=(4,), stiffness=True, fields=True, output=str(tmp_path / "py.h5"))
    result = run_contact(
        run,
        progress=lambda i, n, s: seen.append((i, n, s["nominal_pressure"])),
        monitor=lambda it, f, g: its.append(it) and False,
    )
    r = cli("periodic", *CLI_GEN, "--sweep", "4", "--stiffness", "--fields", "--quiet",
            "--output", str(tmp_path / "cli.h5"))  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert result.status == "complete" and result.converged and len(seen) == 4 and its
    assert [s[:2] for s in seen] == [(i, 4) for i in range(4)]
    with h5py.File(tmp_path / "py.h5") as a, h5py.File(tmp_path / "cli.h5") as b:
        for name in ("nominal_pressure", "mean_gap", "stiffness", "area_fraction"):
            assert np.allclose(a[name][:], b[name][:], rtol=1e-9, atol=0), name
        assert np.allclose(a["gap"][...], b["gap"][...], rtol=0, atol=1e-12)
        assert json.loads(a.attrs["parameters"])["sweep"] is None  # the loads are recorded
    frame, again = result.to_dataframe(), read_frame(str(tmp_path / "py.h5"))
    assert list(frame.index) == [1, 2, 3, 4] and frame.index.name == "step"
    assert np.allclose(frame["mean_gap"], again["mean_gap"], rtol=1e-15)
    assert (tmp_path / "py.csv").read_text().splitlines()[0].startswith("step,")


def test_pause_and_resume_from_python(tmp_path, petsc):
    """stop_after pauses after a step (its file kept as .partial); resume=True completes it
    to the steps of an uninterrupted run."""
    base = Run(**GEN, sweep=(4,), output=str(tmp_path / "cut.h5"))
    paused = run_contact(base.with_(stop_after=0))
    assert paused.status == "paused" and len(paused.table) == 1
    assert (tmp_path / "cut.h5.partial").exists() and not (tmp_path / "cut.h5").exists()
    done = run_contact(base.with_(resume=True))
    whole = run_contact(base.with_(output=None))
    assert done.status == "complete" and len(done.table) == 4 and len(done.steps) == 3
    gaps = [s["mean_gap"] for s in done.table]
    assert np.allclose(gaps, [s["mean_gap"] for s in whole.table], rtol=1e-6)


def test_ensemble_from_python_equals_the_command_line(tmp_path, petsc):
    base = Run(**GEN, pressures=(1e-3, 1e-2), output=str(tmp_path / "py.h5"))
    result = run_ensemble(base, [0, 1])
    r = cli("ensemble", *CLI_GEN, "--seeds", "0-1", "--pressures", "1e-3,1e-2", "--quiet",
            "--output", str(tmp_path / "cli.h5"))  # fmt: skip
    assert r.returncode == 0, r.stderr
    with h5py.File(tmp_path / "cli.h5") as f:
        assert np.allclose(result.summary["mean_gap"], f["mean_gap"][...], rtol=1e-9)
    assert list(result.to_dataframe()["nominal_pressure"]) == [1e-3, 1e-2]


def test_descriptions_check_their_numbers_and_say_their_command_line():
    with pytest.raises(ValueError, match="--modulus must be positive"):
        Run(**GEN, modulus=-1)
    with pytest.raises(ValueError, match="--pressures must be positive"):
        Run(**GEN, pressures=(1e-3, 0.0))
    run = Run(geometry="punch", **GEN, forces=(1e-4, 1e-3), fields=True)
    assert run.arguments()[:3] == ["punch", "--grid", "48"]
    assert "--forces" in run.arguments() and "--fields" in run.arguments()


def test_importing_the_package_and_its_help_load_no_solver():
    """``import petsc_contact`` and building the CLI's parser load neither numba, scipy,
    mpi4py nor PETSc (they are loaded when a run needs them)."""
    code = (
        "import sys, petsc_contact; from petsc_contact.cli.main import main; "
        "from petsc_contact.cli.arguments import build_parser; build_parser(); "
        "print(sorted(m for m in ('numba', 'scipy', 'mpi4py', 'petsc4py', 'h5py') "
        "if m in sys.modules))"
    )
    r = python("-c", code)
    assert r.returncode == 0 and r.stdout.strip() == "[]", (r.stdout, r.stderr)


@pytest.mark.parametrize(
    "old, new, name",
    [
        ("conventions.fft", "devices.fft", "make_fft"),
        ("backend.kernels", "numerics.kernels", "compile_kernels"),
        ("backend.schur", "numerics.schur", "ContactSchur"),
        ("solver.cg", "solver.constrained_cg", "ConstrainedCG"),
        ("workflows.ensemble", "paper.fits", "power_law_fit"),
        ("workflows.paper_study", "paper.paper_study", "run_pieces"),
        ("workflows.predictions", "paper.predictions", "predict_map"),
        ("workflows.redraw", "paper.redraw", "redraw"),
        ("workflows.scenes", "paper.figures", "stiffness_curve"),
        ("workflows.theory_file", "paper.theory_file", "write_theory"),
        ("workflows.theory_run", "paper.theory_run", "line_scan"),
        ("numerics.device", "devices.device", "Device"),
        ("numerics.fft", "devices.fft", "make_fft"),
        ("numerics.passes", "devices.passes", "ArrayPasses"),
        ("numerics.fused", "devices.fused", "FusedPasses"),
    ],
)
def test_moved_modules_warn_and_forward(old, new, name):
    """Moved modules still import from their old paths, with a DeprecationWarning naming the
    new one, and give the same objects (``petsc_contact._moved``)."""
    import importlib
    import sys

    sys.modules.pop(f"petsc_contact.{old}", None)
    with pytest.warns(DeprecationWarning, match=f"petsc_contact.{new}"):
        module = importlib.import_module(f"petsc_contact.{old}")
    assert getattr(module, name) is getattr(importlib.import_module(f"petsc_contact.{new}"), name)


def test_the_source_commit_says_dirty_for_a_change_anywhere_in_the_package(tmp_path):
    """``+dirty`` follows a local change in any of the package's folders (it once looked
    only at ``io/``, where :func:`source_commit` lives), and only there."""
    import shutil
    import subprocess

    from petsc_contact.io import provenance

    repo = tmp_path / "repo"
    shutil.copytree(
        os.path.dirname(provenance.__file__).rsplit(os.sep, 1)[0],
        repo / "petsc_contact",
        ignore=shutil.ignore_patterns("__pycache__"),
    )
    git = ["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t"]
    subprocess.run([*git, "init", "-q"], check=True)
    subprocess.run([*git, "add", "."], check=True)
    subprocess.run([*git, "commit", "-qm", "x"], check=True)
    probe = [
        sys.executable,
        "-c",
        "from petsc_contact.io.provenance import source_commit as s; print(s())",
    ]

    def commit() -> str:
        done = subprocess.run(probe, cwd=repo, capture_output=True, text=True, check=True)
        return done.stdout.strip()

    assert not commit().endswith("+dirty")
    (repo / "notes.txt").write_text("outside the package")
    assert not commit().endswith("+dirty")
    with open(repo / "petsc_contact" / "solver" / "cg.py", "a") as f:
        f.write("# a local change\n")
    assert commit().endswith("+dirty")


def test_the_numba_passes_keep_their_old_names_with_a_warning():
    """The ``cpu`` device's numba passes, now :mod:`petsc_contact.devices.compiled`, still
    read from :mod:`petsc_contact.numerics.kernels`, with a DeprecationWarning naming the new
    path, as the same functions; any other missing name is refused."""
    from petsc_contact.devices import compiled
    from petsc_contact.numerics import kernels

    for name in kernels.PASSES:
        with pytest.warns(DeprecationWarning, match=f"petsc_contact.devices.compiled.{name}"):
            assert getattr(kernels, name) is getattr(compiled, name)
    with pytest.raises(AttributeError):
        kernels.not_a_pass  # noqa: B018
