"""What the composite commands join: an ensemble's seed files, a comparison's finished solvers
and a study's pieces are kept only where they are this command's (their ``parameters``);
anything else is refused in one line (``--overwrite`` starts afresh), and bad study inputs end
in one line, not a traceback."""

from __future__ import annotations

import json
import signal
import subprocess
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import ROOT, cli, python

ENSEMBLE = "ensemble --grid 32 --rms-slope 0.1 --pressures 1e-3,1e-2 --seeds 1-3 --quiet"
COMPARE = "compare --grid 32 --hurst 0.7 --rms-slope 0.1 --pressures 1e-3 --solvers cg,pk,bnls"
STUDY = "study --figure 1 --quiet"


def _killed(spec: str, command: str, *extra: str) -> subprocess.CompletedProcess:
    """``command`` run under tests/kill_at.py, SIGKILLed at ``spec``."""
    return python(str(ROOT / "tests" / "kill_at.py"), spec, "--", *command.split(), *extra)


def _refused(r: subprocess.CompletedProcess, *words: str) -> None:
    """Exit status 2, one line on stderr naming every word, no traceback."""
    assert r.returncode == 2, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr, r.stderr
    for word in words:
        assert word in r.stderr, (word, r.stderr)


def _hurst(path: Path) -> float:
    with h5py.File(path) as f:
        return float(json.loads(f.attrs["parameters"])["hurst"])


def test_ensemble_joins_only_its_own_seed_files(tmp_path, petsc):
    out = tmp_path / "ens.h5"
    at = ["--output", str(out)]
    h3, h7 = [*at, "--hurst", "0.3"], [*at, "--hurst", "0.7"]
    seed = {k: tmp_path / f"ens_seed{k}.h5" for k in (1, 2, 3)}
    assert _killed("after:commit:2", ENSEMBLE, *h3).returncode == -signal.SIGKILL  # in seed 1
    _refused(
        cli(*ENSEMBLE.split(), *h7, "--resume"), "ens_seed1.h5.partial", "hurst", "--overwrite"
    )
    _refused(cli(*ENSEMBLE.split(), *h7), "--resume", "--overwrite")
    assert cli(*ENSEMBLE.split(), *h3, "--resume").returncode == 0  # its own partial continued
    before = seed[2].stat().st_mtime_ns
    _refused(cli(*ENSEMBLE.split(), *h7, "--resume"), "ens_seed1.h5", "hurst", "--overwrite")
    _refused(cli(*ENSEMBLE.split(), *h3, "--grid", "48", "--resume"), "grid")
    _refused(cli(*ENSEMBLE.split(), *h7), "--resume", "--overwrite")
    assert seed[2].stat().st_mtime_ns == before and _hurst(out) == 0.3
    from petsc_contact import Run, run_ensemble

    base = Run(grid=32, hurst=0.7, rms_slope=0.1, pressures=(1e-3, 1e-2), output=str(out))
    with pytest.raises(ValueError, match="hurst"):
        run_ensemble(base.with_(resume=True), [1, 2, 3])
    # --overwrite clears the earlier ensemble first: killed in seed 2, nothing of H = 0.3 is left
    r = _killed("after:commit:5", ENSEMBLE, *h7, "--overwrite")
    assert r.returncode == -signal.SIGKILL, r.stderr
    assert not out.exists() and not seed[3].exists() and _hurst(seed[1]) == 0.7
    assert Path(f"{seed[2]}.partial").exists() and not seed[2].exists()
    r = cli(*ENSEMBLE.split(), *h7, "--resume")  # seed 2 goes on from its partial
    assert r.returncode == 0, r.stderr
    with h5py.File(out) as f:
        assert _hurst(out) == 0.7 and list(f["seeds"][...]) == [1, 2, 3]
        assert json.loads(f.attrs["seed_files"]) == [seed[k].name for k in (1, 2, 3)]
        for row, k in zip(f["mean_gap"][...], (1, 2, 3), strict=True):
            assert _hurst(seed[k]) == 0.7
            with h5py.File(seed[k]) as s:
                assert np.array_equal(s["mean_gap"][...], row)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["ens.h5", *(f"ens_seed{k}.{e}" for k in (1, 2, 3) for e in ("h5", "csv"))]
    )


def test_compare_resumes_only_its_own_solvers(tmp_path, petsc):
    out = tmp_path / "cmp.h5"
    partial = Path(f"{out}.partial")
    at = ["--output", str(out), "--quiet"]
    assert _killed("after:commit:2", COMPARE, *at).returncode == -signal.SIGKILL  # cg, pk kept
    kept = partial.read_bytes()
    _refused(cli(*COMPARE.split(), *at), "cmp.h5.partial", "--resume", "--overwrite")
    other = COMPARE.replace("--pressures 1e-3", "--pressures 2e-3")
    _refused(cli(*other.split(), *at, "--resume"), "pressure")
    assert partial.read_bytes() == kept
    r = cli(*COMPARE.split(), *at, "--overwrite")
    assert r.returncode == 0, r.stderr
    assert not partial.exists()
    with h5py.File(out) as f:
        assert json.loads(f.attrs["solvers"]) == ["cg", "pk", "bnls"]
    # a solver named twice fails before anything is solved or written, in one line
    again = tmp_path / "again.h5"
    _refused(cli(*COMPARE.replace("cg,pk,bnls", "cg,cg").split(), "--output", str(again)))
    assert sorted(p.name for p in tmp_path.glob("again*")) == []
    from petsc_contact.workflows.compare import check_solvers, compare

    with pytest.raises(ValueError, match="twice"):
        compare(None, 1e-3, ["cg", "cg"])  # type: ignore[arg-type]
    for name in ("o/x.opts", "o_x.opts"):
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_text("-tao_type bncg\n")
    with pytest.raises(ValueError, match="twice"):  # the same group of the file
        check_solvers([str(tmp_path / "o/x.opts"), str(tmp_path / "o_x.opts")])


def test_study_reuses_only_its_own_pieces_and_refuses_bad_inputs(tmp_path):
    data, cut = tmp_path / "d", tmp_path / "cut"
    assert cli(*STUDY.split(), "--shrink", "128", "--data", str(data)).returncode == 0
    kept = {p: p.stat().st_mtime_ns for p in data.rglob("*")}
    r = cli(*STUDY.split(), "--shrink", "64", "--data", str(data))  # the same names, other grids
    _refused(r, "fig1", "grid", "--data")
    assert {p: p.stat().st_mtime_ns for p in data.rglob("*")} == kept
    r = _killed("after:commit:2", STUDY, "--shrink", "128", "--data", str(cut))
    assert r.returncode == -signal.SIGKILL, r.stderr
    _refused(cli(*STUDY.split(), "--shrink", "64", "--data", str(cut)), ".partial", "grid")
    for shrink in ("0", "-1", "129"):
        _refused(cli("study", "--shrink", shrink, "--data", str(tmp_path / "s")), "--shrink")
        _refused(cli("study", "--list", "--shrink", shrink), "--shrink")


@pytest.mark.parametrize("listed", [[], ["--list"]], ids=["run", "list"])
def test_study_data_folder_is_checked_before_it_is_made(tmp_path, listed):
    _refused(cli("study", "--data", "", *listed), "give a data folder (--data is empty)")
    (tmp_path / "file").write_text("")
    _refused(cli("study", "--data", str(tmp_path / "file"), *listed), "is not a folder")
    _refused(cli("study", "--shrink", "0", "--data", str(tmp_path / "new"), *listed), "--shrink")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]  # no folder made


def test_a_study_goes_on_with_pieces_of_an_earlier_version(tmp_path):
    """A complete piece and an interrupted one written before some options were recorded
    (``RECORDED_SINCE``: their parameters lack them) are this study's pieces where the
    study's values are those the earlier runs had; a piece recording another value is not."""
    from petsc_contact.io.store import RECORDED_SINCE

    data = tmp_path / "d"
    r = _killed("after:commit:2", STUDY, "--shrink", "128", "--data", str(data))
    assert r.returncode == -signal.SIGKILL, r.stderr
    files = sorted(data.rglob("*.h5")) + sorted(data.rglob("*.h5.partial"))
    assert any(p.suffix == ".partial" for p in files)

    def rewrite(path: Path, change) -> None:
        with h5py.File(path, "r+") as f:
            parameters = json.loads(f.attrs["parameters"])
            f.attrs["parameters"] = json.dumps(change(parameters))

    for path in files:  # as an earlier version wrote them
        rewrite(path, lambda p: {k: v for k, v in p.items() if k not in RECORDED_SINCE})
    assert cli(*STUDY.split(), "--shrink", "128", "--data", str(data)).returncode == 0
    done = sorted(data.rglob("*.h5"))
    rewrite(done[0], lambda p: p | {"options_prefix": "a_"})
    _refused(cli(*STUDY.split(), "--shrink", "128", "--data", str(data)), "options_prefix")


def test_resume_on_a_complete_output_computes_nothing(tmp_path):
    """``--resume`` on a run's complete output (no ``.partial``) solves nothing and leaves the
    file as it was, byte for byte: its steps are the result, in the table and from
    ``run_contact``; it solved every step again and replaced the file before.  A complete
    output of other parameters is refused (``--overwrite`` replaces it)."""
    from petsc_contact import Run, run_contact

    out = tmp_path / "r.h5"
    base = ["periodic", *"--grid 32 --hurst 0.7 --rms-slope 0.1 --output".split(), str(out)]
    assert cli(*base, "--pressures", "1e-3,1e-2", "--quiet").returncode == 0
    before, stamp = out.read_bytes(), out.stat().st_mtime_ns
    r = cli(*base, "--pressures", "1e-3,1e-2", "--resume")
    assert r.returncode == 0, r.stderr
    assert f"# {out} is complete, with this run's 2 steps: nothing to compute" in r.stdout
    assert r.stdout.count("CONVERGED_GATOL") == 2 and "# wrote" not in r.stdout
    run = Run(grid=32, hurst=0.7, rms_slope=0.1, pressures=[1e-3, 1e-2], output=str(out))
    result = run_contact(run.with_(resume=True))
    assert result.status == "complete" and result.steps == [] and result.converged
    with h5py.File(out) as f:
        assert [s["mean_gap"] for s in result.table] == list(f["mean_gap"][:])
    assert out.read_bytes() == before and out.stat().st_mtime_ns == stamp
    _refused(cli(*base, "--pressures", "1e-3,2e-2", "--resume"),
             "different parameters (pressures)", "--overwrite replaces it")  # fmt: skip
    assert out.read_bytes() == before


def test_a_new_run_over_an_existing_output_warns_it_is_replaced(tmp_path):
    """A run without ``--resume`` or ``--overwrite`` over an existing output replaces it
    (as before) and says so (``ReplacedOutput``, a ``FutureWarning``: refused from 0.3.0);
    the warning is about the earlier file, not recorded in the new one.  ``--overwrite``
    replaces it without a word, and so does ``compare`` with it."""
    from petsc_contact import Run, run_contact
    from petsc_contact.conventions.warnings import ReplacedOutput

    out = tmp_path / "r.h5"
    base = ["periodic", *"--grid 32 --hurst 0.7 --rms-slope 0.1 --quiet --output".split(), str(out)]
    assert "replaced" not in cli(*base, "--pressures", "1e-3").stderr  # a new file
    r = cli(*base, "--pressures", "2e-3")
    assert r.returncode == 0, r.stderr
    assert f"warning: '{out}' exists and is replaced when this run ends" in r.stderr
    assert "from 0.3.0 that needs --overwrite" in r.stderr
    with h5py.File(out) as f:
        assert list(f["nominal_pressure"][:]) == [2e-3]
        assert not any("replaced" in w for w in json.loads(f.attrs["warnings"]))
    assert "replaced" not in cli(*base, "--pressures", "1e-3", "--overwrite").stderr
    run = Run(grid=32, hurst=0.7, rms_slope=0.1, pressures=[1e-3], output=str(out))
    with pytest.warns(ReplacedOutput, match="exists and is replaced") as caught:
        result = run_contact(run)
    assert issubclass(caught[0].category, FutureWarning)
    assert not any("replaced" in w for w in result.warnings)
    compared = tmp_path / "c.h5"
    surface = "--grid 32 --hurst 0.7 --rms-slope 0.1 --pressures 1e-3"
    scene = ["compare", *surface.split(), "--solvers", "cg", "--quiet", "--output", str(compared)]
    assert cli(*scene).returncode == 0
    assert "is replaced when this run ends" in cli(*scene).stderr
    assert "replaced" not in cli(*scene, "--overwrite").stderr


def test_the_replaced_output_warning_is_not_a_refusal_s_first_line(tmp_path):
    """A run refused for its ``.partial`` (or its input) says that in one line, not first that
    the output is replaced; with ``PYTHONWARNINGS=error`` the warning is a refusal in one line
    (exit 2, the earlier file as it was), not a traceback."""
    out = tmp_path / "r.h5"
    base = ["periodic", *"--grid 32 --hurst 0.7 --rms-slope 0.1 --quiet --output".split(), str(out)]
    assert cli(*base, "--pressures", "1e-3").returncode == 0
    before = out.read_bytes()
    paused = cli(*base, "--sweep", "3,1e-4,1e-2", "--stop-after", "1e-9")
    assert paused.returncode == 75, paused.stderr
    r = cli(*base, "--sweep", "3,1e-4,1e-2")
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "finished step(s) of an interrupted run" in r.stderr
    r = cli(*base, "--pressures", "2e-3", "-tao_type", "nonexist")
    assert r.returncode != 0 and "replaced" not in r.stderr
    env_error = python(
        "-W",
        "error::FutureWarning",
        "-m",
        "petsc_contact.cli",
        *base,
        "--pressures",
        "2e-3",
        "--overwrite",
    )
    assert env_error.returncode == 0  # --overwrite: nothing to warn
    strict = python(
        "-W",
        "error::FutureWarning",
        "-m",
        "petsc_contact.cli",
        *base,
        "--pressures",
        "3e-3",
        "--resume",
    )
    assert strict.returncode == 2 and "different parameters" in strict.stderr
    out.unlink()
    (tmp_path / "r.h5.partial").unlink(missing_ok=True)
    assert cli(*base, "--pressures", "1e-3").returncode == 0
    before = out.read_bytes()
    strict = python(
        "-W", "error::FutureWarning", "-m", "petsc_contact.cli", *base, "--pressures", "2e-3"
    )
    assert strict.returncode == 2, strict.stderr
    assert strict.stderr.strip().splitlines() == [
        f"petsc-contact: error: '{out}' exists and is replaced when this run ends; from 0.3.0 "
        "that needs --overwrite"
    ]
    assert out.read_bytes() == before and not (tmp_path / "r.h5.partial").exists()


def test_resume_and_overwrite_together_are_refused(tmp_path):
    """``--resume`` and ``--overwrite`` together are refused by every command that takes
    them (a run took ``--resume`` and ignored ``--overwrite``), and by ``Run``."""
    from petsc_contact import Run

    given = "--grid 32 --hurst 0.7 --rms-slope 0.1 --pressures 1e-3 --resume --overwrite"
    for command in ("periodic", "demo", "ensemble --seeds 2", "compare"):
        out = ["--output", str(tmp_path / "o.h5")]
        r = cli(*command.split(), *given.split(), *out)
        assert r.returncode == 2 and "--overwrite starts it afresh: not both" in r.stderr
    with pytest.raises(ValueError, match="not both"):
        Run(grid=32, hurst=0.7, rms_slope=0.1, pressures=[1e-3], resume=True, overwrite=True)
    assert not list(tmp_path.iterdir())


def test_compare_resume_on_a_complete_output_keeps_its_solvers(tmp_path):
    """``compare --resume`` on a complete output keeps every solver it holds (only the
    reference is solved again: the same mean gap), and refuses one of other parameters
    (it replaced it without a word)."""
    out = tmp_path / "c.h5"
    surface = "--grid 32 --hurst 0.7 --rms-slope 0.1 --solvers cg --quiet --output".split()
    scene = ["compare", *surface, str(out)]
    assert cli(*scene, "--pressures", "1e-3").returncode == 0
    with h5py.File(out) as f:
        kept = {k: f["cg"].attrs[k] for k in ("solve_time", "iterations")}
        gap = f.attrs["reference_mean_gap"]
    r = cli(*scene, "--pressures", "1e-3", "--resume")
    assert r.returncode == 0 and not r.stderr, r.stderr
    with h5py.File(out) as f:
        assert {k: f["cg"].attrs[k] for k in kept} == kept  # not solved again
        assert f.attrs["reference_mean_gap"] == gap
    before = out.read_bytes()
    r = cli(*scene, "--pressures", "2e-3", "--resume")
    assert r.returncode == 2 and "different parameters (pressure" in r.stderr, r.stderr
    assert "--overwrite replaces it" in r.stderr and out.read_bytes() == before
    damaged = bytearray(before)
    damaged[: len(damaged) // 2] = bytes(len(damaged) // 2)  # bad bytes over its first half
    out.write_bytes(bytes(damaged))
    r = cli(*scene, "--pressures", "1e-3", "--resume")
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert f"cannot resume '{out}': it is damaged" in r.stderr and "--overwrite" in r.stderr
    assert out.read_bytes() == bytes(damaged) and not (tmp_path / "c.h5.partial").exists()
