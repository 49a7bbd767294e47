"""Faults injected, not assumed away: SIGKILL at every point of the write path and at random
times, two writers on one output, a full file system, damaged resume state, MPI with fields.
After each, ``--resume`` must end with every step, equal to an uninterrupted run to the
solver's tolerance (docs/reliability.md)."""

from __future__ import annotations

import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import ROOT, cli, python
from kill_at import POINTS, RTOL, resumed_from_state, same_result

SWEEP = "periodic --grid 64 --hurst 0.7 --rms-slope 0.1 --seed 3 --sweep 4,1e-4,1e-2 --stiffness"
PUNCH = "punch --grid 48 --hurst 0.7 --rms-slope 0.1 --seed 3 --forces 1e-4,1e-3,3e-3"


def _whole(tmp_path: Path, command: str, *extra: str) -> Path:
    """The uninterrupted run every interrupted one is held against."""
    out = tmp_path / "whole.h5"
    r = cli(*command.split(), *extra, "--quiet", "--output", str(out))
    assert r.returncode == 0, r.stderr
    return out


@pytest.fixture(scope="module")
def whole_fields(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The uninterrupted sweep with fields (and its step table) that the runs killed at
    every point, at random times and the runs on several ranks are held against."""
    return _whole(tmp_path_factory.mktemp("whole"), SWEEP, "--fields")


def _killed(spec: str, command: str, out: Path | None, *extra: str) -> subprocess.CompletedProcess:
    """``command`` run under tests/kill_at.py (``--output out`` unless ``out`` is None)."""
    args = [*command.split(), *extra, "--quiet", *(["--output", str(out)] if out else [])]
    return python(str(ROOT / "tests" / "kill_at.py"), spec, "--", *args)


def _leftovers(out: Path) -> list[str]:
    """What a run on ``out`` left beside its results: files named after it, the table's too."""
    table = out.with_suffix(".csv").name
    return sorted(p.name for name in (out.name, table) for p in out.parent.glob(name + ".*"))


@pytest.mark.slow
def test_sigkill_at_every_point_of_the_write_path(tmp_path, whole_fields):
    """A sweep with fields killed at each point of its write path: --resume ends it with
    every step, equal to the uninterrupted run, and its step table beside it (a kill after
    the final rename leaves the whole result, the table written before it). Each point is
    its own killed process and resume; the run's size hardly matters (0.4 s of a point's
    2 s of CPU: the rest is the process's start)."""
    whole = whole_fields
    for point in POINTS:
        out = tmp_path / f"{point.replace(':', '-')}.h5"
        r = _killed(point, SWEEP, out, "--fields")
        assert r.returncode == -signal.SIGKILL, (point, r.stderr)
        r = cli(*SWEEP.split(), "--fields", "--quiet", "--output", str(out), "--resume")
        assert r.returncode == 0, (point, r.stderr)
        same_result(whole, out, fields=True)
        assert _leftovers(out) == [], (point, _leftovers(out))
        table = out.with_suffix(".csv").read_text().splitlines()  # the step table beside it
        expected = whole.with_suffix(".csv").read_text().splitlines()
        assert [row.split(",")[0] for row in table] == [row.split(",")[0] for row in expected]
        assert len(table) == 5, (point, len(table))  # the header and four steps


def test_sigkill_at_random_times(tmp_path, whole_fields):
    """Killed at random instants, a sweep with fields, a punch and a comparison each come
    back whole with --resume (seeded, so a failure can be replayed)."""
    rng = random.Random(20261125)
    for command, extra, fields in ((SWEEP, ["--fields"], True), (PUNCH, ["--fields"], True)):
        whole = whole_fields if command == SWEEP else _whole(tmp_path, command, *extra)
        for k in range(3):
            out = tmp_path / f"random{k}.h5"
            args = [sys.executable, "-m", "petsc_contact.cli", *command.split(), *extra]
            args += ["--quiet", "--output", str(out)]
            process = subprocess.Popen(args, env=_env(), stdin=subprocess.DEVNULL)
            time.sleep(rng.uniform(0.5, 3.0))
            process.send_signal(signal.SIGKILL)
            process.wait()
            resume = "--resume" if out.with_name(out.name + ".partial").exists() else "--quiet"
            r = cli(*command.split(), *extra, "--quiet", "--output", str(out), resume)
            assert r.returncode == 0, r.stderr
            same_result(whole, out, fields)


def _env() -> dict[str, str]:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env.pop("PETSC_DIR", None)
    return env


def test_compare_keeps_its_finished_solvers(tmp_path):
    """A comparison killed after its second solver resumes with the first two kept (their
    trajectories as recorded) and runs only the third."""
    command = "compare --grid 48 --hurst 0.7 --rms-slope 0.1 --pressures 1e-3 --solvers cg,pk,bnls"
    out = tmp_path / "cmp.h5"
    r = _killed("after:commit:2", command, out)
    assert r.returncode == -signal.SIGKILL, r.stderr
    with h5py.File(str(out) + ".partial") as f:
        assert json.loads(f.attrs["solvers"]) == ["cg", "pk"]
        kept = f["pk/natural_residual"][...]
    r = cli(*command.split(), "--output", str(out), "--resume")
    assert r.returncode == 0, r.stderr
    with h5py.File(out) as f:
        assert json.loads(f.attrs["solvers"]) == ["cg", "pk", "bnls"] and f.attrs["complete"]
        assert np.array_equal(f["pk/natural_residual"][...], kept)
        assert all(f[s].attrs["converged"] for s in ("cg", "pk", "bnls"))
    assert _leftovers(out) == [] and (tmp_path / "cmp.csv").exists()


def test_compare_resume_removes_a_killed_writers_temporary_file(tmp_path):
    """A comparison killed while its second solver's commit was half written leaves that
    temporary file; the resume that completes it removes it."""
    command = "compare --grid 48 --hurst 0.7 --rms-slope 0.1 --pressures 1e-3 --solvers cg,pk"
    out = tmp_path / "cmp.h5"
    assert _killed("during:commit:2", command, out).returncode == -signal.SIGKILL
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")]
    r = cli(*command.split(), "--output", str(out), "--resume")
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cmp.csv", "cmp.h5", "cmp.png"]


def test_ensemble_and_study_come_back_whole(tmp_path):
    """An ensemble killed while its second seed commits, and a study killed inside its first
    piece: --resume (the study: run again) ends with every seed and every piece, the killed
    ones equal to uninterrupted runs."""
    ensemble = "ensemble --grid 48 --hurst 0.7 --rms-slope 0.1 --seeds 0-2 --pressures 1e-3,1e-2"
    whole = tmp_path / "whole.h5"
    assert cli(*ensemble.split(), "--quiet", "--output", str(whole)).returncode == 0
    out = tmp_path / "ens.h5"
    assert _killed("after:commit:4", ensemble, out).returncode == -signal.SIGKILL  # seed 1
    assert (tmp_path / "ens_seed1.h5.partial").exists() and not out.exists()
    r = cli(*ensemble.split(), "--quiet", "--output", str(out), "--resume")
    assert r.returncode == 0, r.stderr
    with h5py.File(whole) as a, h5py.File(out) as b:
        assert np.allclose(b["mean_gap"][...], a["mean_gap"][...], rtol=RTOL, atol=0)
    data = tmp_path / "paper"
    study = f"study --figure 1 --shrink 128 --data {data} --minutes 10"
    assert _killed("after:commit:3", study, None).returncode == -signal.SIGKILL
    assert (data / "fig1" / "punch.h5.partial").exists()
    r = cli(*study.split(), "--quiet")
    assert r.returncode == 0, r.stderr
    assert sorted(f.name for f in (data / "fig1").iterdir() if f.suffix != ".csv") == [
        "periodic_r1.h5",
        "periodic_r8.h5",
        "punch.h5",
    ]
    late = tmp_path / "late"  # killed after its first piece was renamed into place
    killed = _killed("after:final:1", study.replace(str(data), str(late)), None)
    assert killed.returncode == -signal.SIGKILL
    assert cli(*study.replace(str(data), str(late)).split(), "--quiet").returncode == 0
    assert sorted(f.name for f in (late / "fig1").iterdir()) == [  # each with its table
        "periodic_r1.csv",
        "periodic_r1.h5",
        "periodic_r8.csv",
        "periodic_r8.h5",
        "punch.csv",
        "punch.h5",
    ]
    fresh = tmp_path / "fresh"
    assert cli(*study.replace(str(data), str(fresh)).split(), "--quiet").returncode == 0
    same_result(fresh / "fig1" / "punch.h5", data / "fig1" / "punch.h5", fields=False)


def test_a_second_writer_is_refused_before_it_touches_anything(tmp_path):
    """While one run writes an output, a second on the same output exits 2 at once with one
    line naming it, and the first run ends whole.  The first is held still (SIGSTOP) while
    the second tries, so that however slow the machine, it is under way then: 128^2 (six
    steps with fields, some 0.5 s of CPU after it took the lock; 384^2 took 2.1 s) is ample
    beside the 20 ms it may run before it is stopped."""
    out = tmp_path / "busy.h5"
    slow = f"{SWEEP} --fields".replace("--grid 64", "--grid 128").replace("4,", "6,").split()
    args = [sys.executable, "-m", "petsc_contact.cli", *slow, "--quiet", "--output", str(out)]
    first = subprocess.Popen(args, env=_env(), stdin=subprocess.DEVNULL, stderr=subprocess.PIPE)
    lock = tmp_path / "busy.h5.lock"
    deadline = time.time() + 60
    while not (lock.exists() and lock.read_text()) and time.time() < deadline:
        time.sleep(0.02)
    first.send_signal(signal.SIGSTOP)
    try:
        second = cli(*slow, "--quiet", "--output", str(out), process=True)
    finally:
        first.send_signal(signal.SIGCONT)
    assert first.wait(timeout=300) == 0, first.stderr.read() if first.stderr else ""
    assert second.returncode == 2, second.stderr
    lines = second.stderr.strip().splitlines()
    assert len(lines) == 1 and "is being written by another run (pid" in lines[0], lines
    with h5py.File(out) as f:
        assert f.attrs["complete"] and f["gap"].shape[0] == 6
    resumed = cli(*slow, "--quiet", "--output", str(out), "--resume")  # the lock is free again
    assert resumed.returncode == 0, resumed.stderr


def test_a_damaged_state_file_costs_a_cold_start_not_the_run(tmp_path):
    """A truncated or foreign state file: a warning, the next step from first touch, the
    same result; a damaged .partial is refused in one line."""
    whole = _whole(tmp_path, SWEEP)
    out = tmp_path / "cut.h5"
    pause = [*SWEEP.split(), "--quiet", "--output", str(out), "--stop-after", "0"]
    assert cli(*pause).returncode == 75
    state = Path(f"{out}.state.npz")
    state.write_bytes(state.read_bytes()[:100])
    r = cli(*SWEEP.split(), "--quiet", "--output", str(out), "--resume", "-tao_max_it", "5000")
    assert r.returncode == 0, r.stderr
    assert "state.npz is damaged" in r.stderr and "step 2 starts from first touch" in r.stderr
    same_result(whole, out, fields=False)
    with h5py.File(out) as f:  # the resumed segment's own record
        (resumed,) = json.loads(f.attrs["resumed"])
        assert "--resume" in resumed["command_line"]
        assert "-tao_max_it 5000" in resumed["petsc_options"]
        assert not resumed["from_saved_state"]
    assert cli(*pause).returncode == 75
    Path(f"{out}.partial").write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(200))
    r = cli(*SWEEP.split(), "--quiet", "--output", str(out), "--resume")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "is damaged" in r.stderr


def test_a_resume_from_its_state_goes_on_exactly(tmp_path):
    """A sweep and a punch by force paused after every step and resumed each time from the
    saved state and what the sweep held (the load path; the punch's last Newton point): the
    same steps as the uninterrupted run, to rounding and in iterations."""
    for name, command in (("sweep", SWEEP), ("punch", PUNCH)):
        whole = tmp_path / f"{name}-whole.h5"
        assert cli(*command.split(), "--quiet", "--output", str(whole)).returncode == 0
        out = tmp_path / f"{name}.h5"
        step = [*command.split(), "--quiet", "--output", str(out), "--stop-after", "0"]
        calls = [cli(*step)]
        while calls[-1].returncode == 75:
            calls.append(cli(*step, "--resume"))
        assert calls[-1].returncode == 0 and len(calls) > 2, calls[-1].stderr
        with h5py.File(out) as f:
            assert resumed_from_state(f) and len(json.loads(f.attrs["resumed"])) == len(calls) - 1
        same_result(whole, out, fields=False)  # to EXACT


@pytest.fixture
def small_disk(tmp_path):
    """A 2.5 MiB tmpfs, or a skip where this machine does not allow mounting one."""
    mount = tmp_path / "disk"
    mount.mkdir()
    r = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=2560k", "tmpfs", str(mount)], capture_output=True
    )
    if r.returncode != 0:
        pytest.skip(f"cannot mount a small tmpfs here: {r.stderr.decode().strip()}")
    yield mount
    subprocess.run(["umount", "-l", str(mount)], check=False)


def test_a_full_disk_is_an_error_and_resume_completes(tmp_path, small_disk):
    """Fields fill the disk after a few steps: exit 74 in one line, the finished steps kept,
    never a file marked complete; with room again --resume completes the run correctly."""
    command = SWEEP.replace("--grid 64", "--grid 192").replace("4,", "8,")
    whole = _whole(tmp_path, command, "--fields")
    out = small_disk / "full.h5"
    r = cli(*command.split(), "--fields", "--quiet", "--output", str(out))
    assert r.returncode == 74, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "No space left on device" in lines[0], lines
    assert "finished step(s) kept" in lines[0] and not out.exists()
    with h5py.File(str(out) + ".partial") as f:
        kept = f["converged"].shape[0]
        assert not f.attrs["complete"] and 0 < kept < 8
    subprocess.run(["mount", "-o", "remount,size=64m", str(small_disk)], check=True)
    r = cli(*command.split(), "--fields", "--quiet", "--output", str(out), "--resume")
    assert r.returncode == 0, r.stderr
    same_result(whole, out, fields=True)


def test_fields_on_several_ranks_equal_the_serial_run(tmp_path, whole_fields):
    """With --fields on 2 and 3 ranks the file is the serial one's (it used to hang)."""
    whole = whole_fields
    for ranks in (2, 3):
        out = tmp_path / f"mpi{ranks}.h5"
        r = cli(*SWEEP.split(), "--fields", "--quiet", "--output", str(out), mpi=ranks)
        assert r.returncode == 0, r.stderr
        same_result(whole, out, fields=True)


def test_a_closed_pipe_ends_the_table_not_the_run(tmp_path):
    """``petsc-contact ... | head -2``: the run still writes its file and plot, quietly."""
    out, png = tmp_path / "piped.h5", tmp_path / "piped.png"
    exe = shutil.which("head")
    assert exe
    command = f"{sys.executable} -m petsc_contact.cli {SWEEP} --output {out} --plot {png}"
    r = subprocess.run(
        ["bash", "-c", f"{command} | {exe} -2; exit ${{PIPESTATUS[0]}}"],
        capture_output=True,
        text=True,
        env=_env(),
    )
    assert r.returncode == 0 and r.stderr == "", r.stderr
    assert len(r.stdout.splitlines()) == 2
    with h5py.File(out) as f:
        assert f.attrs["complete"]
    assert png.stat().st_size > 0


def test_bad_inputs_get_one_line_and_leave_nothing(tmp_path):
    """Each bad input: exit 2, one line on stderr, no traceback, no file left behind."""
    rng = np.random.default_rng(0)
    np.save(tmp_path / "huge.npy", rng.standard_normal((32, 32)) * 1e300)
    np.save(tmp_path / "flat.npy", np.ones((32, 32)))
    out = str(tmp_path / "out.h5")
    gen = "--grid 32 --hurst 0.7 --rms-slope 0.1".split()
    cases = {
        "--minutes": ["study", "--minutes", "nan", "--data", str(tmp_path / "d")],
        "minutes must be": ["study", "--minutes=-1", "--data", str(tmp_path / "d")],
        "--stop-after": ["periodic", *gen, "--pressures", "1e-3", "--stop-after", "nan"],
        "GiB available": ["periodic", "--grid", "200000", "--hurst", "0.7", "--rms-slope", "1"],
        "a seed is from 0": ["periodic", *gen, "--seed", str(2**70), "--pressures", "1e-3"],
        "flat": ["theory", "--heights", str(tmp_path / "flat.npy")],
        "names no solver": ["compare", *gen, "--pressures", "1e-3", "--solvers", ","],
        "does not exist (-options_file)": ["periodic", *gen, "-options_file", "/no/such.opts"],
        "heights up to": ["periodic", "--heights", str(tmp_path / "huge.npy")],
        "more than 1e+06 E*": ["periodic", *gen, "--pressures", "1e300"],
        "below what double precision resolves": ["periodic", *gen, "--pressures", "1e-12"],
        "-tao_gatol takes a number, not 'abc'": ["periodic", *gen, "-tao_gatol", "abc"],
        "give an output file name": ["periodic", *gen, "--output", ""],
        "unrecognized arguments: --no-such": ["periodic", *gen, "--no-such"],
    }
    for words, args in cases.items():
        if "--output" not in args and args[0] != "study":
            args = [*args, "--output", out]
        if args[0] == "periodic" and "--pressures" not in args:
            args = [*args, "--pressures", "1e-3"]
        r = cli(*args)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 2, (words, r.stderr)
        assert len(lines) == 1 and lines[0].startswith("petsc-contact: error:"), (words, lines)
        assert words in lines[0], (words, lines[0])
        left = sorted(p.name for p in tmp_path.iterdir())
        assert left == ["flat.npy", "huge.npy"], (words, left)


def test_an_unresolved_force_is_flagged_not_converged(petsc):
    """A force whose approach is lost in the gap tolerance comes back with force 0: it is
    flagged, with the reason, never reported converged; a resolved one meets its target."""
    from petsc_contact import punch_contact
    from petsc_contact.paper.figures import surface

    h, _ = surface(32, 0.7, 1.0, 16.0, 1)
    tiny, fine = punch_contact(h, length=1.0, modulus=1.0, forces=[1e-30, 1e-3])
    assert not tiny.converged and "below what this grid resolves" in tiny.scalars["verification"]
    assert fine.converged and abs(fine.scalars["force"] / 1e-3 - 1) < 1e-4
