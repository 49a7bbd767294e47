"""Optional extras are optional: without mpi4py and mpi4py-fft (the ``mpi`` extra) every
one-rank run works and a run on several ranks says in one line how to install them (exit
69); without SurfaceTopography (``measured``) the package's own readers work and an
instrument file says how to install it (exit 69).

Each extra is hidden from a fresh interpreter: ``sys.modules[name] = None`` makes ``import
name`` fail as it does where the package is not installed."""

from __future__ import annotations

import subprocess

import h5py
import numpy as np
import pytest
from conftest import python

HIDDEN = {"mpi": ("mpi4py", "mpi4py_fft"), "measured": ("SurfaceTopography",)}
SURFACE = ("--grid", "32", "--hurst", "0.7", "--rms-slope", "0.1", "--seed", "2")
UNAVAILABLE = 69


def without(extra: str, code: str, *args: str, mpi: int = 0) -> subprocess.CompletedProcess:
    """Run the Python ``code`` (``sys.argv[1:]`` are ``args``) where the modules of ``extra``
    cannot be imported."""
    hide = "".join(f"sys.modules[{name!r}] = None; " for name in HIDDEN[extra])
    return python("-c", f"import sys; {hide}{code}", *args, mpi=mpi, timeout=240)


def cli_without(extra: str, *args: str, mpi: int = 0) -> subprocess.CompletedProcess:
    """``petsc-contact ARGS`` where the modules of ``extra`` cannot be imported."""
    code = "from petsc_contact.cli import main; sys.exit(main(sys.argv[1:]))"
    return without(extra, code, *args, mpi=mpi)


def one_line(stderr: str, *expected: str) -> None:
    """``stderr`` holds the package's error as one line that contains every ``expected``."""
    errors = [line for line in stderr.splitlines() if line.startswith("petsc-contact: error")]
    assert len(errors) == 1 and "Traceback" not in stderr, stderr
    for text in expected:
        assert text in errors[0], stderr


@pytest.mark.parametrize(
    "command",
    [
        ["periodic", *SURFACE, "--sweep", "3,1e-4,1e-2", "--stiffness"],
        ["punch", *SURFACE, "--forces", "1e-4"],
        ["compare", *SURFACE, "--pressures", "1e-3", "--solvers", "cg,tron"],
        ["ensemble", *SURFACE, "--seeds", "1-2", "--sweep", "2,1e-4,1e-2"],
        ["theory", *SURFACE],
    ],
    ids=lambda command: command[0],
)
def test_one_rank_runs_without_mpi4py(tmp_path, command):
    """Every command on one rank, its files written, mpi4py recorded as not available."""
    out = tmp_path / "out.h5"
    r = cli_without("mpi", *command, "--output", str(out), "--quiet")
    assert r.returncode == 0, r.stdout + r.stderr
    with h5py.File(out) as f:
        assert '"mpi4py": "not available"' in f.attrs["versions"]


def test_the_library_runs_without_mpi4py(tmp_path):
    """``run_contact`` (the README's Python) on one rank, periodic and punch."""
    code = (
        "from petsc_contact import Run, run_contact; "
        "run = Run(grid=32, hurst=0.7, rms_slope=0.1, seed=2, pressures=[1e-3]); "
        "steps = run_contact(run).steps + run_contact("
        "run.with_(geometry='punch', pressures=None, forces=[1e-4])).steps; "
        "sys.exit(0 if all(s.converged for s in steps) else 1)"
    )
    r = without("mpi", code)
    assert r.returncode == 0, r.stdout + r.stderr


def test_several_ranks_without_mpi4py_say_how_to_install_it(tmp_path):
    """Two ranks without mpi4py: one line (from rank 0) naming the install, exit 69."""
    out = str(tmp_path / "out.h5")
    r = cli_without("mpi", "periodic", *SURFACE, "--pressures", "1e-3", "--output", out, mpi=2)
    assert r.returncode == UNAVAILABLE, r.stdout + r.stderr
    one_line(r.stderr, "2 MPI ranks", "pip install 'petsc-contact[mpi]'", "pip install mpi4py")


def test_the_package_readers_work_without_surface_topography(tmp_path):
    """Text, .npy and .h5 maps run; an instrument file says how to install SurfaceTopography."""
    heights = np.random.default_rng(1).standard_normal((32, 32)) * 1e-3
    np.savetxt(tmp_path / "map.txt", heights)
    np.save(tmp_path / "map.npy", heights)
    with h5py.File(tmp_path / "map.h5", "w") as f:
        f["heights"] = heights
    (tmp_path / "scan.x3p").write_bytes(b"PK\x03\x04 an instrument's file")
    run = ("periodic", "--length", "1", "--pressures", "1e-3", "--quiet")
    for name in ("map.txt", "map.npy", "map.h5"):
        heights_file, out = str(tmp_path / name), str(tmp_path / f"{name}.out.h5")
        r = cli_without("measured", *run, "--heights", heights_file, "--output", out)
        assert r.returncode == 0, (name, r.stderr)
        with h5py.File(out) as f:
            assert np.allclose(f["heights"][...], heights), name
    out = str(tmp_path / "scan.h5")
    r = cli_without("measured", *run, "--heights", str(tmp_path / "scan.x3p"), "--output", out)
    assert r.returncode == UNAVAILABLE, r.stdout + r.stderr
    one_line(r.stderr, "scan.x3p", "pip install 'petsc-contact[measured]'", "SurfaceTopography")
