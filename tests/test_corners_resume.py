"""A resume joins only the same input: a height map changed between a pause and ``--resume``
(a file or an array; a comparison's map, against which its reference was solved) is refused
in one line naming ``--overwrite``.  An ensemble's file names its seed files relative to
itself: its folder moves with them, and a seed file missing or replaced is refused."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import cli

from petsc_contact.io.provenance import input_digest

PERIODIC = ["periodic", "--length", "1", "--sweep", "4,1e-3,1e-1", "--quiet"]
PUNCH = ["punch", "--length", "1", "--approaches", "1e-3,2e-3,3e-3", "--quiet"]
COMPARE = ["compare", "--length", "1", "--pressures", "1e-2", "--solvers", "cg", "--quiet"]
ENSEMBLE = ["ensemble", "--grid", "32", "--hurst", "0.7", "--rms-slope", "0.1", "--pressures"]


def _map(n: int = 64) -> np.ndarray:
    """A rough map of rms slope about 0.1 on a unit cell."""
    return 1e-3 * (64 / n) * np.random.default_rng(1).standard_normal((n, n))


def _refused(r: subprocess.CompletedProcess, *words: str) -> None:
    """Exit status 2, one line on stderr (beside the map's warnings) naming every word."""
    assert r.returncode == 2, r.stderr
    errors = [line for line in r.stderr.splitlines() if "error:" in line]
    assert len(errors) == 1 and "Traceback" not in r.stderr, r.stderr
    for word in words:
        assert word in errors[0], (word, r.stderr)


def _steps(path: Path) -> int:
    with h5py.File(path) as f:
        return int(f["converged"].shape[0])


def _digest(path: Path) -> str:
    with h5py.File(path) as f:
        return str(f.attrs["heights_sha256"])


@pytest.mark.parametrize("command", [PERIODIC, PUNCH], ids=["periodic", "punch"])
def test_a_heights_file_changed_between_pause_and_resume_is_refused(
    tmp_path: Path, command: list[str]
) -> None:
    heights, out = tmp_path / "h.npy", tmp_path / "out.h5"
    np.save(heights, _map())
    run = [*command, "--heights", str(heights), "--output", str(out)]
    paused = cli(*run, "--stop-after", "0")
    assert paused.returncode == 75, paused.stderr
    original = heights.read_bytes()
    np.save(heights, 2 * np.load(heights))  # the same path, the same shape: another map
    partial = Path(f"{out}.partial")
    kept = partial.read_bytes()
    _refused(cli(*run, "--resume"), "out.h5.partial", "height map has changed", "--overwrite")
    assert partial.read_bytes() == kept and not out.exists()  # nothing of the new map joined
    heights.write_bytes(original)
    done = cli(*run, "--resume")  # its own map: it goes on
    assert done.returncode == 0, done.stderr
    assert _steps(out) == (3 if command is PUNCH else 4)
    np.save(heights, 2 * np.load(heights))
    _refused(cli(*run, "--resume"), "out.h5", "height map has changed", "--overwrite")
    again = cli(*run, "--overwrite")
    assert again.returncode == 0, again.stderr
    assert _digest(out) == input_digest(str(heights))


def test_an_array_changed_between_pause_and_resume_is_refused(tmp_path: Path, petsc) -> None:
    from petsc_contact import Run, run_contact

    heights = _map()
    run = Run(heights=heights, length=1.0, sweep=(4, 1e-3, 1e-1), output=str(tmp_path / "a.h5"))
    assert run_contact(run.with_(stop_after=0)).status == "paused"
    for changed in (2 * heights, heights.T.copy(), heights.astype(np.float32)):
        with pytest.raises(ValueError, match=r"height map has changed.*--overwrite") as caught:
            run_contact(run.with_(heights=changed, resume=True))
        assert "\n" not in str(caught.value)
    result = run_contact(run.with_(heights=heights.copy(), resume=True))  # equal values
    assert result.status == "complete" and len(result.table) == 4
    assert result.record["heights_sha256"] == _digest(tmp_path / "a.h5")
    with pytest.raises(ValueError, match="height map has changed"):
        run_contact(run.with_(heights=-heights, resume=True))  # its complete output


def test_a_partial_file_without_the_digest_of_its_array_is_joined_with_a_warning(
    tmp_path: Path, petsc
) -> None:
    """An interrupted run of an earlier version recorded no digest of an array: the resume
    says that the map is not compared."""
    from petsc_contact import Run, run_contact
    from petsc_contact.conventions.warnings import ResumeWarning

    run = Run(heights=_map(32), length=1.0, pressures=(1e-3, 1e-2), output=str(tmp_path / "o.h5"))
    assert run_contact(run.with_(stop_after=0)).status == "paused"
    with h5py.File(f"{run.output}.partial", "a") as f:
        del f.attrs["heights_sha256"]
    with pytest.warns(ResumeWarning, match="records no digest of its height map"):
        assert run_contact(run.with_(resume=True)).status == "complete"


def test_compare_resume_refuses_the_solvers_of_another_map(tmp_path: Path) -> None:
    heights, out = tmp_path / "h.npy", tmp_path / "cmp.h5"
    np.save(heights, _map(32))
    run = [*COMPARE, "--heights", str(heights), "--output", str(out)]
    first = cli(*run)
    assert first.returncode == 0, first.stderr
    with h5py.File(out) as f:
        reference = float(f.attrs["reference_mean_gap"])
    np.save(heights, 2 * np.load(heights))  # the old solvers' errors are against the old map
    _refused(cli(*run, "--resume"), "cmp.h5", "height map has changed", "--overwrite")
    shutil.copy(out, f"{out}.partial")  # an interrupted comparison's solvers, of the old map
    _refused(cli(*run, "--resume"), "cmp.h5.partial", "height map has changed", "--overwrite")
    with h5py.File(out) as f:
        assert float(f.attrs["reference_mean_gap"]) == reference  # untouched


def _ensemble(folder: Path, *extra: str) -> Path:
    folder.mkdir()
    out = folder / "ens.h5"
    r = cli(*ENSEMBLE, "1e-3", "--seeds", "1-2", "--output", str(out), "--quiet", *extra)
    assert r.returncode == 0, r.stderr
    return out


def _plot(path: Path) -> subprocess.CompletedProcess:
    return cli("plot", str(path), "--output", str(path.parent / "e.png"))


def test_an_ensemble_moves_with_its_seed_files(tmp_path: Path) -> None:
    out = _ensemble(tmp_path / "a")
    with h5py.File(out) as f:
        assert json.loads(f.attrs["seed_files"]) == ["ens_seed1.h5", "ens_seed2.h5"]
    moved = tmp_path / "b"
    shutil.move(tmp_path / "a", moved)
    drawn = _plot(moved / "ens.h5")
    assert drawn.returncode == 0, drawn.stderr
    (moved / "ens_seed2.h5").unlink()
    _refused(_plot(moved / "ens.h5"), "ens_seed2.h5 is missing")


def test_an_earlier_ensemble_file_draws_the_seed_files_beside_it(tmp_path: Path) -> None:
    """An ensemble file of an earlier version names its seeds by absolute path: copied with
    its seeds, it draws those beside it, not the originals (here made unreadable)."""
    out = _ensemble(tmp_path / "a")
    with h5py.File(out, "a") as f:
        names = json.loads(f.attrs["seed_files"])
        f.attrs["seed_files"] = json.dumps([str(tmp_path / "a" / n) for n in names])
        del f.attrs["seed_created"]
    shutil.copytree(tmp_path / "a", tmp_path / "b")
    for name in names:
        (tmp_path / "a" / name).write_bytes(b"not the seeds")
    drawn = _plot(tmp_path / "b" / "ens.h5")
    assert drawn.returncode == 0, drawn.stderr


def test_a_seed_file_replaced_by_another_run_is_refused(tmp_path: Path) -> None:
    other = _ensemble(tmp_path / "other", "--hurst", "0.3")
    out = _ensemble(tmp_path / "a")
    with h5py.File(out) as f, h5py.File(other.parent / "ens_seed1.h5") as g:
        assert json.loads(f.attrs["seed_created"])[0] != g.attrs["created"]  # two runs
    mine = tmp_path / "a" / "ens_seed1.h5"
    shutil.copy(mine, tmp_path / "kept.h5")
    shutil.copy(other.parent / "ens_seed1.h5", mine)
    _refused(_plot(out), "ens_seed1.h5 is not the run of seed 1 it summarises", "--resume")
    shutil.copy(tmp_path / "a" / "ens_seed2.h5", mine)  # the same ensemble's other seed
    _refused(_plot(out), "ens_seed1.h5 is not the run of seed 1", "(seed 2")
    shutil.copy(tmp_path / "kept.h5", mine)
    drawn = _plot(out)
    assert drawn.returncode == 0, drawn.stderr
