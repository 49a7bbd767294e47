"""Nothing silently wrong: finished steps never deleted unasked, part files checked against
their commit's checksums, the step table and the HDF5 file always of one run, signals never
lost, a full disk refused in one line (docs/reliability.md).  Each fault is injected."""

from __future__ import annotations

import json
import shutil
import signal
import subprocess
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import ROOT, cli, python
from kill_at import same_result
from test_reliability import _leftovers, small_disk  # noqa: F401 (a fixture)

SWEEP = "periodic --grid 32 --hurst 0.7 --rms-slope 0.1 --seed 3 --sweep 3,1e-4,1e-2 --fields"


def _run(out: Path, *extra: str, seed: int = 3) -> subprocess.CompletedProcess:
    """The sweep (with ``seed``) on output ``out``."""
    command = SWEEP.replace("--seed 3", f"--seed {seed}").split()
    return cli(*command, "--quiet", "--output", str(out), *extra)


def _killed(spec: str, out: Path, *extra: str, seed: int = 3) -> subprocess.CompletedProcess:
    """The sweep on ``out`` under tests/kill_at.py ``spec``."""
    command = SWEEP.replace("--seed 3", f"--seed {seed}").split()
    args = [*command, "--quiet", "--output", str(out), *extra]
    return python(str(ROOT / "tests" / "kill_at.py"), spec, "--", *args)


@pytest.fixture(scope="module")
def whole(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The uninterrupted sweep every other is held against."""
    out = tmp_path_factory.mktemp("whole") / "whole.h5"
    r = _run(out)
    assert r.returncode == 0, r.stderr
    return out


def _one_line(r: subprocess.CompletedProcess, status: int, *words: str) -> str:
    """The one line ``r`` said on standard error, after checking its status and words."""
    lines = r.stderr.strip().splitlines()
    assert r.returncode == status and len(lines) == 1, (r.returncode, lines)
    assert all(w in lines[0] for w in words), (words, lines[0])
    return lines[0]


def _steps(partial: str | Path) -> int:
    with h5py.File(partial) as f:
        return int(f["converged"].shape[0]) if "converged" in f else 0


def _as_output(src: Path, dst: Path) -> None:
    """The unfinished run files of output ``src`` copied to be those of output ``dst``."""
    shutil.copytree(f"{src}.parts", f"{dst}.parts")
    shutil.copy(f"{src}.state.npz", f"{dst}.state.npz")
    shutil.copy(f"{src}.partial", f"{dst}.partial")
    with h5py.File(f"{dst}.partial", "r+") as f:
        parameters = json.loads(f.attrs["parameters"])
        f.attrs["parameters"] = json.dumps({**parameters, "output": str(dst)})


def test_finished_steps_are_never_discarded_silently(tmp_path, whole):
    """The same command again, without --resume, over an interrupted run's finished steps is
    refused in one line naming --resume and --overwrite, and deletes nothing; a .partial
    with no finished step, or one beside its own complete output, is no loss; a damaged one
    is refused naming --overwrite, which starts afresh."""
    out = tmp_path / "kept.h5"
    assert _killed("after:commit:3", out).returncode == -signal.SIGKILL  # 2 steps committed
    _one_line(_run(out), 2, "2 finished step(s)", "--resume continues", "--overwrite")
    assert _steps(f"{out}.partial") == 2
    assert _run(out, "--resume").returncode == 0
    same_result(whole, out, fields=True)

    empty = tmp_path / "empty.h5"  # killed after the first commit, which holds no step
    assert _killed("after:commit:1", empty).returncode == -signal.SIGKILL
    assert _run(empty).returncode == 0 and _leftovers(empty) == []

    done = tmp_path / "done.h5"  # killed after its OUT.h5 was renamed into place
    assert _killed("after:final:1", done).returncode == -signal.SIGKILL
    assert _run(done).returncode == 0 and _leftovers(done) == []

    Path(f"{out}.partial").write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(200))
    _one_line(_run(out), 2, "is damaged", "--overwrite starts afresh")
    _one_line(_run(out, "--resume"), 2, "is damaged", "--overwrite starts afresh")
    assert _run(out, "--overwrite").returncode == 0 and _leftovers(out) == []
    same_result(whole, out, fields=True)


def _invert(path: Path, count: int = 64) -> None:
    """Invert ``count`` bytes in the middle of ``path``."""
    data = bytearray(path.read_bytes())
    middle = len(data) // 2
    data[middle : middle + count] = bytes(255 - b for b in data[middle : middle + count])
    path.write_bytes(bytes(data))


def _without_checksums(out: Path) -> None:
    """Make ``out``'s .partial one of an earlier version: no checksums of its parts."""
    with h5py.File(f"{out}.partial", "r+") as f:
        del f.attrs["parts"]


def test_missing_damaged_or_foreign_parts_are_computed_again(tmp_path, whole):
    """A run killed before its assembly, then its heights part removed, a step's part damaged
    or replaced by another step's, the parts folder a plain file, or its .partial of an
    earlier version (no checksums): --resume says what it computes again, and ends with
    every step equal to the uninterrupted run."""
    cut = tmp_path / "cut.h5"
    assert _killed("before:final:1", cut).returncode == -signal.SIGKILL

    def step(out: Path, k: int) -> Path:
        return Path(f"{out}.parts") / f"step-{k:06d}.h5"

    faults = {
        "heights.h5 is missing": lambda out: Path(f"{out}.parts/heights.h5").unlink(),
        "step-000002.h5 does not match the checksum": lambda out: _invert(step(out, 2)),
        "step-000003.h5 does not match": lambda out: shutil.copy(step(out, 1), step(out, 3)),
        "step-000001.h5 is missing": lambda out: (
            shutil.rmtree(f"{out}.parts"),
            Path(f"{out}.parts").write_text("not a folder"),
        ),
        "": _without_checksums,
    }
    for number, (words, fault) in enumerate(faults.items()):
        out = tmp_path / f"fault{number}.h5"
        _as_output(cut, out)
        fault(out)
        r = _run(out, "--resume")
        assert r.returncode == 0, (words, r.stderr)
        assert words in r.stderr and ("again" in r.stderr) == bool(words), (words, r.stderr)
        same_result(whole, out, fields=True)
        assert _leftovers(out) == [], (words, _leftovers(out))


def test_a_part_damaged_during_the_run_stops_its_assembly(tmp_path, whole):
    """A step's part or the heights part damaged after its commit: the assembly stops with
    exit 74 in one line saying what --resume computes again, no OUT.h5; --resume ends it
    equal to the uninterrupted run."""
    for spec, words in (
        ("damage:step:2", "--resume computes steps 2 to 3 again"),
        ("damage:heights:1", "--resume writes it again"),
    ):
        out = tmp_path / f"{spec.replace(':', '-')}.h5"
        _one_line(_killed(spec, out), 74, "cannot assemble", words, "3 finished step(s) kept")
        assert not out.exists()
        assert _run(out, "--resume").returncode == 0
        same_result(whole, out, fields=True)


def _one_run(out: Path) -> None:
    """Assert that ``out``'s step table, where there is one, is that of ``out``."""
    table = out.with_suffix(".csv")
    if not table.exists():
        return
    lines = table.read_text().splitlines()
    column = lines[0].split(",").index("mean_gap")
    mean_gap = [float(row.split(",")[column]) for row in lines[1:]]
    with h5py.File(out) as f:
        assert np.array_equal(mean_gap, f["mean_gap"][...]), out


def test_the_table_and_the_file_are_of_one_run_whatever_instant(tmp_path, whole):
    """Another seed's run over a complete output, killed around the final renames: the
    table beside OUT.h5 is never the other run's; --resume, or tidy (what a study does with
    a complete piece), leaves the new run's pair."""
    from petsc_contact.io.store import tidy

    for spec in ("before:final:1", "after:final:1", "after:table:1"):
        out = tmp_path / f"{spec.replace(':', '-')}.h5"
        shutil.copy(whole, out)
        shutil.copy(whole.with_suffix(".csv"), out.with_suffix(".csv"))
        assert _killed(spec, out, seed=4).returncode == -signal.SIGKILL
        _one_run(out)
        if spec == "after:final:1":
            assert not out.with_suffix(".csv").exists()
            tidy(str(out))
        else:
            assert _run(out, "--resume", seed=4).returncode == 0
        _one_run(out)
        with h5py.File(out) as f:
            assert f.attrs["seed"] == 4 and f.attrs["complete"], spec
        assert out.with_suffix(".csv").exists() and _leftovers(out) == [], _leftovers(out)


def test_a_signal_during_the_assembly_or_after_a_commit_says_what_was_kept(tmp_path, whole):
    """SIGTERM while OUT.h5 is assembled, or just after a step's commit: exit 130, the one
    note with the steps the .partial holds; --resume completes the run."""
    for spec, kept in (("before:final:1:TERM", 3), ("after:commit:3:TERM", 2)):
        out = tmp_path / f"{spec.replace(':', '-')}.h5"
        note = _one_line(_killed(spec, out), 130, f"{kept} finished step(s) kept", "--resume")
        assert note.startswith("petsc-contact: note: interrupted;"), note
        assert _steps(f"{out}.partial") == kept and not out.exists()
        assert _run(out, "--resume").returncode == 0
        same_result(whole, out, fields=True)


def test_a_signal_dropped_in_a_finaliser_still_ends_the_run(tmp_path, whole):
    """SIGTERM while Python runs a finaliser, which drops the handler's KeyboardInterrupt:
    the run still ends at the next point that matters, exit 130 with the note, its one line
    (Python's report of the dropped exception is left out)."""
    out = tmp_path / "dropped.h5"
    r = _killed("after:commit:2:FINALIZER", out)
    assert r.returncode == 130, r.stderr
    (line,) = r.stderr.strip().splitlines()
    assert "note: interrupted; 1 finished step(s) kept" in line
    assert _run(out, "--resume").returncode == 0
    same_result(whole, out, fields=True)


def test_no_byte_free_is_refused_in_one_line_leaving_nothing(small_disk):  # noqa: F811
    """A file system with no byte free: exit 74, one line naming the lock file, nothing
    left behind."""
    filler = small_disk / "filler"
    with open(filler, "wb") as f, pytest.raises(OSError):
        while True:
            f.write(bytes(1 << 16))
            f.flush()
    out = small_disk / "full.h5"
    _one_line(_run(out), 74, f"cannot write {out}.lock: No space left on device")
    assert sorted(p.name for p in small_disk.iterdir()) == ["filler"]
