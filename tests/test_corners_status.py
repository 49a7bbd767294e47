"""Options that do what they say, statuses said before anything runs, nothing half-written
on a full disk, and hints where more ranks do not help.  Each fault or bad input is injected:
a command line, a full disk (a small tmpfs, or a write made to fail), swapped state slabs, a
signal sent to the library."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import cli, python
from test_reliability import small_disk  # noqa: F401 (a fixture)

SURFACE = ["--grid", "32", "--hurst", "0.7", "--rms-slope", "0.1", "--seed", "3"]
PERIODIC = ["periodic", *SURFACE, "--pressures", "1e-3"]


def _one_line(r: subprocess.CompletedProcess, status: int, *words: str) -> str:
    """The one line ``r`` said on standard error (nothing on standard output: said before
    anything ran), after checking its status and words."""
    lines = r.stderr.strip().splitlines()
    assert r.returncode == status and len(lines) == 1, (r.returncode, lines, r.stdout)
    assert all(w in lines[0] for w in words), (words, lines[0])
    return lines[0]


def _fill(disk: Path) -> None:
    """Leave no byte free on ``disk``."""
    with open(disk / "filler", "wb") as f, pytest.raises(OSError):
        while True:
            f.write(bytes(1 << 16))
            f.flush()


# --options-prefix on the command line, as in Run


def test_options_prefix_on_the_command_line_reaches_the_run_alone(tmp_path):
    """``--options-prefix a_ -a_tao_type tron`` runs TRON, with no word of unused options;
    an unprefixed option is not the run's: it is said to be unused, and has no effect."""
    out = tmp_path / "p.h5"
    r = cli(*PERIODIC, "--quiet", "--output", str(out), "--options-prefix", "a_",
            "-a_tao_type", "tron")  # fmt: skip
    assert r.returncode == 0 and "never used" not in r.stderr, r.stderr
    with h5py.File(out) as f:
        assert [t.decode() for t in f["tao_type"][...]] == ["tron"]
    r = cli(*PERIODIC, "--quiet", "--output", str(out), "--overwrite", "--options-prefix", "a_",
            "-tao_type", "bncg")  # fmt: skip
    assert r.returncode == 0 and "PETSc options never used: -tao_type" in r.stderr, r.stderr
    with h5py.File(out) as f:
        assert [t.decode() for t in f["tao_type"][...]] == ["cg"]


# per-solver options of compare


def _solver(path: Path, name: str) -> dict[str, object]:
    with h5py.File(path) as f:
        return {k: f[name].attrs[k] for k in ("petsc_options", "iterations", "solve_time")}


def test_per_solver_options_are_used_and_a_changed_one_is_solved_again(tmp_path):
    """``-bncg_tao_max_it 5`` reaches bncg alone, never said to be unused, and bncg's group
    records it; ``--resume`` with ``-bncg_tao_max_it 500`` solves bncg again (cg kept)."""
    out = tmp_path / "c.h5"
    scene = ["compare", *SURFACE, "--pressures", "1e-3", "--solvers", "cg,bncg", "--quiet"]
    r = cli(*scene, "--output", str(out), "-bncg_tao_max_it", "5")
    assert r.returncode in (0, 1) and "never used" not in r.stderr, r.stderr
    cg, bncg = _solver(out, "cg"), _solver(out, "bncg")
    assert "-tao_max_it 5" in str(bncg["petsc_options"]) and int(bncg["iterations"]) <= 5
    assert "-tao_max_it" not in str(cg["petsc_options"])
    r = cli(*scene, "--output", str(out), "--resume", "-bncg_tao_max_it", "500")
    assert r.returncode == 0 and "never used" not in r.stderr, r.stderr
    again = _solver(out, "bncg")
    assert "-tao_max_it 500" in str(again["petsc_options"]) and int(again["iterations"]) > 5
    assert _solver(out, "cg") == cg  # unchanged: kept as it was


# a full disk: 74, nothing half-written


def test_a_full_disk_under_a_figure_is_74_and_leaves_no_torn_figure(tmp_path, small_disk):  # noqa: F811
    """``theory --plot`` and ``plot --output`` on a full disk: exit 74 in one line, and no
    figure (not a 0-byte one) nor a temporary file left."""
    out = tmp_path / "t.h5"
    _fill(small_disk)
    png = small_disk / "t.png"
    r = cli("theory", *SURFACE, "--output", str(out), "--plot", str(png), "--quiet")
    assert r.returncode == 74 and "No space left on device" in r.stderr, r.stderr
    assert sorted(p.name for p in small_disk.iterdir()) == ["filler"]
    with h5py.File(out) as f:  # written whole before the figure
        assert f.attrs["geometry"] == "theory"
    r = cli("plot", str(out), "--output", str(small_disk / "again.png"))
    _one_line(r, 74, "cannot write", "No space left on device")
    assert sorted(p.name for p in small_disk.iterdir()) == ["filler"]


FULL_AT_FIGURES = """
import errno, sys
from matplotlib.figure import Figure
from petsc_contact.cli.main import main

def full(self, name, **kw):  # a few bytes written, then the disk is full
    with open(name, "wb") as f:
        f.write(b"\\x89PNG")
    raise OSError(errno.ENOSPC, "No space left on device")

Figure.savefig = full
sys.exit(main(sys.argv[1:]))
"""


def test_compare_on_a_full_disk_at_its_figure_is_74_with_nothing_stale(tmp_path):
    """The disk fills as ``compare`` draws its figure: exit 74 in one line, the whole
    comparison in OUT.h5 and no ``.partial`` beside it, no torn figure; ``--resume`` then
    draws it."""
    out = tmp_path / "c.h5"
    args = ["compare", *SURFACE, "--pressures", "1e-3", "--solvers", "cg", "--quiet",
            "--output", str(out)]  # fmt: skip
    r = python("-c", FULL_AT_FIGURES, *args)
    _one_line(r, 74, "c.png", "No space left on device")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.csv", "c.h5"]
    with h5py.File(out) as f:
        assert f.attrs["complete"] and json.loads(f.attrs["solvers"]) == ["cg"]
    assert cli(*args, "--resume").returncode == 0
    assert (tmp_path / "c.png").stat().st_size > 0


# statuses said in one line before anything runs


def test_plot_draws_an_experiment_file(tmp_path):
    """``plot`` of an ``experiment`` file draws its figure (no traceback)."""
    table, out = tmp_path / "t.txt", tmp_path / "e.h5"
    table.write_text("0.1 1\n0.2 1.5\n0.4 1.9\n0.8 2.2\n1.6 2.4\n")
    r = cli("experiment", "--table", str(table), "--modulus", "1", "--thickness", "0.1",
            "--output", str(out), "--quiet")  # fmt: skip
    assert r.returncode == 0, r.stderr
    r = cli("plot", str(out))
    assert r.returncode == 0 and not r.stderr, r.stderr
    assert (tmp_path / "e_redrawn.png").stat().st_size > 0


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["punch", *SURFACE, "--forces", "1e300"], ("--forces", "no elastic contact")),
        ([*PERIODIC, "--length", "150um,"], ("--length", "150um,")),
        ([*PERIODIC, "-tao_max_it", "abc"], ("-tao_max_it takes a whole number", "abc")),
        ([*PERIODIC, "--options-prefix", "a_", "-a_tao_gatol", "x"], ("-a_tao_gatol", "'x'")),
    ],
    ids=["huge-force", "length-comma", "int-option", "prefixed-real-option"],
)
def test_bad_input_is_one_line_before_anything_runs(tmp_path, args, words):
    """Each bad input is exit 2 in one line, with nothing printed nor written."""
    out = tmp_path / "o.h5"
    _one_line(cli(*args, "--output", str(out)), 2, *words)
    assert list(tmp_path.iterdir()) == []


def test_an_output_named_as_a_folder_is_bad_input(tmp_path):
    """``--output x.h5/`` names a folder: exit 2, as a folder that exists is."""
    _one_line(cli(*PERIODIC, "--output", f"{tmp_path / 'x.h5'}/"), 2, "is a folder")
    assert list(tmp_path.iterdir()) == []


def test_the_library_refuses_an_option_value_of_the_wrong_type():
    """``Run(options=...)`` with ``-tao_max_it abc``: ``ValueError`` at once."""
    from petsc_contact import Run

    with pytest.raises(ValueError, match="-tao_max_it takes a whole number, not 'abc'"):
        Run(grid=32, hurst=0.7, rms_slope=0.1, pressures=1e-3, options="-tao_max_it abc")


SWEEP = [*SURFACE, "--sweep", "3,1e-4,1e-2", "--quiet"]


def test_swapped_state_slabs_are_not_used(tmp_path):
    """A run paused on 2 ranks whose two state slabs (of equal rows) are swapped: the resume
    says so and starts that step from first touch, never from another rank's rows."""
    out = tmp_path / "s.h5"
    r = cli("periodic", *SWEEP, "--output", str(out), "--stop-after", "0", mpi=2, timeout=120)
    assert r.returncode == 75, r.stderr
    first, second = (tmp_path / f"s.h5.state.{k}of2.npz" for k in (0, 1))
    swap = tmp_path / "swap.npz"
    first.rename(swap)
    second.rename(first)
    swap.rename(second)
    r = cli("periodic", *SWEEP, "--output", str(out), "--resume", mpi=2, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stderr.count("holds the rows of rank 1 of 2, not of rank 0") == 1, r.stderr
    assert "first touch" in r.stderr, r.stderr


SIGTERM_IN_THE_LIBRARY = """
import os, signal, sys
from petsc_contact import Run, run_contact
from petsc_contact.workflows.runner import RunInterrupted

run = Run(grid=32, hurst=0.7, rms_slope=0.1, seed=3, sweep=(3, 1e-4, 1e-2), output=sys.argv[1])
try:
    run_contact(run, progress=lambda i, n, s: os.kill(os.getpid(), signal.SIGTERM))
except RunInterrupted as exc:
    print("interrupted:", exc)
assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL  # the caller's handler restored
result = run_contact(run.with_(resume=True))
print("resumed:", result.status, len(result.table))
"""


def test_sigterm_in_the_library_raises_an_interrupt_and_the_run_resumes(tmp_path):
    """SIGTERM during ``run_contact`` raises ``RunInterrupted`` (not the end of the
    process), its steps kept, the handler restored; ``resume=True`` completes it."""
    r = python("-c", SIGTERM_IN_THE_LIBRARY, str(tmp_path / "l.h5"))
    assert r.returncode == 0 and "first touch" not in r.stderr, r.stderr  # its state used
    lines = r.stdout.splitlines()
    assert lines[0].startswith("interrupted:") and "1 finished step(s) kept" in lines[0], lines
    assert lines[1] == "resumed: complete 3", lines


# more ranks than help


def test_more_ranks_than_the_grid_can_use_are_said_once(tmp_path):
    """An ensemble of two seeds of a 32^2 grid on 2 ranks: one warning line that the ranks
    are more than the grid can use, for the whole ensemble."""
    out = tmp_path / "e.h5"
    r = cli("ensemble", *SURFACE, "--seeds", "1,2", "--pressures", "1e-3", "--quiet",
            "--output", str(out), mpi=2, timeout=120)  # fmt: skip
    assert r.returncode == 0, r.stderr
    said = [line for line in r.stderr.splitlines() if "MPI ranks are more than" in line]
    assert len(said) == 1 and "32 rows" in said[0], r.stderr
    assert np.all(np.isfinite(h5py.File(out)["mean_gap_mean"][...]))
    assert not os.path.exists(str(out) + ".partial")


def test_compare_keeps_a_solver_only_while_its_options_file_says_the_same(tmp_path):
    """A finished solver is kept by ``compare --resume`` only while its options, and what its
    options file says, are those it ran with; options with spaces survive the file."""
    import h5py

    from petsc_contact.workflows.compare import Trajectory, _write_groups, read_partial, unchanged

    folder = tmp_path / "my opts"
    folder.mkdir()
    opts = folder / "s.opts"
    opts.write_text("-tao_type bncg\n")
    name = str(opts)
    ran = Trajectory(name, ["-options_file", name])
    with h5py.File(tmp_path / "c.h5.partial", "w") as f:
        _write_groups(f, {}, [ran], {"parameters": {}, "solvers": [name]})
    (back,) = read_partial(str(tmp_path / "c.h5"), {})
    assert back.options == ["-options_file", name]
    assert unchanged([back], [name], []) == [back]
    opts.write_text("-tao_type blmvm\n")  # edited since: solved again
    assert unchanged([back], [name], []) == []
    with h5py.File(tmp_path / "c.h5.partial") as f:  # the file records what it ran with
        assert "bncg" in f[next(iter(f))].attrs["options_file_text"]


def test_a_callers_own_interrupt_handler_keeps_the_signals_it_remembered():
    """``interruptible`` under a caller that handles SIGTERM itself (as the command line
    does) leaves the signals remembered within the block to the caller's check."""
    import signal

    from petsc_contact.io import interrupts

    before = signal.signal(signal.SIGTERM, interrupts.interrupt)
    try:
        interrupts.forget_interrupts()
        with interrupts.interruptible():
            interrupts._SIGNALLED.append(signal.SIGTERM)  # as a finaliser's dropped signal
        with pytest.raises(KeyboardInterrupt):
            interrupts.check_interrupt()
    finally:
        signal.signal(signal.SIGTERM, before)
        interrupts.forget_interrupts()
