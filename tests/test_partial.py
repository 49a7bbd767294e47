"""The ``.partial`` file's one commit protocol and its readers (``io.partial``)."""

from __future__ import annotations

import os

import numpy as np
import pytest

from petsc_contact.io.partial import (
    commit,
    committed_steps,
    discard,
    read_attributes,
    read_committed,
)


def _table(steps: int):
    def write(f):
        f.create_dataset("step", data=np.arange(1, steps + 1))
        f.create_dataset("converged", data=np.ones(steps, dtype=bool))
        f.create_dataset("mean_gap", data=np.linspace(1.0, 0.5, steps))

    return write


def test_a_commit_replaces_the_partial_whole_and_is_read_back(tmp_path):
    """Each commit holds the attributes given and what its writer added, nothing of the
    last; the readers see the record, the table and the steps."""
    out = str(tmp_path / "out.h5")
    record = {"parameters": {"seed": 3}, "heights_sha256": "ab", "complete": False}
    commit(out, record, _table(2))
    commit(out, {**record, "parts": {"heights.h5": "cd"}}, _table(3))
    kept = read_committed(out + ".partial")
    assert kept.parameters == {"seed": 3}
    assert kept.digest == "ab" and kept.parts == {"heights.h5": "cd"}
    assert kept.steps == 3 and list(kept.table["mean_gap"]) == list(np.linspace(1.0, 0.5, 3))
    assert committed_steps(out + ".partial") == 3
    assert not read_attributes(out + ".partial")["complete"]
    assert os.listdir(tmp_path) == ["out.h5.partial"]


def test_a_failed_commit_leaves_the_last_one(tmp_path):
    """A writer that fails mid-commit leaves the last commit and no temporary file."""
    out = str(tmp_path / "out.h5")
    commit(out, {"parameters": {}}, _table(2))

    def broken(f):
        _table(5)(f)
        raise RuntimeError("killed")

    with pytest.raises(RuntimeError):
        commit(out, {"parameters": {}}, broken)
    assert committed_steps(out + ".partial") == 2
    assert os.listdir(tmp_path) == ["out.h5.partial"]


def test_discard_removes_the_partial_if_there_is_one(tmp_path):
    """The ``.partial`` goes, and its absence is no error."""
    out = str(tmp_path / "out.h5")
    discard(out)  # none: nothing to do
    commit(out, {"parameters": {}}, _table(1))
    discard(out)
    assert os.listdir(tmp_path) == []


def _labelled(out: str) -> None:
    """Rewrite output ``out``'s ``.partial`` as earlier versions committed it: each column
    with its units and description, on the dimension scale ``step`` (the final file's
    labelled table, :func:`~petsc_contact.io.assemble.write_table`)."""
    from petsc_contact.conventions.grid import Grid
    from petsc_contact.io.assemble import write_table
    from petsc_contact.io.store import StepStore

    kept = read_committed(out + ".partial")
    store = StepStore(out, Grid(8, 1.0))
    store.attributes, store.table = kept.attributes, kept.table
    commit(out, kept.attributes, lambda f: write_table(store, f))


def test_a_resume_goes_on_from_an_earlier_versions_labelled_partial(tmp_path):
    """A commit writes the step table bare (no units, descriptions or dimension scales), and
    a run paused under an earlier version, whose ``.partial`` labelled them, resumes to the
    result of the run never paused; the complete file is labelled as before either way."""
    import h5py
    from kill_at import same_result

    from petsc_contact import Run, run_contact

    heights = 2e-3 * np.random.default_rng(5).standard_normal((32, 32))  # rms slope ~0.1
    loads = (1e-3, 1e-2, 1e-1)
    whole = Run(heights=heights, length=1.0, pressures=loads, output=str(tmp_path / "w.h5"))
    assert run_contact(whole).status == "complete"
    for name, earlier in (("now.h5", False), ("then.h5", True)):
        run = whole.with_(output=str(tmp_path / name))
        assert run_contact(run.with_(stop_after=0)).status == "paused"
        with h5py.File(run.output + ".partial") as f:
            assert set(f["mean_gap"].attrs) == set()  # bare: the final file labels them
        if earlier:
            _labelled(run.output)
            with h5py.File(run.output + ".partial") as f:
                assert {"units", "DIMENSION_LIST"} <= set(f["mean_gap"].attrs)
        assert run_contact(run.with_(resume=True)).status == "complete"
        same_result(tmp_path / "w.h5", tmp_path / name, fields=False)
        with h5py.File(tmp_path / "w.h5") as fa, h5py.File(run.output) as fb:
            assert set(fa) == set(fb)
            for key in fa:  # the same labels: units, description, dimension scales
                assert set(fa[key].attrs) == set(fb[key].attrs), key
                for label in ("units", "description"):
                    assert fa[key].attrs.get(label) == fb[key].attrs.get(label), key
