"""Every command of the README's "Command line" block runs as written, exits 0 and converges.

The commands are read from README.md (the first ```sh block of "## Command line": lines
ending in a backslash joined, comment lines and trailing ``# ...`` comments left out), so this
test follows the README when it changes. They run in README order, one test each, in one
shared folder, because later commands read earlier outputs (``measured.h5``). Each runs as
``petsc-contact ARGS`` in the test's process (conftest's ``cli``: the process is not what is
tested here; the ``mpiexec`` line runs as processes) with the README's arguments
unchanged: every grid as printed (512^2 sweeps, a 256^2 punch, compare and ensemble), since
each takes seconds, not minutes, on 2 cores (the README's examples are sized to run in
seconds where a newcomer pastes them). What is added or changed, and why:

- ``h.npy``, which the measured-map and theory commands read, is written first: a 96 x 64
  random-phase self-affine map (H = 0.7, 100 nm rms), in nm, so that the README's
  ``--height-unit nm --length 150um,100um`` gives square pixels and its 100 kPa and 1 MPa on
  1 GPa are partial contact (about 1% and 10% of the area).
- ``study --figure 1 --minutes 45`` computes the paper's 8192^2 study (hours). It runs with
  the README's arguments plus ``--data study --shrink 32`` (its documented quick look: every
  grid divided by 32, pieces written to a folder of the test's own), which completes all
  pieces in seconds, well inside the 45 minutes, so exit 0 is required (75, "paused by
  --minutes", would mean it did not finish).
- ``mpiexec -n 2 .venv/bin/petsc-contact periodic ...`` elides its arguments: they are the
  README's first ``periodic`` command's (its ``--plot`` left out, its output renamed), run
  on 2 ranks (skipped without ``mpiexec``), and its results must match the 1-rank file's.

Every command must exit 0. Every HDF5 file it writes or rewrites must say so: each step's
``converged`` true, each ``compare`` solver group's ``converged`` attribute true, no NaN
(not converged) in an ensemble summary, ``complete`` not false; ``-tao_type X`` is recorded
as the steps' ``tao_type``, and each ``--plot`` file exists.
"""

from __future__ import annotations

import re
import shlex
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import ROOT, cli

EXE = ".venv/bin/petsc-contact"
STUDY_EXTRA = ["--data", "study", "--shrink", "32"]


def _readme_commands() -> list[list[str]]:
    """The argument lists of the README's command-line block, in order."""
    readme = (ROOT / "README.md").read_text()
    section = readme.split("\n## Command line\n", 1)[1].split("\n## ", 1)[0]
    block = re.search(r"```sh\n(.*?)```", section, flags=re.S)
    assert block, "README's Command line section has no ```sh block"
    text = re.sub(r"\\\n", " ", block.group(1))
    commands = []
    for line in text.splitlines():
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        commands.append(shlex.split(line, comments=True))
    return commands


COMMANDS = _readme_commands()


def _first_periodic() -> list[str]:
    return next(argv[1:] for argv in COMMANDS if argv[:2] == [EXE, "periodic"])


def _option(args: list[str], name: str) -> str | None:
    return args[args.index(name) + 1] if name in args else None


def _without(args: list[str], name: str) -> list[str]:
    """``args`` without the option ``name`` and its value."""
    if name not in args:
        return list(args)
    i = args.index(name)
    return args[:i] + args[i + 2 :]


def _resolve(argv: list[str]) -> tuple[list[str], int]:
    """The CLI arguments (after ``petsc-contact``) and the number of ranks for one README line."""
    mpi = 0
    if argv[0] == "mpiexec":
        assert argv[1] == "-n", argv
        mpi, argv = int(argv[2]), argv[3:]
    assert argv[0] == EXE, f"a README command this test does not know how to run: {argv}"
    args = argv[1:]
    if args[0] == "study":
        args = [*args, *STUDY_EXTRA]
    if args[-1] == "...":
        assert args[:-1] == ["periodic"], f"elided arguments this test cannot fill in: {argv}"
        args = _without(_first_periodic(), "--plot")
        output = _option(args, "--output") or "periodic.h5"
        args = [*_without(args, "--output"), "--output", f"mpi{mpi}_{output}"]
    return args, mpi


def _h5_files(folder: Path) -> dict[Path, float]:
    return {p: p.stat().st_mtime_ns for p in folder.rglob("*.h5")}


def _check_converged(path: Path, args: list[str]) -> None:
    with h5py.File(path, "r") as f:
        assert f.attrs.get("complete", True), f"{path.name}: not complete"
        if "converged" in f:
            converged = f["converged"][...]
            assert converged.size and converged.all(), f"{path.name}: converged = {converged}"
            tao_type = _option(args, "-tao_type")
            if tao_type and "tao_type" in f:
                recorded = {v.decode() if isinstance(v, bytes) else v for v in f["tao_type"][...]}
                assert recorded == {tao_type}, f"{path.name}: tao_type {recorded}"
        groups = [name for name in f if isinstance(f[name], h5py.Group)]
        for name in groups:
            if "converged" in f[name].attrs:
                assert f[name].attrs["converged"], f"{path.name}: {name} did not converge"
        if args[0] == "compare":
            solvers = (_option(args, "--solvers") or "").split(",")
            assert [g for g in solvers if g in groups] == solvers, f"{path.name}: {groups}"
        if "seeds" in f and "mean_gap" in f:  # an ensemble summary: NaN where not converged
            assert np.isfinite(f["mean_gap"][...]).all(), f"{path.name}: NaN in mean_gap"
        if "converged" not in f and not groups:  # theory: predictions, no solve
            assert "mean_gap" in f and np.isfinite(f["mean_gap"][...]).all(), path.name


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    """The shared folder, holding the measured map ``h.npy`` the README's commands read."""
    path = tmp_path_factory.mktemp("readme_commands")
    rng = np.random.default_rng(1)
    shape = (96, 64)  # 150 um x 100 um in square pixels
    q = np.hypot(np.fft.fftfreq(shape[0])[:, None], np.fft.rfftfreq(shape[1])[None, :])
    q[0, 0] = np.inf
    spectrum = q**-1.7 * np.exp(2j * np.pi * rng.random(q.shape))  # H = 0.7
    h = np.fft.irfft2(spectrum, shape)
    np.save(path / "h.npy", 100 * h / h.std())  # nm
    return path


def test_the_readme_block_is_parsed():
    """The block is found and holds the commands the README describes, each runnable here."""
    subcommands = [_resolve(argv)[0][0] for argv in COMMANDS]
    for name in ("periodic", "theory", "punch", "plot", "compare", "study", "ensemble"):
        assert name in subcommands, subcommands
    assert any(argv[0] == "mpiexec" for argv in COMMANDS)


@pytest.mark.slow
def test_the_readme_commands_run_in_order(folder, monkeypatch):
    """Every command of the README's block, in its order, in one folder: a command reads what
    earlier ones wrote (``theory --compare``, ``plot``), so they are one test, whichever
    worker of ``-n 2`` runs it."""
    monkeypatch.chdir(folder)  # the subprocesses run here: README's relative paths
    for argv in COMMANDS:
        _command_runs(argv, folder)


def _command_runs(argv: list[str], folder: Path) -> None:
    """Run one of the README's commands in ``folder`` and check what it wrote (an MPI command
    without ``mpiexec``: nothing to run)."""
    args, mpi = _resolve(argv)
    if mpi and not shutil.which("mpiexec"):
        return
    before = _h5_files(folder)
    pngs = {p: p.stat().st_mtime_ns for p in folder.rglob("*.png")}
    run = cli(*args, mpi=mpi, timeout=300)
    command = shlex.join(argv)
    assert run.returncode == 0, (
        f"{command}\nexit {run.returncode}\n{run.stdout[-3000:]}\n{run.stderr}"
    )
    written = [p for p, t in _h5_files(folder).items() if before.get(p) != t]
    output = _option(args, "--output")
    if output:
        assert folder / output in written, f"{command}: wrote {written}, not {output}"
    if args[0] == "study":
        assert written, f"{command}: wrote no pieces"
    for path in written:
        _check_converged(path, args)
    plot = _option(args, "--plot")
    if plot:
        assert (folder / plot).stat().st_size > 0, f"{command}: no {plot}"
    if args[0] == "plot":
        assert any(pngs.get(p) != p.stat().st_mtime_ns for p in folder.rglob("*.png")), command
    if mpi:  # the same scene on 1 rank, written by the README's first command
        serial = folder / (_option(_first_periodic(), "--output") or "-")
        if serial.exists() and output:
            with h5py.File(serial, "r") as one, h5py.File(folder / output, "r") as n:
                assert int(n.attrs["mpi_size"]) == mpi
                np.testing.assert_allclose(n["mean_gap"][...], one["mean_gap"][...], rtol=1e-9)
